//! A user-written shift checked by the conformance kit (`docs/adding-a-shift.md`).
//!
//! Run: `cargo run -p restir --release --example custom_shift`. Exits non-zero if a check fails.

use std::process::ExitCode;

use restir::check::CheckReport;
use restir::mis::{DefensivePairwise, Gbh};
use restir::shift::{Fail, Shift, Shifted};
use restir::toy::kit::{KitConfig, run_kit};
use restir::toy::{Point, ToyPixel};

/// Point reflection through the two bump centres: `y = μ_dst + μ_src − x`, `|J| = 1`.
/// It is its own inverse between the two pixels and fails (in both directions) outside Ω.
struct PointReflection;

impl Shift<ToyPixel> for PointReflection {
    fn shift(&self, x: &Point, src: &ToyPixel, dst: &ToyPixel) -> Result<Shifted<Point>, Fail> {
        let y = [
            dst.centre[0] + src.centre[0] - x[0],
            dst.centre[1] + src.centre[1] - x[1],
        ];
        if ToyPixel::in_omega(&y) {
            Ok(Shifted { y, jacobian: 1.0 })
        } else {
            Err(Fail::OutOfSupport)
        }
    }
}

fn main() -> ExitCode {
    let cfg = KitConfig::default();
    let mut all_passed = true;
    for mis in [&Gbh as &dyn restir::mis::MisScheme, &DefensivePairwise] {
        println!("point reflection + {}:", mis.name());
        let reports: Vec<CheckReport> = match run_kit(&PointReflection, mis, &cfg) {
            Ok(reports) => reports,
            Err(e) => {
                eprintln!("resampling failed: {e}");
                return ExitCode::FAILURE;
            }
        };
        for report in &reports {
            println!("  {report}");
            all_passed &= report.passed;
        }
    }
    if all_passed {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    }
}
