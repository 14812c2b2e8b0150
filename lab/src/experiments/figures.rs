//! The diagnostics figures of seed 001: the hybrid criterion's map (Fig. 4), the fraction of
//! improved samples of hybrid vs. sequential (Fig. 5) and the temporal shift of the sequential
//! scheme (Fig. 10). Per-pixel diagnostics of `engine::diagnostics` (replica 0, the 16-frame
//! trajectory) are averaged per region.

use std::path::Path;

use engine::{Backend, Diagnostics, RunConfig};
use serde_json::json;
use sss::scene::{GBuffer, Scene};

use crate::compare;
use crate::error::Error;
use crate::findings::{self, Finding, mse};
use crate::methods::restir;
use crate::progress::Progress;
use crate::reference_cache::REFERENCE_SEED;
use crate::regions::{Region, Regions};
use crate::report::{file_stem, output_dir};
use crate::scenes::{load_scene, with_resolution};

use super::setup::{FRAMES, Report, Settings, equal_time_plan};

/// A value averaged over each of [`AREAS`]; `None` where a region is empty.
type RegionMeans = Vec<Option<f64>>;

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
    let d = diagnostics(&settings.backend, &scene, "restir:hybrid")?;
    d.hybrid_choice.write_png(out.join("hybrid-choice.png"))?;
    // The map is yellow → blue by the reconnection fraction (its blue channel); black = no choice.
    let fraction = |p: usize| {
        let c = d.hybrid_choice.pixels[p];
        (c != glam::Vec3::ZERO).then_some(c.z as f64)
    };
    let means: Vec<Option<f64>> = AREAS
        .iter()
        .map(|&r| region_mean(&regions, r, fraction))
        .collect();
    let mut table = String::from("| region | pixels | reconnection fraction |\n|---|---:|---:|\n");
    for (r, m) in AREAS.iter().zip(&means) {
        table.push_str(&format!("| {r} | {} | {} |\n", regions.count(*r), fmt(*m)));
    }
    let (lit, shadowed) = (means[1], means[3]);
    let findings = findings::markdown(&[Finding {
        claim: "the criterion separates lit (delayed) and shadowed (reconnection) regions".into(),
        holds: lit.zip(shadowed).map(|(l, s)| s > l),
        measured: format!(
            "reconnection fraction lit {}, shadowed {}",
            fmt(lit),
            fmt(shadowed)
        ),
    }]);
    let json = json!({
        "schema": "reshift-experiment/1",
        "experiment": "hybrid-map",
        "reconnection_fraction": AREAS.iter().zip(&means)
            .map(|(r, m)| (r.name().to_string(), json!(m.filter(|v| v.is_finite()))))
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
    let (table, means) = improved_table(&settings.backend, &scene, &regions, &methods, &out)?;
    let found: Vec<Finding> = [(0, Region::Translucent), (2, Region::Penumbra)]
        .into_iter()
        .map(|(i, region)| Finding {
            claim: format!("sequential yields more improved samples than hybrid ({region})"),
            holds: means[0][i].zip(means[1][i]).map(|(h, s)| s > h),
            measured: format!(
                "hybrid {}, sequential {}",
                fmt(means[0][i]),
                fmt(means[1][i])
            ),
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
    let outcome = compare::run(
        &equal_time_plan(settings, "bumpy", &specs, &root)?,
        progress,
    )?;
    let (scene, regions) = scene_and_regions(settings, "bumpy")?;
    let (improved, means) =
        improved_table(&settings.backend, &scene, &regions, &specs, &outcome.out)?;
    let r = &outcome.rows;
    let (a, b) = (
        mse(r, specs[0], Region::Translucent),
        mse(r, specs[1], Region::Translucent),
    );
    let findings = findings::markdown(&[
        Finding {
            claim: "temporal reconnection gives lower error than temporal delayed reconnection"
                .into(),
            holds: a.zip(b).map(|(a, b)| a < b),
            measured: format!(
                "translucent MSE {:.3e} vs {:.3e}",
                a.unwrap_or(f64::NAN),
                b.unwrap_or(f64::NAN)
            ),
        },
        Finding {
            claim: "temporal reconnection yields more improved samples".into(),
            holds: means[0][0].zip(means[1][0]).map(|(a, b)| a > b),
            measured: format!("{} vs {}", fmt(means[0][0]), fmt(means[1][0])),
        },
    ]);
    let mut report = Report::of_comparison(outcome, findings)?;
    report.table = format!("{}\n{improved}", report.table);
    Ok(report)
}

/// The scene of an experiment at the experiment's resolution, with its regions at the last frame.
fn scene_and_regions(settings: &Settings, name: &str) -> Result<(Scene, Regions), Error> {
    let scene = with_resolution(load_scene(name)?.scene, Some(settings.resolution));
    let regions = Regions::classify(&scene, &GBuffer::render(&scene, FRAMES - 1), REFERENCE_SEED);
    Ok((scene, regions))
}

/// Diagnostics of replica 0 of the ReSTIR method `spec` over the trajectory.
fn diagnostics(backend: &Backend, scene: &Scene, spec: &str) -> Result<Diagnostics, Error> {
    let preset = restir::preset(spec.strip_prefix("restir:")).map_err(|reason| {
        Error::Invalid(format!(
            "{spec}: diagnostics need a ReSTIR method; {reason}"
        ))
    })?;
    let config = RunConfig {
        seed: 0,
        frames: FRAMES,
        collect_diagnostics: true,
    };
    backend
        .run(scene, &preset, &config)?
        .diagnostics
        .ok_or_else(|| Error::Invalid(format!("{spec}: the run returned no diagnostics")))
}

/// Mean of `value(pixel)` over the pixels of `region` where it is defined.
fn region_mean(
    regions: &Regions,
    region: Region,
    value: impl Fn(usize) -> Option<f64>,
) -> Option<f64> {
    let values: Vec<f64> = regions
        .pixels(region)
        .into_iter()
        .filter_map(value)
        .collect();
    (!values.is_empty()).then(|| values.iter().sum::<f64>() / values.len() as f64)
}

fn fmt(v: Option<f64>) -> String {
    v.map_or("-".into(), |v| format!("{v:.3}"))
}

/// Mean improved fraction (shifted samples with a higher target than the canonical one) per
/// region for each method, as a table; writes each method's map `<method>-improved.png`.
fn improved_table(
    backend: &Backend,
    scene: &Scene,
    regions: &Regions,
    methods: &[&str],
    out: &Path,
) -> Result<(String, Vec<RegionMeans>), Error> {
    let mut table = String::from(
        "| method | translucent | lit | penumbra | shadowed |\n|---|---:|---:|---:|---:|\n",
    );
    let mut all = Vec::new();
    for spec in methods {
        let d = diagnostics(backend, scene, spec)?;
        let stem = file_stem(spec);
        d.improved_fraction
            .write_png(out.join(format!("{stem}-improved.png")))?;
        let means: RegionMeans = AREAS
            .iter()
            .map(|&r| region_mean(regions, r, |p| Some(d.improved_fraction.pixels[p].x as f64)))
            .collect();
        let cells: Vec<String> = means.iter().map(|m| fmt(*m)).collect();
        table.push_str(&format!("| {spec} | {} |\n", cells.join(" | ")));
        all.push(means);
    }
    Ok((table, all))
}
