//! The replica protocol that measures a method's bias per region and colour channel (DESIGN §3
//! "Statistics", §7 `bias`).
//!
//! * Estimate: N replicas of the method (replica `i` runs with seed `i`, so the replicas draw from
//!   disjoint streams); each replica's final frame is reduced, per region, to the mean of its
//!   pixels in each [`Channel`]: red, green, blue and luminance. Pixels inside a replica are
//!   correlated by reuse, so the replica, not the pixel, is the unit of independence.
//! * Reference: B independent batches of the path tracer at the same frame (same primary hits
//!   x1), reduced the same way; the spread of the batch means is the reference's own standard
//!   error.
//! * Test, per region and channel: [`equivalence`] of the relative bias at confidence `1 − α`
//!   with tolerance δ; across all regions and channels, Holm's procedure at family-wise level α
//!   on the zero-bias p-values decides which show a significant bias (see [`Protocol`] for the
//!   verdict). A bias in one channel only (a tint) can hide in the luminance; it cannot hide
//!   from its channel's row.
//!
//! Here: the channels and the test's rows ([`bias_rows`], [`paired_rows`], [`overall`]); the
//! test as a job of a [`BiasPlan`] (in `plan`) run by [`run`] in `run` from the pieces of `job`, with a fixed N or, within a time budget,
//! the group-sequential design of `sequential` planned and run by `budgeted`; what it found
//! ([`BiasOutcome`], the JSON of `reshift bias`) in `outcome`; the replicas' and reference batches' final frames in
//! `render`; their reduction to region means in `summary`; the replicas a run needs in
//! `planning`; the Markdown table in `table`; a test split over seeds and merged again in
//! [`shard`]; a tinted method, the negative control of a colour bias, in `tinted`.

mod budgeted;
mod job;
mod outcome;
mod plan;
mod planning;
mod render;
mod run;
pub mod sequential;
pub mod shard;
mod summary;
mod table;
#[cfg(test)]
mod tests;
mod tinted;

pub use budgeted::{CV_MARGIN, PILOT};

pub use outcome::{
    BiasOutcome, LookEntry, Needs, NonFinite, PLANNED_POWER, Planned, ReferenceEntry, RowDesign,
    SCHEMA, SequentialEntry,
};
pub use plan::{BiasPlan, DEFAULT_PIXELS, ReferenceBatches, Replicas, default_resolution};
pub use planning::{Unplannable, replicas_needed};
pub use render::{
    Images, reference_batches, reference_images, reference_images_with, replica_images, test_bytes,
};
pub use run::run;
pub use summary::{RegionSummary, region_mean, summarize};
use summary::{channel_summary, region_means, summaries};
pub use table::Table;
pub use tinted::Tinted;

use std::fmt;

use glam::DVec3;
use restir::stats::{Equivalence, Summary, Verdict, equivalence, holm};
use sss::color::luminance;

use crate::regions::{Region, Regions};

/// What a row of the bias test measures: one colour channel, or the Rec. 709 luminance.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Channel {
    Red,
    Green,
    Blue,
    Luminance,
}

impl Channel {
    /// All channels, in table order.
    pub const ALL: [Channel; 4] = [
        Channel::Red,
        Channel::Green,
        Channel::Blue,
        Channel::Luminance,
    ];

    /// `red`, `green`, `blue` or `luminance`.
    pub fn name(self) -> &'static str {
        match self {
            Channel::Red => "red",
            Channel::Green => "green",
            Channel::Blue => "blue",
            Channel::Luminance => "luminance",
        }
    }

    /// This channel of linear RGB.
    pub fn of(self, rgb: DVec3) -> f64 {
        match self {
            Channel::Red => rgb.x,
            Channel::Green => rgb.y,
            Channel::Blue => rgb.z,
            Channel::Luminance => luminance(rgb),
        }
    }
}

impl fmt::Display for Channel {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.pad(self.name())
    }
}

/// Tolerance and level of the bias test.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Protocol {
    /// Tolerance δ on the relative bias of a region's mean in one channel.
    pub delta: f64,
    /// Each CI has confidence `1 − alpha`; Holm controls the family-wise rate of false "biased"
    /// findings across all regions and channels at `alpha`.
    pub alpha: f64,
}

impl Protocol {
    /// A row's verdict: `Equivalent` ⇔ its `1 − α` CI lies inside ±δ; otherwise `Biased` if
    /// the CI lies outside [−δ, δ] or Holm rejects zero bias, `Inconclusive` if neither (an
    /// unknown spread, see [`equivalence`], is never `Biased`: its p-value is 1).
    pub(crate) fn verdict(&self, e: &Equivalence, holm_rejected: bool) -> Verdict {
        if e.ci_low > -self.delta && e.ci_high < self.delta {
            Verdict::Equivalent
        } else if e.ci_low >= self.delta || e.ci_high <= -self.delta || holm_rejected {
            Verdict::Biased
        } else {
            Verdict::Inconclusive
        }
    }

    /// `equivalent within ±δ at 1 − α`, `biased` or `inconclusive`.
    pub fn describe(&self, verdict: Verdict) -> String {
        verdict.describe(self.delta, 1.0 - self.alpha)
    }
}

/// One row of a bias table: a method in one region and channel.
#[derive(Clone, Debug, PartialEq)]
pub struct BiasRow {
    pub method: String,
    pub region: Region,
    pub channel: Channel,
    pub pixels: usize,
    pub estimate: Summary,
    pub reference: Summary,
    pub equivalence: Equivalence,
    /// Whether Holm's procedure across the method's rows rejects zero bias here.
    pub holm_rejected: bool,
    pub verdict: Verdict,
}

