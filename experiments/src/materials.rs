//! Fig. 8 of paper 001: hybrid and sequential against equal-time and 1-spp path tracing on the
//! ten measured materials (`materials`).

use lab::error::Error;
use lab::progress::Progress;
use lab::regions::Region;

use crate::findings::{self, all_below, cost_below, mse_below};

use super::setup::{Report, Settings, compare, equal_time_comparison};

pub fn run(settings: &Settings, progress: &mut dyn Progress) -> Result<Report, Error> {
    let methods = ["pt", "pt:1", "restir:hybrid", "restir:sequential"];
    let out = settings.out_dir("materials");
    let (outcome, written) = compare(
        &equal_time_comparison(settings, "materials", &methods, &out)?,
        progress,
    )?;
    let r = &outcome.rows;
    let mut found = Vec::new();
    for (pt, budget) in [("pt:1", "1-spp (equal-spp)"), ("pt", "equal-time")] {
        for method in ["restir:hybrid", "restir:sequential"] {
            // Equal spp compares MSE; equal time compares MSE·s, which also absorbs what the
            // calibration left of the time difference.
            let quantity = if pt == "pt" {
                cost_below(r, method, pt, Region::Translucent)
            } else {
                mse_below(r, method, pt, Region::Translucent)
            };
            found.push(all_below(
                format!("{method} is below {budget} path tracing over translucent pixels"),
                &[quantity],
                0.0,
                true,
            ));
        }
    }
    let table = findings::markdown(&found);
    Report::of_comparison(&outcome, written, table)
}
