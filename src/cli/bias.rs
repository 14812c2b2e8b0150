//! `reshift bias`: N replicas of one method against independent path-traced reference batches
//! (the path tracer with the method's reference settings, `Method::reference`: the dipole
//! profile for `image-space`); per region and colour channel (red, green, blue, luminance) the
//! Welch test of zero bias (Holm across all of them) and the verdict "equivalent within ±δ at
//! 1 − α", "biased" or "inconclusive" (`lab::bias`); what it prints: the overall verdict in words and the JSON of the test
//! (schema `reshift-bias/2`, docs/results-schema.md).

use clap::Args;
use glam::DVec3;
use lab::bias::{
    BiasRow, Protocol, Table, bias_rows, overall, reference_images_with, replicas_needed,
    summarize, test_bytes,
};
use lab::limits::MAX_REPLICAS;
use lab::reference_cache::REFERENCE_SEED;
use lab::regions::Regions;
use methods::Method;
use restir::stats::Verdict;
use serde_json::{Value, json};
use sss::limits::{self, MAX_SPP};
use sss::scene::GBuffer;

use super::common::{
    BackendArgs, CliError, CliResult, command_line, interrupted, json_number, load_scene,
    parse_resolution, progress, with_resolution,
};

/// The power for which `bias` plans the replicas a method needs.
const PLANNED_POWER: f64 = 0.9;

#[derive(Args, Clone, Debug)]
pub struct BiasArgs {
    /// Built-in scene name or path to a scene .toml.
    #[arg(long, default_value = "bumpy")]
    pub scene: String,
    /// The method under test, e.g. restir:hybrid.
    #[arg(long)]
    pub method: String,
    /// Independent replicas (seeds 0..N).
    #[arg(long, default_value_t = 256)]
    pub replicas: u32,
    /// Tolerance δ on the relative bias of a region's mean in each channel (0.02 = ±2%).
    #[arg(long, default_value_t = 0.02)]
    pub delta: f64,
    /// Family-wise level α (each CI has confidence 1 − α).
    #[arg(long, default_value_t = 0.01)]
    pub alpha: f64,
    /// Frames of the camera trajectory; the last one is tested.
    #[arg(long, default_value_t = 16)]
    pub frames: u32,
    /// Image size WxH.
    #[arg(long, default_value = "64x48")]
    pub resolution: String,
    /// Independent path-traced reference batches.
    #[arg(long, default_value_t = 32)]
    pub reference_batches: u32,
    /// Samples per pixel of one reference batch.
    #[arg(long, default_value_t = 64)]
    pub reference_batch_spp: u32,
    /// Print JSON (schema `reshift-bias/1`) instead of the table.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub backend: BackendArgs,
}

pub fn command(args: &BiasArgs) -> CliResult<()> {
    let method = Method::parse(&args.method)?;
    let valid = args.delta > 0.0 && args.delta.is_finite() && args.alpha > 0.0 && args.alpha < 1.0;
    if !valid {
        return Err(CliError(format!(
            "need δ > 0 and 0 < α < 1 (got --delta {} --alpha {})",
            args.delta, args.alpha
        )));
    }
    let resolution = check_sizes(args)?;
    let backend = args.backend.open()?;
    let loaded = load_scene(&args.scene)?;
    let scene = with_resolution(loaded.scene, Some(resolution));
    let frame = args.frames - 1;
    let regions = Regions::classify(&scene, &GBuffer::render(&scene, frame), REFERENCE_SEED);
    let reference_settings = method.reference();
    let profile = reference_settings.profile.name();
    let reference = reference_images_with(
        &reference_settings,
        &scene,
        frame,
        args.reference_batches,
        args.reference_batch_spp,
        REFERENCE_SEED,
    )?;
    let bar = progress(args.replicas as u64, &method.name());
    let (mut images, mut nonfinite): (Vec<Vec<DVec3>>, u64) = (Vec::new(), 0);
    for seed in 0..args.replicas as u64 {
        if interrupted() {
            break;
        }
        let rendered = method.render_on(&backend, &scene, args.frames, seed)?;
        nonfinite += rendered.nonfinite;
        images.push(rendered.image.pixels.iter().map(|p| p.as_dvec3()).collect());
        bar.inc(1);
    }
    bar.finish_and_clear();
    let stopped = images.len() < args.replicas as usize;
    if images.len() < 2 {
        return Err(CliError("interrupted before 2 replicas finished".into()));
    }
    let protocol = Protocol {
        delta: args.delta,
        alpha: args.alpha,
    };
    let rows = bias_rows(
        &method.name(),
        &summarize(&images, &regions),
        &summarize(&reference.rgb, &regions),
        &protocol,
    );
    let planned = replicas_needed(&rows, &protocol, PLANNED_POWER);
    if args.json {
        let value = bias_json(
            args,
            &scene.name,
            &rows,
            planned.ok(),
            profile,
            [nonfinite, reference.nonfinite],
            images.len(),
            stopped,
        );
        println!(
            "{}",
            serde_json::to_string_pretty(&value).expect("JSON values")
        );
    } else {
        println!(
            "# bias of {} on {} ({}, frame {frame}): N = {} replicas vs {} reference batches × {} spp ({profile} profile); per region and channel, δ = ±{}%, α = {} ({}% CIs, Holm across all rows)\n",
            method,
            scene.name,
            args.resolution,
            images.len(),
            args.reference_batches,
            args.reference_batch_spp,
            100.0 * args.delta,
            args.alpha,
            100.0 * (1.0 - args.alpha)
        );
        println!("{}", Table(&rows));
        println!(
            "verdict: {}; non-finite values: {} in replicas, {} in the reference",
            verdict_line(&rows, &protocol),
            nonfinite,
            reference.nonfinite
        );
        let goal = format!(
            "every row equivalent within ±{}% with probability ≥ {PLANNED_POWER} if the method had no bias",
            100.0 * args.delta
        );
        match planned {
            Ok(n) => println!("planned: N = {n} for {goal} (from this run's per-replica CVs)"),
            Err(why) => println!("planned: no N for {goal}: {why}"),
        }
    }
    if stopped {
        return Err(CliError(format!(
            "interrupted after {} of {} replicas",
            images.len(),
            args.replicas
        )));
    }
    Ok(())
}

