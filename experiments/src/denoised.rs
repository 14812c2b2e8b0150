//! Paper 001's comparison with and without a denoiser (§6, Fig. 6 and 7): on `bumpy` (one large
//! light) and `many-lights` (512 small lights), at the experiment's resolution and at twice it,
//! the four presets and path tracing at their measured cost (equal time), every replica's last
//! frame also through each denoiser installed ([`engine::denoise`]). Its findings ask whether
//! ReSTIR SSS lowers the error at equal time per region, raw and denoised, decided by the
//! intervals of MSE·s ratios (at equal time the seconds include the denoiser's).

use engine::denoise::Denoiser;
use serde_json::json;

use lab::compare::{Comparison, Outcome};
use lab::error::Error;
use lab::method_result::MethodResult;
use lab::output::write_text;
use lab::progress::Progress;
use lab::regions::Region;

use crate::findings::{self, Finding, Quantity, all_below, cost_below};

use super::setup::{Report, Settings, compare, equal_time_comparison};

/// The presets of Fig. 6 and 7.
const PRESETS: [&str; 4] = [
    "restir:reconnection",
    "restir:delayed",
    "restir:hybrid",
    "restir:sequential",
];

/// The scenes of Fig. 6 and 7.
const SCENES: [&str; 2] = ["bumpy", "many-lights"];

/// The regions the findings judge.
const REGIONS: [Region; 3] = [Region::Shadowed, Region::Penumbra, Region::Lit];

pub fn run(settings: &Settings, name: &str, progress: &mut dyn Progress) -> Result<Report, Error> {
    let denoise: Vec<Denoiser> = Denoiser::ALL
        .into_iter()
        .filter(|d| d.available().is_ok())
        .collect();
    let out = settings.out_dir(name);
    let (w, h) = settings.resolution;
    let methods: Vec<&str> = ["pt"].into_iter().chain(PRESETS).collect();
    let (mut table, mut all, mut runs) = (String::new(), Vec::new(), Vec::new());
    for scene in SCENES {
        for (width, height) in [(w, h), (2 * w, 2 * h)] {
            let sized = Settings {
                resolution: (width, height),
                ..settings.clone()
            };
            let folder = out.join(format!("{scene}-{width}x{height}"));
            let plan = Comparison {
                denoise: denoise.clone(),
                ..equal_time_comparison(&sized, scene, &methods, &folder)?
            };
            let (outcome, written) = compare(&plan, progress)?;
            let findings = denoised_findings(&outcome);
            runs.push(written.results.to_json());
            let title = format!("{scene} at {width}×{height}");
            table.push_str(&format!("## {title}\n\n{}\n", written.markdown));
            write_text(&folder.join("findings.md"), &findings::markdown(&findings))?;
            all.extend(findings.into_iter().map(|f| Finding {
                claim: format!("{title}: {}", f.claim),
                ..f
            }));
        }
    }
    let missing: Vec<&str> = Denoiser::ALL
        .iter()
        .filter(|d| !denoise.contains(d))
        .map(|d| d.name())
        .collect();
    if !missing.is_empty() {
        table.push_str(&format!(
            "\nNot installed, left out: {} (see `reshift compare --denoise`).\n",
            missing.join(", ")
        ));
    }
    Report {
        table,
        findings: findings::markdown(&all),
        out,
        json: json!({ "schema": "reshift-experiment/1", "experiment": "denoised", "runs": runs }),
    }
    .write()
}

/// Per group (raw, then each denoiser) and region: every preset has a lower MSE·s than
/// equal-time path tracing through the same denoiser.
fn denoised_findings(outcome: &Outcome) -> Vec<Finding> {
    let groups: Vec<(String, &[MethodResult])> =
        std::iter::once(("raw".to_string(), &outcome.rows[..]))
            .chain(
                outcome
                    .denoised
                    .iter()
                    .map(|(d, rows)| (format!("denoised with {d}"), &rows[..])),
            )
            .collect();
    let mut findings = Vec::new();
    for (group, rows) in groups {
        for region in REGIONS {
            let quantities: Vec<Quantity> = PRESETS
                .iter()
                .map(|m| cost_below(rows, m, "pt", region))
                .collect();
            findings.push(all_below(
                format!(
                    "ReSTIR SSS lowers the error at equal time in {region} regions ({group}): \
                     every preset's MSE·s below path tracing's"
                ),
                &quantities,
                0.0,
                true,
            ));
        }
    }
    findings
}
