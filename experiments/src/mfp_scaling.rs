//! Fig. 9 of paper 001: the gain of hybrid and sequential over path tracing (equal time and
//! 1 spp) on the same scene at five scales of the mean free path.

use serde_json::json;

use lab::error::Error;
use lab::method_result::Measured;
use lab::metrics::Area;
use lab::output::output_dir;
use lab::progress::Progress;
use lab::regions::Region;
use lab::report::tables::with_ci;
use lab::uncertainty::Estimate;

use crate::findings::{self, Finding, all_above, log_cost_ratio, log_mse_ratio, row};

use super::setup::{Report, Settings, compare, equal_time_comparison};

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
    // Per scene, log gains: [equal-time hybrid, equal-time sequential, 1-spp hybrid,
    // 1-spp sequential]; equal time as MSE·s ratios, 1 spp as MSE ratios.
    let mut gains: Vec<[Option<Estimate>; 4]> = Vec::new();
    let mut runs = Vec::new();
    for (scene, scale) in MFP_SCENES {
        let plan = equal_time_comparison(settings, scene, &methods, &root.join(scene))?;
        let (outcome, written) = compare(&plan, progress)?;
        let r = &outcome.rows;
        let t = Region::Translucent;
        let mse = |m| {
            row(r, m)
                .and_then(|x| x.area(Area::Region(t)))
                .map_or("-".into(), |a| with_ci(Some(Measured::of(&a.mse))))
        };
        let spp = row(r, "pt").map_or(0, |x| x.spp);
        let g = [
            log_cost_ratio(r, "pt", "restir:hybrid", t),
            log_cost_ratio(r, "pt", "restir:sequential", t),
            log_mse_ratio(r, "pt:1", "restir:hybrid", t),
            log_mse_ratio(r, "pt:1", "restir:sequential", t),
        ];
        let shown: Vec<String> = g
            .iter()
            .map(|e| with_ci(e.as_ref().map(Measured::of_log)))
            .collect();
        table.push_str(&format!(
            "| {scale} | {spp} | {} | {} | {} | {} | {} |\n",
            mse("pt"),
            mse("pt:1"),
            mse("restir:hybrid"),
            mse("restir:sequential"),
            shown.join(" | ")
        ));
        gains.push(g);
        runs.push(written.results.to_json());
    }
    let found: Vec<Finding> = [
        (0, "hybrid, equal time"),
        (1, "sequential, equal time"),
        (2, "hybrid, 1 spp"),
        (3, "sequential, 1 spp"),
    ]
    .into_iter()
    .map(|(i, what)| {
        let (first, last) = (&gains[0][i], &gains[gains.len() - 1][i]);
        // Replicas of every scene share their seeds, so the gains pair by seed.
        let growth = last
            .as_ref()
            .zip(first.as_ref())
            .and_then(|(l, f)| l.minus(f));
        all_above(
            format!("the gain over path tracing grows with the mean free path ({what})"),
            &[("gain(mfp ×4) / gain(mfp ×0.25)".into(), growth)],
            0.0,
            true,
        )
    })
    .collect();
    Report {
        table: format!(
            "{table}\nTranslucent pixels, MSE in linear HDR with 95% intervals; gain = MSE(pt:1) / \
             MSE(method) at 1 spp, (MSE·s)(pt) / (MSE·s)(method) at equal time.\n"
        ),
        findings: findings::markdown(&found),
        out: output_dir(&root)?,
        json: json!({ "schema": "reshift-experiment/1", "runs": runs }),
    }
    .write()
}