/// The resolution, once every count is within `sss::limits` (at least two replicas and two
/// reference batches, for their standard errors) and the test fits the memory budget.
fn check_sizes(args: &BiasArgs) -> CliResult<(u32, u32)> {
    let line = command_line();
    let count = |flag: &str, n: u32, min: u32, max: u32| {
        limits::count(line, flag, n as u64, min as u64, max as u64)
    };
    count("--replicas", args.replicas, 2, MAX_REPLICAS)?;
    count(
        "--reference-batches",
        args.reference_batches,
        2,
        MAX_REPLICAS,
    )?;
    count(
        "--reference-batch-spp",
        args.reference_batch_spp,
        1,
        MAX_SPP,
    )?;
    limits::frames(line, "--frames", args.frames)?;
    let (width, height) = parse_resolution(&args.resolution)?;
    let value = format!(
        "{} replicas, {} reference batches, {} frames at {width}×{height}",
        args.replicas, args.reference_batches, args.frames
    );
    let pixels = width as u64 * height as u64;
    let needed = test_bytes(pixels, args.replicas, args.reference_batches, args.frames);
    limits::memory(line, "--replicas", &value, needed, "the bias test")?;
    Ok((width, height))
}

/// The overall verdict in words: `equivalent within ±δ at 99% in every region and channel`,
/// `biased (in k of n rows)` or `inconclusive (k of n rows not decided)`.
fn verdict_line(rows: &[BiasRow], protocol: &Protocol) -> String {
    let count = |v| rows.iter().filter(|r| r.verdict == v).count();
    let verdict = overall(rows);
    match verdict {
        Verdict::Equivalent => {
            format!("{} in every region and channel", protocol.describe(verdict))
        }
        Verdict::Biased => format!("biased (in {} of {} rows)", count(verdict), rows.len()),
        Verdict::Inconclusive => format!(
            "inconclusive ({} of {} rows not decided)",
            count(verdict),
            rows.len()
        ),
    }
}

/// JSON of the bias test (schema `reshift-bias/2`, docs/results-schema.md).
fn bias_json(
    args: &BiasArgs,
    scene: &str,
    rows: &[BiasRow],
    planned: Option<usize>,
    profile: &str,
    [replica_nonfinite, reference_nonfinite]: [u64; 2],
    replicas: usize,
    interrupted: bool,
) -> Value {
    let verdict = overall(rows);
    let rows: Vec<Value> = rows
        .iter()
        .map(|r| {
            let e = &r.equivalence;
            json!({
                "region": r.region.name(),
                "channel": r.channel.name(),
                "pixels": r.pixels,
                "n": e.n,
                "mean": json_number(r.estimate.mean),
                "reference_mean": json_number(r.reference.mean),
                "reference_std_err": json_number(r.reference.std_err),
                "relative_bias": json_number(e.relative_bias),
                "ci_low": json_number(e.ci_low),
                "ci_high": json_number(e.ci_high),
                "ci_half_width": json_number(r.ci_half_width()),
                "p_zero_bias": json_number(e.p_zero_bias),
                "holm_rejected": r.holm_rejected,
                "verdict": r.verdict.name(),
            })
        })
        .collect();
    json!({
        "schema": "reshift-bias/2",
        "scene": scene,
        "method": args.method,
        "resolution": args.resolution,
        "frames": args.frames,
        "replicas": replicas,
        "delta": args.delta,
        "alpha": args.alpha,
        "confidence": 1.0 - args.alpha,
        "reference": {
            "batches": args.reference_batches,
            "spp_per_batch": args.reference_batch_spp,
            "profile": profile,
            "seed": REFERENCE_SEED,
        },
        "nonfinite": { "replicas": replica_nonfinite, "reference": reference_nonfinite },
        "interrupted": interrupted,
        "verdict": verdict.name(),
        "planned": { "power": PLANNED_POWER, "replicas": planned },
        "rows": rows,
    })
}
