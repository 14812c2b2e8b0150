//! The diagnostics figures of paper 001: the hybrid criterion's map (Fig. 4), the fraction of
//! improved samples of hybrid vs. sequential (Fig. 5) and the temporal shift of the sequential
//! scheme (Fig. 10). Per-pixel diagnostics of `engine::diagnostics` (the 16-frame trajectory)
//! are averaged per region in every replica; findings compare those means by their 95%
//! intervals over replicas ([`crate::findings`]), maps show replica 0.

use std::path::Path;

use engine::{Diagnostics, RunConfig};
use serde_json::json;
use sss::scene::{GBuffer, Scene};

use lab::error::Error;
use lab::method_result::Measured;
use lab::output::{file_stem, output_dir};
use lab::progress::Progress;
use lab::reference_cache::REFERENCE_SEED;
use lab::regions::{Region, Regions};
use lab::report::tables::with_ci;
use lab::scenes::{load_scene, with_resolution};
use lab::uncertainty::Estimate;
use methods::restir;

use crate::findings::{self, Quantity, all_above, all_below, mse_below};

use super::setup::{FRAMES, Report, Settings, compare, equal_time_comparison};

/// Per area of [`AREAS`], a value's region mean over replicas; `None` where a region is empty.
type RegionMeans = Vec<Option<Estimate>>;

const AREAS: [Region; 4] = [
    Region::Translucent,
    Region::Lit,
    Region::Penumbra,
    Region::Shadowed,
];

/// Fig. 4: the fraction of frames in which the hybrid criterion picks reconnection for the base
/// path (blue = reconnection, yellow = delayed), per region of `bumpy`.
pub fn hybrid_map(settings: &Settings) -> Result<Report, Error> {
    let out = output_dir(&settings.out_dir("hybrid-map"))?;
    let (scene, regions) = scene_and_regions(settings, "bumpy")?;
    let runs = replicas(settings, &scene, "restir:hybrid")?;
    runs[0]
        .hybrid_choice
        .write_png(out.join("hybrid-choice.png"))?;
    // The map is yellow → blue by the reconnection fraction (its blue channel); black = no choice.
    let means = region_means(&runs, &regions, |d, p| {
        let c = d.hybrid_choice.pixels[p];
        (c != glam::Vec3::ZERO).then_some(c.z as f64)
    });
    let mut table =
        String::from("| region | pixels | reconnection fraction [95% CI] |\n|---|---:|---:|\n");
    for (r, m) in AREAS.iter().zip(&means) {
        table.push_str(&format!("| {r} | {} | {} |\n", regions.count(*r), shown(m)));
    }
    let difference = means[3]
        .as_ref()
        .zip(means[1].as_ref())
        .and_then(|(s, l)| s.minus(l));
    let findings = findings::markdown(&[all_above(
        "the criterion separates lit (delayed) and shadowed (reconnection) regions".into(),
        &[("reconnection fraction shadowed − lit".into(), difference)],
        0.0,
        false,
    )]);
    let json = json!({
        "schema": "reshift-experiment/1",
        "experiment": "hybrid-map",
        "replicas": runs.len(),
        "reconnection_fraction": AREAS.iter().zip(&means)
            .map(|(r, m)| (r.name().to_string(), json!(m.as_ref().map(|e| e.value).filter(|v| v.is_finite()))))
            .collect::<serde_json::Map<_, _>>(),
    });
    Report {
        table,
        findings,
        out,
        json,
    }
    .write()
}

/// Fig. 5: sequential yields more improved samples than hybrid, notably at shadow edges.
pub fn improved_fraction(settings: &Settings) -> Result<Report, Error> {
    let out = output_dir(&settings.out_dir("improved-fraction"))?;
    let (scene, regions) = scene_and_regions(settings, "bumpy")?;
    let methods = ["restir:hybrid", "restir:sequential"];
    let (table, means) = improved_table(settings, &scene, &regions, &methods, &out)?;
    let found: Vec<_> = [(0, Region::Translucent), (2, Region::Penumbra)]
        .into_iter()
        .map(|(i, region)| {
            let more = means[1][i]
                .as_ref()
                .zip(means[0][i].as_ref())
                .and_then(|(s, h)| s.minus(h));
            all_above(
                format!("sequential yields more improved samples than hybrid ({region})"),
                &[("improved fraction sequential − hybrid".into(), more)],
                0.0,
                false,
            )
        })
        .collect();
    Report {
        table,
        findings: findings::markdown(&found),
        out,
        json: json!({ "schema": "reshift-experiment/1", "experiment": "improved-fraction" }),
    }
    .write()
}

