//! Fig. 6 (`bumpy`, one large light) and Fig. 7 (`many-lights`) of paper 001: the four presets,
//! equal-time `pt` and `pt:1`, and which shift wins in which region.

use lab::error::Error;
use lab::method_result::MethodResult;
use lab::progress::Progress;
use lab::regions::Region;

use crate::findings::{self, Finding, Quantity, all_below, cost_below, lowest_of, mse_below};

use super::setup::{Report, Settings, compare, equal_time_comparison};

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
    let methods: Vec<&str> = ["pt"].into_iter().chain(PRESETS).chain(["pt:1"]).collect();
    let plan = equal_time_comparison(settings, scene, &methods, &settings.out_dir(name))?;
    let (outcome, written) = compare(&plan, progress)?;
    let table = findings::markdown(&shift_findings(&outcome.rows));
    Report::of_comparison(&outcome, written, table)
}

/// Paper 001 §6 (Fig. 6, 7): reconnection wins in shadow, delayed reconnection in the light,
/// hybrid and sequential over all translucent pixels, and every preset beats path tracing
/// where the light is hard to reach; each decided by the intervals of MSE ratios (equal spp)
/// or of MSE·s ratios (equal time) ([`findings`]).
fn shift_findings(r: &[MethodResult]) -> Vec<Finding> {
    let [reconnection, delayed, hybrid, sequential] = PRESETS;
    let others = |best: &str, region| lowest_of(r, best, &PRESETS, region);
    let mut findings = vec![
        all_below(
            "reconnection has lower error than delayed reconnection in shadowed regions".into(),
            &[mse_below(r, reconnection, delayed, Region::Shadowed)],
            0.0,
            true,
        ),
        all_below(
            "delayed reconnection has lower error than reconnection in lit regions".into(),
            &[mse_below(r, delayed, reconnection, Region::Lit)],
            0.0,
            true,
        ),
        all_below(
            "reconnection has the lowest error in shadowed regions".into(),
            &others(reconnection, Region::Shadowed),
            0.0,
            true,
        ),
        all_below(
            "delayed reconnection has the lowest error in lit regions".into(),
            &others(delayed, Region::Lit),
            0.0,
            true,
        ),
        all_below(
            "hybrid and sequential are best over all translucent pixels".into(),
            &[
                mse_below(r, hybrid, reconnection, Region::Translucent),
                mse_below(r, hybrid, delayed, Region::Translucent),
                mse_below(r, sequential, reconnection, Region::Translucent),
                mse_below(r, sequential, delayed, Region::Translucent),
            ],
            0.0,
            true,
        ),
    ];
    for (pt, budget) in [("pt:1", "1-spp (equal-spp)"), ("pt", "equal-time")] {
        for region in [Region::Shadowed, Region::Penumbra] {
            let quantities: Vec<Quantity> = PRESETS
                .iter()
                .map(|m| {
                    if pt == "pt" {
                        cost_below(r, m, pt, region)
                    } else {
                        mse_below(r, m, pt, region)
                    }
                })
                .collect();
            findings.push(all_below(
                format!("every ReSTIR preset is below {budget} path tracing in {region} regions"),
                &quantities,
                0.0,
                true,
            ));
        }
    }
    findings
}
