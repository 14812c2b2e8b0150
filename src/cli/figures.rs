//! The diagnostics experiments of seed 001: the hybrid criterion's map (Fig. 4), the fraction of
//! improved samples of hybrid vs. sequential (Fig. 5) and the temporal shift of the sequential
//! scheme (Fig. 10). Per-pixel diagnostics of `engine::diagnostics` are averaged per region.

use std::path::Path;

use engine::{Backend, Diagnostics, Image, RunConfig};
use lab::compare::REFERENCE_SEED;
use lab::methods::restir;
use lab::regions::{Region, Regions};
use serde_json::json;
use sss::scene::{GBuffer, Scene};

use super::common::{
    CliError, CliResult, json_opt, load_scene, output_dir, parse_resolution, with_resolution,
    write_file,
};
use super::compare;
use super::experiment::{ExperimentArgs, Finding, equal_time_args, findings_markdown, mse, report};

/// The scene of an experiment at the experiment's resolution, with its regions at the last frame.
fn scene_and_regions(args: &ExperimentArgs, name: &str) -> CliResult<(Scene, Regions)> {
    let scene = with_resolution(
        load_scene(name)?.scene,
        Some(parse_resolution(&args.resolution)?),
    );
    let regions = Regions::classify(&scene, &GBuffer::render(&scene, 15), REFERENCE_SEED);
    Ok((scene, regions))
}

