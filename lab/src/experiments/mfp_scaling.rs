//! Fig. 9 of seed 001: the gain of hybrid and sequential over path tracing (equal time and
//! 1 spp) on the same scene at five scales of the mean free path.

use serde_json::json;

use crate::compare;
use crate::error::Error;
use crate::findings::{self, Finding, mse};
use crate::progress::Progress;
use crate::regions::Region;
use crate::report::output_dir;

use super::setup::{Report, Settings, equal_time_plan};

const MFP_SCENES: [(&str, f64); 5] = [
    ("mfp-0.25", 0.25),
    ("mfp-0.5", 0.5),
    ("mfp-1", 1.0),
    ("mfp-2", 2.0),
    ("mfp-4", 4.0),
];

pub fn run(settings: &Settings, progress: &mut dyn Progress) -> Result<Report, Error> {
    let root = settings.out_dir("mfp-scaling");
    let methods = ["pt", "pt:1", "restir:hybrid", "restir:sequential"];
    let mut table = String::from(
        "| mfp scale | pt spp (equal time) | MSE pt | MSE pt:1 | MSE hybrid | MSE sequential | gain hybrid (equal time) | gain sequential (equal time) | gain hybrid (1 spp) | gain sequential (1 spp) |\n|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    // Per scene: [equal-time hybrid, equal-time sequential, 1-spp hybrid, 1-spp sequential].
    let mut gains: Vec<[f64; 4]> = Vec::new();
    let mut runs = Vec::new();
    for (scene, scale) in MFP_SCENES {
        let plan = equal_time_plan(settings, scene, &methods, &root.join(scene))?;
        let outcome = compare::run(&plan, progress)?;
        let r = &outcome.rows;
        let get = |m| {
            mse(r, m, Region::Translucent)
                .ok_or_else(|| Error::Invalid(format!("{scene}: no translucent pixels")))
        };
        let (pt, pt1) = (get("pt")?, get("pt:1")?);
        let (hybrid, sequential) = (get("restir:hybrid")?, get("restir:sequential")?);
        let spp = r.iter().find(|x| x.method == "pt").map_or(0, |x| x.spp);
        let g = [pt / hybrid, pt / sequential, pt1 / hybrid, pt1 / sequential];
        table.push_str(&format!(
            "| {scale} | {spp} | {pt:.3e} | {pt1:.3e} | {hybrid:.3e} | {sequential:.3e} | {:.2} | {:.2} | {:.2} | {:.2} |\n",
            g[0], g[1], g[2], g[3]
        ));
        gains.push(g);
        runs.push(outcome.results.to_json());
    }
    let steps = gains.len() - 1;
    let found: Vec<Finding> = [
        (0, "hybrid, equal time"),
        (1, "sequential, equal time"),
        (2, "hybrid, 1 spp"),
        (3, "sequential, 1 spp"),
    ]
    .into_iter()
    .map(|(i, what)| {
        let rises = gains.windows(2).filter(|w| w[1][i] > w[0][i]).count();
        let (first, last) = (gains[0][i], gains[steps][i]);
        Finding {
            claim: format!("the gain over path tracing grows with the mean free path ({what})"),
            holds: Some(last > first),
            measured: format!(
                "gain {first:.2} at the smallest mfp, {last:.2} at the largest; rises in {rises}/{steps} steps"
            ),
        }
    })
    .collect();
    Report {
        table: format!(
            "{table}\nTranslucent pixels, MSE in linear HDR; gain = MSE(path tracing) / MSE(method).\n"
        ),
        findings: findings::markdown(&found),
        out: output_dir(&root)?,
        json: json!({ "schema": "reshift-experiment/1", "runs": runs }),
    }
    .write()
}
