//! Paper 001's Fig. 6 and Fig. 7 on the paper's own scenes (`ajax`: the Ajax bust under one
//! large emissive plane; `ajax-many-lights`: under 512 small emissive rectangles), with the
//! paper's protocol as far as two CPU cores allow: the 16-frame trajectory, path tracing at 1, 6
//! and 12 samples per pixel and at the per-frame time of `restir:hybrid` (equal time), the four
//! presets and reshift's best configuration, every replica's last frame raw and through each
//! installed denoiser (SVGF, OIDN), with FLIP, the low-frequency error and per-region
//! efficiencies over equal-time path tracing, each with its interval ([`lab::compare`]).
//!
//! Its findings are paper 001's claims about these figures, each decided by intervals
//! ([`crate::findings`]): reconnection best in shadow, delayed reconnection best in the light,
//! hybrid and sequential good in both, ReSTIR SSS below path tracing at equal time, and its
//! "superior denoising quality compared to standard path tracing" at equal time, per denoiser.

use engine::denoise::Denoiser;
use lab::compare::Comparison;
use lab::error::Error;
use lab::method_result::MethodResult;
use lab::progress::Progress;
use lab::regions::Region;

use crate::findings::{self, Finding, Quantity, all_below, cost_below, lowest_of, mse_below};

use super::setup::{Report, Settings, compare, equal_time_comparison};

/// The presets of Fig. 6 and 7.
const PRESETS: [&str; 4] = [
    "restir:reconnection",
    "restir:delayed",
    "restir:hybrid",
    "restir:sequential",
];

/// reshift's best measured configuration on `bumpy` (the main job's).
pub const BEST: &str = "restir:reconnection/shade=all/neighbours=2";

/// The path-traced baselines of the paper's figures (equal-time `pt` is the comparison's
/// baseline).
const PATH_TRACING: [&str; 3] = ["pt:1", "pt:6", "pt:12"];

/// Runs the comparison of Fig. 6 (`scene` = `ajax`) or Fig. 7 (`ajax-many-lights`).
pub fn run(
    settings: &Settings,
    scene: &str,
    name: &str,
    progress: &mut dyn Progress,
) -> Result<Report, Error> {
    let methods: Vec<&str> = ["pt"]
        .into_iter()
        .chain(PATH_TRACING)
        .chain(PRESETS)
        .chain([BEST])
        .collect();
    let denoise: Vec<Denoiser> = Denoiser::ALL
        .into_iter()
        .filter(|d| d.available().is_ok())
        .collect();
    let plan = Comparison {
        denoise,
        ..equal_time_comparison(settings, scene, &methods, &settings.out_dir(name))?
    };
    let (outcome, written) = compare(&plan, progress)?;
    let mut claims = paper_findings(&outcome.rows, "raw");
    for (denoiser, rows) in &outcome.denoised {
        claims.extend(denoising_findings(rows, &format!("through {denoiser}")));
    }
    Report::of_comparison(&outcome, written, findings::markdown(&claims))
}

/// Paper 001 §6 on Fig. 6 and 7. Its "lit" claims are judged on lit pixels (every light sample
/// visible) and on penumbra pixels (some visible): the Ajax bust under the large plane has no
/// lit pixel, and under 512 small lights hardly any, so the penumbra is where these scenes are
/// directly lit.
fn paper_findings(r: &[MethodResult], group: &str) -> Vec<Finding> {
    let [reconnection, delayed, hybrid, sequential] = PRESETS;
    let others = |best: &str, region| lowest_of(r, best, &PRESETS, region);
    let mut claims = vec![all_below(
        format!("reconnection has the lowest error in shadowed regions ({group})"),
        &others(reconnection, Region::Shadowed),
        0.0,
        true,
    )];
    for lit in [Region::Lit, Region::Penumbra] {
        claims.push(all_below(
            format!("delayed reconnection has a lower error than reconnection in {lit} regions ({group})"),
            &[mse_below(r, delayed, reconnection, lit)],
            0.0,
            true,
        ));
        claims.push(all_below(
            format!("delayed reconnection has the lowest error in {lit} regions ({group})"),
            &others(delayed, lit),
            0.0,
            true,
        ));
        claims.push(all_below(
            format!(
                "hybrid and sequential are good in both: below reconnection in {lit} and below \
                 delayed reconnection in shadowed regions ({group})"
            ),
            &[
                mse_below(r, hybrid, reconnection, lit),
                mse_below(r, sequential, reconnection, lit),
                mse_below(r, hybrid, delayed, Region::Shadowed),
                mse_below(r, sequential, delayed, Region::Shadowed),
            ],
            0.0,
            true,
        ));
    }
    claims.extend(denoising_findings(r, group));
    claims
}

/// In one group of rows (raw or one denoiser's), per region: every preset below 1-spp path
/// tracing at equal spp (MSE), and every preset and the best configuration below equal-time
/// path tracing (MSE·s).
fn denoising_findings(r: &[MethodResult], group: &str) -> Vec<Finding> {
    let restir: Vec<&str> = PRESETS.into_iter().chain([BEST]).collect();
    let regions = [
        Region::Translucent,
        Region::Lit,
        Region::Penumbra,
        Region::Shadowed,
    ];
    let mut claims = Vec::new();
    for region in regions {
        let quantities: Vec<Quantity> = PRESETS
            .iter()
            .map(|m| mse_below(r, m, "pt:1", region))
            .collect();
        claims.push(all_below(
            format!(
                "every preset has a lower error than 1-spp path tracing at equal spp in {region} \
                 regions ({group})"
            ),
            &quantities,
            0.0,
            true,
        ));
    }
    for region in regions {
        let quantities: Vec<Quantity> = restir
            .iter()
            .map(|m| cost_below(r, m, "pt", region))
            .collect();
        claims.push(all_below(
            format!(
                "ReSTIR SSS has a lower error than path tracing at equal time in {region} \
                 regions ({group}): every preset's MSE·s below pt's"
            ),
            &quantities,
            0.0,
            true,
        ));
    }
    claims
}
