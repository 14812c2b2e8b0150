//! `reshift experiment NAME`: seed 001 §6 reproductions built on `compare`, each ending in a
//! table of the paper's qualitative findings and whether the measured numbers reproduce them.

use std::path::PathBuf;

use clap::{Args, ValueEnum};
use experiments::compare::MethodResult;
use experiments::methods::Method;
use experiments::metrics::Area;
use experiments::regions::Region;
use serde_json::json;

use super::common::{CliError, CliResult, load_scene, parse_resolution, with_resolution, write_file};
use super::compare::{self, CompareArgs, DEFAULT_METHODS};

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Name {
    /// Fig. 6: the four shifts vs. path tracing at equal time, one large light (`bumpy`).
    ShiftComparison,
    /// Fig. 9: the gain of hybrid / sequential over equal-time path tracing vs. the mean free path.
    MfpScaling,
}

#[derive(Args, Clone, Debug)]
pub struct ExperimentArgs {
    pub name: Name,
    /// Independent replicas per method.
    #[arg(long, default_value_t = 4)]
    pub replicas: u32,
    /// Image size WxH.
    #[arg(long, default_value = "64x48")]
    pub resolution: String,
    /// Samples per pixel of the references.
    #[arg(long, default_value_t = 2048)]
    pub reference_spp: u32,
    /// Output folder [default: out/experiment-<name>].
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Folder of cached references.
    #[arg(long, default_value = "out/cache")]
    pub cache: PathBuf,
    /// Print JSON instead of the tables.
    #[arg(long)]
    pub json: bool,
}

pub fn command(args: &ExperimentArgs) -> CliResult<()> {
    match args.name {
        Name::ShiftComparison => shift_comparison(args),
        Name::MfpScaling => mfp_scaling(args),
    }
}

/// The compare arguments of an experiment on `scene` with `methods`, path tracing at the
/// per-frame time of `restir:hybrid` (measured on replica 0 of this scene).
fn equal_time_args(args: &ExperimentArgs, scene: &str, methods: &str, out: PathBuf) -> CliResult<CompareArgs> {
    let resolution = parse_resolution(&args.resolution)?;
    let loaded = load_scene(scene)?;
    let scene_at = with_resolution(loaded.scene, Some(resolution));
    let hybrid = Method::parse("restir:hybrid")?;
    let budget = hybrid.render(&scene_at, 16, 1_000_000)?.seconds_per_frame;
    Ok(CompareArgs {
        scene: scene.to_string(),
        methods: methods.split(',').map(str::to_string).collect(),
        replicas: args.replicas,
        frames: 16,
        equal_spp: false,
        equal_time: Some(budget),
        resolution: args.resolution.clone(),
        out: Some(out),
        cache: args.cache.clone(),
        reference: None,
        reference_spp: args.reference_spp,
        reference_batch_spp: 64,
        json: false,
    })
}

fn mse(results: &[MethodResult], method: &str, region: Region) -> Option<f64> {
    results
        .iter()
        .find(|r| r.method == method)?
        .metrics
        .iter()
        .find(|m| m.area == Area::Region(region))
        .map(|m| m.mse)
}

/// The method with the lowest MSE in `region` among `among`.
fn best<'a>(results: &[MethodResult], among: &[&'a str], region: Region) -> Option<&'a str> {
    among
        .iter()
        .filter_map(|m| Some((*m, mse(results, m, region)?)))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(m, _)| m)
}

struct Finding {
    claim: String,
    holds: Option<bool>,
    measured: String,
}

fn findings_markdown(findings: &[Finding]) -> String {
    let mut out = String::from("| finding of seed 001 | reproduces | measured |\n|---|---|---|\n");
    for f in findings {
        let holds = match f.holds {
            Some(true) => "yes",
            Some(false) => "**no**",
            None => "n/a (region empty)",
        };
        out.push_str(&format!("| {} | {holds} | {} |\n", f.claim, f.measured));
    }
    out
}

const PRESETS: [&str; 4] = [
    "restir:reconnection",
    "restir:delayed",
    "restir:hybrid",
    "restir:sequential",
];