/// Diagnostics of replica 0 of a ReSTIR method over the 16-frame trajectory.
fn diagnostics(backend: &Backend, scene: &Scene, spec: &str) -> CliResult<Diagnostics> {
    let preset = spec
        .strip_prefix("restir:")
        .ok_or_else(|| CliError(format!("{spec}: diagnostics need a ReSTIR method")))
        .and_then(|arg| restir::preset(Some(arg)).map_err(|e| CliError(format!("{spec}: {e}"))))?;
    let config = RunConfig {
        seed: 0,
        frames: 16,
        collect_diagnostics: true,
    };
    backend
        .run(scene, &preset, &config)?
        .diagnostics
        .ok_or_else(|| CliError(format!("{spec}: the run returned no diagnostics")))
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

const AREAS: [Region; 4] = [
    Region::Translucent,
    Region::Lit,
    Region::Penumbra,
    Region::Shadowed,
];

fn write_png(image: &Image, path: &Path) -> CliResult<()> {
    image.write_png(path)?;
    Ok(())
}

/// Fig. 4: the fraction of frames in which the hybrid criterion picks reconnection for the base
/// path (blue = reconnection, yellow = delayed), per region of `bumpy`.
pub fn hybrid_map(args: &ExperimentArgs) -> CliResult<()> {
    let out = output_dir(&super::experiment::out_dir(args, "hybrid-map"))?;
    let (scene, regions) = scene_and_regions(args, "bumpy")?;
    let d = diagnostics(&args.backend.open()?, &scene, "restir:hybrid")?;
    write_png(&d.hybrid_choice, &out.join("hybrid-choice.png"))?;
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
    let findings = findings_markdown(&[Finding {
        claim: "the criterion separates lit (delayed) and shadowed (reconnection) regions".into(),
        holds: lit.zip(shadowed).map(|(l, s)| s > l),
        measured: format!(
            "reconnection fraction lit {}, shadowed {}",
            fmt(lit),
            fmt(shadowed)
        ),
    }]);
    write_file(&out.join("table.md"), &table)?;
    write_file(&out.join("findings.md"), &findings)?;
    let json = json!({
        "schema": "reshift-experiment/1",
        "experiment": "hybrid-map",
        "reconnection_fraction": AREAS.iter().zip(&means)
            .map(|(r, m)| (r.name().to_string(), json_opt(*m)))
            .collect::<serde_json::Map<_, _>>(),
    });
    report(args, &table, &findings, &out, json)
}

/// Mean improved fraction (shifted samples with a higher target than the canonical one) per
/// region for each method.
fn improved_table(
    backend: &Backend,
    scene: &Scene,
    regions: &Regions,
    methods: &[&str],
    out: &Path,
) -> CliResult<(String, Vec<Vec<Option<f64>>>)> {
    let mut table = String::from(
        "| method | translucent | lit | penumbra | shadowed |\n|---|---:|---:|---:|---:|\n",
    );
    let mut all = Vec::new();
    for spec in methods {
        let d = diagnostics(backend, scene, spec)?;
        let stem = super::common::file_stem(spec);
        write_png(
            &d.improved_fraction,
            &out.join(format!("{stem}-improved.png")),
        )?;
        let means: Vec<Option<f64>> = AREAS
            .iter()
            .map(|&r| region_mean(regions, r, |p| Some(d.improved_fraction.pixels[p].x as f64)))
            .collect();
        let cells: Vec<String> = means.iter().map(|m| fmt(*m)).collect();
        table.push_str(&format!("| {spec} | {} |\n", cells.join(" | ")));
        all.push(means);
    }
    Ok((table, all))
}

/// Fig. 5: sequential yields more improved samples than hybrid, notably at shadow edges.
pub fn improved_fraction(args: &ExperimentArgs) -> CliResult<()> {
    let out = output_dir(&super::experiment::out_dir(args, "improved-fraction"))?;
    let (scene, regions) = scene_and_regions(args, "bumpy")?;
    let methods = ["restir:hybrid", "restir:sequential"];
    let backend = args.backend.open()?;
    let (table, means) = improved_table(&backend, &scene, &regions, &methods, &out)?;
    let findings: Vec<Finding> = [(0, Region::Translucent), (2, Region::Penumbra)]
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
    let findings = findings_markdown(&findings);
    write_file(&out.join("table.md"), &table)?;
    write_file(&out.join("findings.md"), &findings)?;
    let json = json!({ "schema": "reshift-experiment/1", "experiment": "improved-fraction" });
    report(args, &table, &findings, &out, json)
}

/// Fig. 10: in the sequential scheme, reconnection in the temporal pass beats delayed
/// reconnection (error and improved fraction), at equal cost.
pub fn temporal_shift(args: &ExperimentArgs) -> CliResult<()> {
    let root = super::experiment::out_dir(args, "temporal-shift");
    let methods = "restir:sequential,restir:sequential/temporal=delayed";
    let compare_args = equal_time_args(args, "bumpy", methods, root.clone())?;
    let outcome = compare::run(&compare_args)?;
    let (scene, regions) = scene_and_regions(args, "bumpy")?;
    let specs: Vec<&str> = methods.split(',').collect();
    let backend = args.backend.open()?;
    let (improved, means) = improved_table(&backend, &scene, &regions, &specs, &outcome.out)?;
    let r = &outcome.results;
    let findings = findings_markdown(&[
        Finding {
            claim: "temporal reconnection gives lower error than temporal delayed reconnection"
                .into(),
            holds: mse(r, specs[0], Region::Translucent)
                .zip(mse(r, specs[1], Region::Translucent))
                .map(|(a, b)| a < b),
            measured: format!(
                "translucent MSE {:.3e} vs {:.3e}",
                mse(r, specs[0], Region::Translucent).unwrap_or(f64::NAN),
                mse(r, specs[1], Region::Translucent).unwrap_or(f64::NAN)
            ),
        },
        Finding {
            claim: "temporal reconnection yields more improved samples".into(),
            holds: means[0][0].zip(means[1][0]).map(|(a, b)| a > b),
            measured: format!("{} vs {}", fmt(means[0][0]), fmt(means[1][0])),
        },
    ]);
    write_file(&outcome.out.join("findings.md"), &findings)?;
    let table = format!("{}\n{improved}", outcome.markdown);
    report(args, &table, &findings, &outcome.out, outcome.json)
}