/// Fig. 10: in the sequential scheme, reconnection in the temporal pass beats delayed
/// reconnection (error and improved fraction), at equal cost.
pub fn temporal_shift(settings: &Settings, progress: &mut dyn Progress) -> Result<Report, Error> {
    let specs = ["restir:sequential", "restir:sequential/temporal=delayed"];
    let root = settings.out_dir("temporal-shift");
    let (outcome, written) = compare(
        &equal_time_comparison(settings, "bumpy", &specs, &root)?,
        progress,
    )?;
    let (scene, regions) = scene_and_regions(settings, "bumpy")?;
    let (improved, means) = improved_table(settings, &scene, &regions, &specs, &outcome.out)?;
    let r = &outcome.rows;
    let more = means[0][0]
        .as_ref()
        .zip(means[1][0].as_ref())
        .and_then(|(a, b)| a.minus(b));
    let error: Quantity = mse_below(r, specs[0], specs[1], Region::Translucent);
    let findings = findings::markdown(&[
        all_below(
            "temporal reconnection gives lower error than temporal delayed reconnection".into(),
            &[error],
            0.0,
            true,
        ),
        all_above(
            "temporal reconnection yields more improved samples".into(),
            &[(
                "improved fraction reconnection − delayed (translucent)".into(),
                more,
            )],
            0.0,
            false,
        ),
    ]);
    let mut report = Report::of_comparison(&outcome, written, findings)?;
    report.table = format!("{}\n{improved}", report.table);
    Ok(report)
}

/// The scene of an experiment at the experiment's resolution, with its regions at the last frame.
fn scene_and_regions(settings: &Settings, name: &str) -> Result<(Scene, Regions), Error> {
    let scene = with_resolution(load_scene(name)?.scene, Some(settings.resolution));
    let regions = Regions::classify(&scene, &GBuffer::render(&scene, FRAMES - 1), REFERENCE_SEED);
    Ok((scene, regions))
}

/// Diagnostics of every replica (seeds `0..settings.replicas`) of the ReSTIR method `spec`
/// over the trajectory.
fn replicas(settings: &Settings, scene: &Scene, spec: &str) -> Result<Vec<Diagnostics>, Error> {
    let preset = restir::preset(spec.strip_prefix("restir:")).map_err(|reason| {
        Error::Invalid(format!(
            "{spec}: diagnostics need a ReSTIR method; {reason}"
        ))
    })?;
    (0..settings.replicas.max(1) as u64)
        .map(|seed| {
            let config = RunConfig {
                seed,
                frames: FRAMES,
                collect_diagnostics: true,
            };
            settings
                .backend
                .run(scene, &preset, &config)?
                .diagnostics
                .ok_or_else(|| Error::Invalid(format!("{spec}: the run returned no diagnostics")))
        })
        .collect()
}

/// Per area of [`AREAS`], the mean of `value(diagnostics, pixel)` over the area's pixels where
/// it is defined, as an estimate over the replicas `runs`; `None` where a replica has no
/// defined pixel there.
fn region_means(
    runs: &[Diagnostics],
    regions: &Regions,
    value: impl Fn(&Diagnostics, usize) -> Option<f64>,
) -> RegionMeans {
    AREAS
        .iter()
        .map(|&r| {
            let pixels = regions.pixels(r);
            let means = runs
                .iter()
                .map(|d| {
                    let values: Vec<f64> = pixels.iter().filter_map(|&p| value(d, p)).collect();
                    (!values.is_empty()).then(|| values.iter().sum::<f64>() / values.len() as f64)
                })
                .collect::<Option<Vec<f64>>>()?;
            Some(Estimate::mean(&means))
        })
        .collect()
}

/// A region mean with its interval.
fn shown(m: &Option<Estimate>) -> String {
    with_ci(m.as_ref().map(Measured::of))
}

/// Mean improved fraction (shifted samples with a higher target than the canonical one) per
/// region for each method over replicas, as a table; writes replica 0's map of each method,
/// `<method>-improved.png`.
fn improved_table(
    settings: &Settings,
    scene: &Scene,
    regions: &Regions,
    methods: &[&str],
    out: &Path,
) -> Result<(String, Vec<RegionMeans>), Error> {
    let mut table = String::from(
        "| method (95% CI over replicas) | translucent | lit | penumbra | shadowed |\n|---|---:|---:|---:|---:|\n",
    );
    let mut all = Vec::new();
    for spec in methods {
        let runs = replicas(settings, scene, spec)?;
        let stem = file_stem(spec);
        runs[0]
            .improved_fraction
            .write_png(out.join(format!("{stem}-improved.png")))?;
        let means = region_means(&runs, regions, |d, p| {
            Some(d.improved_fraction.pixels[p].x as f64)
        });
        let cells: Vec<String> = means.iter().map(shown).collect();
        table.push_str(&format!("| {spec} | {} |\n", cells.join(" | ")));
        all.push(means);
    }
    Ok((table, all))
}