fn shift_comparison(args: &ExperimentArgs) -> CliResult<()> {
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("out/experiment-shift-comparison"));
    let compare_args = equal_time_args(args, "bumpy", DEFAULT_METHODS, out)?;
    let outcome = compare::run(&compare_args)?;
    let r = &outcome.results;
    let fmt = |m: &str, region| mse(r, m, region).map_or("-".into(), |v| format!("{v:.3e}"));
    let list = |region| {
        PRESETS
            .iter()
            .chain(["pt"].iter())
            .map(|m| format!("{}={}", m.trim_start_matches("restir:"), fmt(m, region)))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let mut findings = vec![
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
                let worst_new = mse(r, "restir:hybrid", Region::Translucent)?
                    .max(mse(r, "restir:sequential", Region::Translucent)?);
                let best_old = mse(r, "restir:reconnection", Region::Translucent)?
                    .min(mse(r, "restir:delayed", Region::Translucent)?);
                Some(worst_new < best_old)
            })(),
            measured: list(Region::Translucent),
        },
    ];
    for region in [Region::Shadowed, Region::Penumbra] {
        findings.push(Finding {
            claim: format!("every ReSTIR preset is below equal-time path tracing in {region} regions"),
            holds: mse(r, "pt", region).map(|pt| {
                PRESETS
                    .iter()
                    .all(|m| mse(r, m, region).is_some_and(|v| v < pt))
            }),
            measured: list(region),
        });
    }
    let table = findings_markdown(&findings);
    write_file(&outcome.out.join("findings.md"), &table)?;
    report(args, &outcome.markdown, &table, &outcome.out, outcome.json)
}

const MFP_SCENES: [(&str, f64); 5] = [
    ("mfp-0.25", 0.25),
    ("mfp-0.5", 0.5),
    ("mfp-1", 1.0),
    ("mfp-2", 2.0),
    ("mfp-4", 4.0),
];

fn mfp_scaling(args: &ExperimentArgs) -> CliResult<()> {
    let root = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("out/experiment-mfp-scaling"));
    let methods = "pt,restir:hybrid,restir:sequential";
    let mut table = String::from(
        "| mfp scale | pt spp (equal time) | MSE pt | MSE hybrid | MSE sequential | gain pt/hybrid | gain pt/sequential |\n|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    let mut gains = Vec::new();
    let mut runs = Vec::new();
    for (scene, scale) in MFP_SCENES {
        let compare_args = equal_time_args(args, scene, methods, root.join(scene))?;
        let outcome = compare::run(&compare_args)?;
        let r = &outcome.results;
        let get = |m| mse(r, m, Region::Translucent).ok_or_else(|| CliError(format!("{scene}: no translucent pixels")));
        let (pt, hybrid, sequential) = (get("pt")?, get("restir:hybrid")?, get("restir:sequential")?);
        let spp = r.iter().find(|x| x.method == "pt").map_or(0, |x| x.spp);
        table.push_str(&format!(
            "| {scale} | {spp} | {pt:.3e} | {hybrid:.3e} | {sequential:.3e} | {:.2} | {:.2} |\n",
            pt / hybrid,
            pt / sequential
        ));
        gains.push((scale, pt / hybrid, pt / sequential));
        runs.push(outcome.json);
    }
    let increasing = |pick: fn(&(f64, f64, f64)) -> f64| gains.windows(2).filter(|w| pick(&w[1]) > pick(&w[0])).count();
    let steps = gains.len() - 1;
    let findings = [Finding {
        claim: "the gain over equal-time path tracing grows with the mean free path".into(),
        holds: Some(
            gains.last().map(|g| g.1) > gains.first().map(|g| g.1)
                && gains.last().map(|g| g.2) > gains.first().map(|g| g.2),
        ),
        measured: format!(
            "gain rises in {}/{steps} steps (hybrid), {}/{steps} (sequential); largest vs. smallest mfp compared",
            increasing(|g| g.1),
            increasing(|g| g.2)
        ),
    }];
    let findings = findings_markdown(&findings);
    let all = format!("{table}\nTranslucent pixels, MSE in linear HDR; gain = MSE(pt) / MSE(method).\n");
    super::common::output_dir(&root)?;
    write_file(&root.join("table.md"), &all)?;
    write_file(&root.join("findings.md"), &findings)?;
    report(args, &all, &findings, &root, json!({ "schema": "reshift-experiment/1", "runs": runs }))
}

fn report(
    args: &ExperimentArgs,
    table: &str,
    findings: &str,
    out: &std::path::Path,
    json: serde_json::Value,
) -> CliResult<()> {
    if args.json {
        println!("{}", serde_json::to_string_pretty(&json).expect("JSON values"));
    } else {
        println!("{table}\n{findings}\nOutputs are in {}", out.display());
    }
    Ok(())
}