impl BiasRow {
    /// Half-width of the CI of the relative bias.
    pub fn ci_half_width(&self) -> f64 {
        0.5 * (self.equivalence.ci_high - self.equivalence.ci_low)
    }
}

/// The bias table rows of `method`: its replicas' per-region summaries against the reference's,
/// for every region both have and every channel; Holm runs across all of them.
pub fn bias_rows(
    method: &str,
    replicas: &[RegionSummary],
    reference: &[RegionSummary],
    protocol: &Protocol,
) -> Vec<BiasRow> {
    let tests = replicas
        .iter()
        .filter_map(|e| Some((e, reference.iter().find(|r| r.region == e.region)?)))
        .flat_map(|(e, r)| {
            Channel::ALL.map(|c| {
                let (estimate, reference) = (*e.channel(c), *r.channel(c));
                let test = equivalence(&estimate, &reference, protocol.delta, 1.0 - protocol.alpha);
                (e.region, e.pixels, c, estimate, reference, test)
            })
        })
        .collect();
    holm_rows(method, tests, protocol)
}

/// `rows` (of `method`) tested again under `protocol`: each row's estimate against its
/// reference at the new tolerance and level, Holm across them; the rows [`bias_rows`] gives at
/// that protocol from the same summaries.
pub fn rows_at(method: &str, rows: &[BiasRow], protocol: &Protocol) -> Vec<BiasRow> {
    let tests = rows
        .iter()
        .map(|r| {
            let test = equivalence(
                &r.estimate,
                &r.reference,
                protocol.delta,
                1.0 - protocol.alpha,
            );
            (r.region, r.pixels, r.channel, r.estimate, r.reference, test)
        })
        .collect();
    holm_rows(method, tests, protocol)
}

/// The rows of a paired comparison: replica `i` of `images` against replica `i` of `baseline`
/// (the same seed on another backend, say), per region and channel. The estimand is the
/// relative difference of the expectations, `b = ḡ/c̄ − 1 = d̄/c̄` with `dᵢ = gᵢ − cᵢ`; its
/// standard error is that of the linearised ratio (delta method), `sd(dᵢ − b·cᵢ)/(c̄·√N)`, so a
/// shared seed's noise, common to both sides, cancels. The test is [`equivalence`] of the
/// samples `1 + b + (dᵢ − b·cᵢ)/c̄` (mean `1 + b`) against the exact 1: its CI is
/// `b ± t_{1−α/2, N−1}·se`, its p-value the one-sample t-test of `b = 0`; Holm runs across all
/// rows. Unequal replica counts pair the surplus with NaN (a defect: Biased). Where the
/// baseline's mean is 0 or not finite the rows fall back to the unpaired test, whose edge cases
/// [`equivalence`] defines.
pub fn paired_rows(
    method: &str,
    images: &[Vec<DVec3>],
    baseline: &[Vec<DVec3>],
    regions: &Regions,
    protocol: &Protocol,
) -> Vec<BiasRow> {
    let n = images.len().max(baseline.len());
    let padded = |set: &[Vec<DVec3>]| {
        let mut means: Vec<Vec<DVec3>> = set.to_vec();
        means.resize(n, Vec::new());
        region_means(&means, regions)
    };
    let tests = padded(images)
        .into_iter()
        .zip(padded(baseline))
        .flat_map(|((region, pixels, g), (_, _, c))| {
            Channel::ALL.map(|channel| {
                let estimate = channel_summary(&g, channel);
                let reference = channel_summary(&c, channel);
                let confidence = 1.0 - protocol.alpha;
                let c_mean = reference.mean;
                let test = if c_mean != 0.0 && c_mean.is_finite() {
                    let b = (estimate.mean - c_mean) / c_mean;
                    let linearised: Vec<f64> = g
                        .iter()
                        .zip(&c)
                        .map(|(&gi, &ci)| {
                            let (gi, ci) = (channel.of(gi), channel.of(ci));
                            1.0 + b + (gi - ci - b * ci) / c_mean
                        })
                        .collect();
                    let paired = Summary::from_samples(&linearised);
                    equivalence(&paired, &Summary::exact(1.0), protocol.delta, confidence)
                } else {
                    equivalence(&estimate, &reference, protocol.delta, confidence)
                };
                (region, pixels, channel, estimate, reference, test)
            })
        })
        .collect();
    holm_rows(method, tests, protocol)
}

/// The rows of `tests` (region, pixels, channel, the two summaries and their test) with Holm's
/// procedure across all of them at `protocol.alpha`.
fn holm_rows(
    method: &str,
    tests: Vec<(Region, usize, Channel, Summary, Summary, Equivalence)>,
    protocol: &Protocol,
) -> Vec<BiasRow> {
    let p_values: Vec<f64> = tests.iter().map(|t| t.5.p_zero_bias).collect();
    let rejected = holm(&p_values, protocol.alpha);
    tests
        .into_iter()
        .zip(rejected)
        .map(
            |((region, pixels, channel, estimate, reference, test), holm_rejected)| BiasRow {
                method: method.to_string(),
                region,
                channel,
                pixels,
                estimate,
                reference,
                verdict: protocol.verdict(&test, holm_rejected),
                equivalence: test,
                holm_rejected,
            },
        )
        .collect()
}

/// Over rows: `Biased` if any row is, `Equivalent` if every row is (and there is one),
/// otherwise `Inconclusive`.
pub fn overall(rows: &[BiasRow]) -> Verdict {
    if rows.iter().any(|r| r.verdict == Verdict::Biased) {
        Verdict::Biased
    } else if !rows.is_empty() && rows.iter().all(|r| r.verdict == Verdict::Equivalent) {
        Verdict::Equivalent
    } else {
        Verdict::Inconclusive
    }
}
