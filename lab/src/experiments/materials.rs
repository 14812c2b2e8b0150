//! Fig. 8 of seed 001: hybrid and sequential against equal-time and 1-spp path tracing on the
//! ten measured materials (`materials`).

use crate::compare;
use crate::error::Error;
use crate::findings::{self, Finding, mse};
use crate::progress::Progress;
use crate::regions::Region;

use super::setup::{Report, Settings, equal_time_plan};

pub fn run(settings: &Settings, progress: &mut dyn Progress) -> Result<Report, Error> {
    let methods = ["pt", "pt:1", "restir:hybrid", "restir:sequential"];
    let out = settings.out_dir("materials");
    let outcome = compare::run(
        &equal_time_plan(settings, "materials", &methods, &out)?,
        progress,
    )?;
    let r = &outcome.rows;
    let mut found = Vec::new();
    for (pt, budget) in [("pt:1", "1-spp (equal-spp)"), ("pt", "equal-time")] {
        for method in ["restir:hybrid", "restir:sequential"] {
            let (m, p) = (
                mse(r, method, Region::Translucent),
                mse(r, pt, Region::Translucent),
            );
            found.push(Finding {
                claim: format!("{method} is below {budget} path tracing over translucent pixels"),
                holds: m.zip(p).map(|(m, p)| m < p),
                measured: m.zip(p).map_or("-".into(), |(m, p)| {
                    format!("MSE {m:.3e} vs {p:.3e} (gain {:.2})", p / m)
                }),
            });
        }
    }
    let table = findings::markdown(&found);
    Report::of_comparison(outcome, table)
}
