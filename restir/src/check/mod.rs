//! The conformance kit (DESIGN §3): seven checks a user runs on their own shift. Each returns a
//! [`CheckReport`] naming the check, whether it passed, and the figures it measured.
//!
//! 1. [`round_trip`], 2. [`reciprocal_jacobian`], 3. [`finite_difference_jacobian`] test the
//!    shift alone on pairs of domains; 4. [`partition_of_unity`] tests a shift with an MIS scheme;
//!    5. [`ucw_histogram`] and 6. [`unbiasedness`] test replica outputs of a whole chain;
//!    7. [`negative_control`] confirms a deliberately broken shift fails at least one check.

mod geometry;
mod mis;
mod replicas;

use std::fmt;

pub use geometry::{ShiftCase, finite_difference_jacobian, reciprocal_jacobian, round_trip};
pub use mis::{MisCase, partition_of_unity};
pub use replicas::{image_equivalence, ucw_histogram, unbiasedness};

/// Pass number of the stream keys the kit draws its test samples from.
const PASS_CHECK: u32 = 0xC4EC;

/// The seven checks.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum CheckName {
    RoundTrip,
    ReciprocalJacobian,
    FiniteDifferenceJacobian,
    PartitionOfUnity,
    UcwHistogram,
    Unbiasedness,
    NegativeControl,
}

impl fmt::Display for CheckName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::RoundTrip => "1 round trip",
            Self::ReciprocalJacobian => "2 reciprocal Jacobian",
            Self::FiniteDifferenceJacobian => "3 finite-difference Jacobian",
            Self::PartitionOfUnity => "4 MIS partition of unity",
            Self::UcwHistogram => "5 UCW histogram",
            Self::Unbiasedness => "6 unbiasedness",
            Self::NegativeControl => "7 negative control",
        })
    }
}

/// A named number a check measured.
#[derive(Clone, Debug, PartialEq)]
pub struct Figure {
    pub name: &'static str,
    pub value: f64,
}

/// The outcome of one check.
#[derive(Clone, Debug, PartialEq)]
pub struct CheckReport {
    pub check: CheckName,
    pub passed: bool,
    pub figures: Vec<Figure>,
    /// The first violation found, or what caught a negative control.
    pub note: String,
}

impl CheckReport {
    fn new(check: CheckName, passed: bool, figures: &[(&'static str, f64)], note: String) -> Self {
        let figures = figures
            .iter()
            .map(|&(name, value)| Figure { name, value })
            .collect();
        Self {
            check,
            passed,
            figures,
            note,
        }
    }

    /// The figure called `name`, if the check measured it.
    pub fn figure(&self, name: &str) -> Option<f64> {
        self.figures
            .iter()
            .find(|f| f.name == name)
            .map(|f| f.value)
    }
}

impl fmt::Display for CheckReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let verdict = if self.passed { "pass" } else { "FAIL" };
        write!(f, "{}: {verdict} (", self.check)?;
        for (i, fig) in self.figures.iter().enumerate() {
            let sep = if i == 0 { "" } else { ", " };
            write!(f, "{sep}{} = {:.4e}", fig.name, fig.value)?;
        }
        write!(f, ")")?;
        if !self.note.is_empty() {
            write!(f, " {}", self.note)?;
        }
        Ok(())
    }
}

/// Check 7: a deliberately broken shift (`name`) must fail at least one of `reports`; the
/// report's note names every check that caught it.
pub fn negative_control(name: &str, reports: &[CheckReport]) -> CheckReport {
    let caught: Vec<String> = reports
        .iter()
        .filter(|r| !r.passed)
        .map(|r| r.check.to_string())
        .collect();
    let note = if caught.is_empty() {
        format!("{name}: NOT detected by any check")
    } else {
        format!("{name}: caught by {}", caught.join(", "))
    };
    CheckReport::new(
        CheckName::NegativeControl,
        !caught.is_empty(),
        &[
            ("checks_run", reports.len() as f64),
            ("checks_failed", caught.len() as f64),
        ],
        note,
    )
}
