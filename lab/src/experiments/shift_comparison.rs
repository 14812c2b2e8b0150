//! Fig. 6 (`bumpy`, one large light) and Fig. 7 (`many-lights`) of seed 001: the four presets,
//! equal-time `pt` and `pt:1`, and which shift wins in which region.

use crate::compare::{self, DEFAULT_METHODS};
use crate::error::Error;
use crate::findings::{self, Finding, best, mse};
use crate::method_result::MethodResult;
use crate::progress::Progress;
use crate::regions::Region;

use super::setup::{Report, Settings, equal_time_plan};

const PRESETS: [&str; 4] = [
    "restir:reconnection",
    "restir:delayed",
    "restir:hybrid",
    "restir:sequential",
];

pub fn run(
    settings: &Settings,
    scene: &str,
    name: &str,
    progress: &mut dyn Progress,
) -> Result<Report, Error> {
    let methods = format!("{DEFAULT_METHODS},pt:1");
    let methods: Vec<&str> = methods.split(',').collect();
    let plan = equal_time_plan(settings, scene, &methods, &settings.out_dir(name))?;
    let outcome = compare::run(&plan, progress)?;
    let table = findings::markdown(&shift_findings(&outcome.rows));
    Report::of_comparison(outcome, table)
}

/// Seed 001 §6 (Fig. 6, 7): reconnection wins in shadow, delayed reconnection in the light, hybrid and
/// sequential over all translucent pixels, and every preset beats path tracing where the light
/// is hard to reach.
fn shift_findings(r: &[MethodResult]) -> Vec<Finding> {
    let fmt = |m: &str, region| mse(r, m, region).map_or("-".into(), |v| format!("{v:.3e}"));
    let list = |region| {
        PRESETS
            .iter()
            .chain(["pt", "pt:1"].iter())
            .map(|m| format!("{}={}", m.trim_start_matches("restir:"), fmt(m, region)))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let below = |a: &str, b: &str, region| Some(mse(r, a, region)? < mse(r, b, region)?);
    let mut findings = vec![
        Finding {
            claim: "reconnection has lower error than delayed reconnection in shadowed regions"
                .into(),
            holds: below("restir:reconnection", "restir:delayed", Region::Shadowed),
            measured: list(Region::Shadowed),
        },
        Finding {
            claim: "delayed reconnection has lower error than reconnection in lit regions".into(),
            holds: below("restir:delayed", "restir:reconnection", Region::Lit),
            measured: list(Region::Lit),
        },
        Finding {
            claim: "reconnection has the lowest error in shadowed regions".into(),
            holds: best(r, &PRESETS, Region::Shadowed).map(|b| b == "restir:reconnection"),
            measured: list(Region::Shadowed),
        },
        Finding {
            claim: "delayed reconnection has the lowest error in lit regions".into(),
            holds: best(r, &PRESETS, Region::Lit).map(|b| b == "restir:delayed"),
            measured: list(Region::Lit),
        },
        Finding {
            claim: "hybrid and sequential are best over all translucent pixels".into(),
            holds: (|| {
                let worst_new = mse(r, "restir:hybrid", Region::Translucent)?.max(mse(
                    r,
                    "restir:sequential",
                    Region::Translucent,
                )?);
                let best_old = mse(r, "restir:reconnection", Region::Translucent)?.min(mse(
                    r,
                    "restir:delayed",
                    Region::Translucent,
                )?);
                Some(worst_new < best_old)
            })(),
            measured: list(Region::Translucent),
        },
    ];
    for (pt, budget) in [("pt:1", "1-spp (equal-spp)"), ("pt", "equal-time")] {
        for region in [Region::Shadowed, Region::Penumbra] {
            findings.push(Finding {
                claim: format!(
                    "every ReSTIR preset is below {budget} path tracing in {region} regions"
                ),
                holds: mse(r, pt, region).map(|pt| {
                    PRESETS
                        .iter()
                        .all(|m| mse(r, m, region).is_some_and(|v| v < pt))
                }),
                measured: list(region),
            });
        }
    }
    findings
}
