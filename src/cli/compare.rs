//! `reshift compare`: K replicas of several methods on one scene against cached references
//! (`lab::compare`); writes `table.md`, `table.csv`, `convergence.csv`, `results.json`
//! (docs/results-schema.md), images, `figure.png`, `convergence.png`, the trajectory videos
//! (`video/`) and `report.html`, and
//! prints the table with the efficiency verdicts over the baseline, or the JSON. With
//! `--shard i/n` it writes one shard's files instead, which `reshift merge` makes the report of.

use std::path::{Path, PathBuf};

use clap::Args;
use engine::denoise::Denoiser;
use lab::compare::shard::{CompareShard, payload_path, run_shard};
use lab::compare::{
    self, Comparison, DEFAULT_BASELINE, DEFAULT_METHODS, Outcome, frame_reference_spp,
    parse_methods,
};
use lab::output::file_stem;
use lab::reference_cache::ReferenceSource;
use lab::report;
use lab::shard::Shard;
use serde_json::Value;

use super::common::{
    BackendArgs, Bars, CliError, CliResult, LoadedScene, command_line, load_scene,
    parse_resolution, scene_and_frames, with_resolution,
};

#[derive(Args, Clone, Debug)]
pub struct CompareArgs {
    /// Built-in scene name or path to a scene .toml.
    #[arg(long, default_value = "bumpy")]
    pub scene: String,
    /// Comma-separated methods (see `reshift methods`).
    #[arg(long, value_delimiter = ',', default_value = DEFAULT_METHODS)]
    pub methods: Vec<String>,
    /// The method efficiency ratios are taken against (one of --methods).
    #[arg(long, default_value = DEFAULT_BASELINE)]
    pub baseline: String,
    /// Independent replicas per method (seeds S..S+K, S = --first-seed).
    #[arg(long, default_value_t = 8)]
    pub replicas: u32,
    /// Seed S of the first replica. A run whose seeds do not overlap an earlier run's shares no
    /// random number with it: `--first-seed 8` after a default run of 8 replicas is an
    /// independent, confirmatory run.
    #[arg(long, value_name = "S", default_value_t = 0)]
    pub first_seed: u64,
    /// Frames of the camera trajectory; the tables measure the last one, the convergence record
    /// every one [default: 16, or the poses of --trajectory].
    #[arg(long)]
    pub frames: Option<u32>,
    /// Replay this camera path (a trajectory file, e.g. recorded by `reshift view --record`)
    /// instead of the scene camera's.
    #[arg(long, value_name = "FILE")]
    pub trajectory: Option<PathBuf>,
    /// Every method at its own samples per pixel (the default).
    #[arg(long, conflicts_with = "equal_time")]
    pub equal_spp: bool,
    /// Scale a bare `pt` to this many seconds per frame (`pt:N` and ReSTIR presets keep their
    /// cost), on the backend's clock: CPU seconds of the process on the CPU backend (about twice
    /// the wall time on 2 cores), wall seconds on Vulkan.
    #[arg(long, value_name = "SECONDS")]
    pub equal_time: Option<f64>,
    /// Image size WxH [default: the scene's own; 256x192 for the built-in procedural scenes].
    #[arg(long)]
    pub resolution: Option<String>,
    /// Output folder [default: out/compare-<scene>].
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Folder of cached references.
    #[arg(long, default_value = "out/cache")]
    pub cache: PathBuf,
    /// Use this reference checkpoint (from `reshift reference`) instead of the cache.
    #[arg(long)]
    pub reference: Option<PathBuf>,
    /// Samples per pixel of the last frame's reference (a multiple of --reference-batch-spp).
    #[arg(long, default_value_t = 4096)]
    pub reference_spp: u32,
    /// Samples per pixel of the references of earlier frames (their variance is subtracted);
    /// 0 measures the last frame only [default: 1/32 of --reference-spp, at least 2 batches].
    #[arg(long)]
    pub frame_reference_spp: Option<u32>,
    /// Samples per pixel of one reference batch.
    #[arg(long, default_value_t = 128)]
    pub reference_batch_spp: u32,
    /// Denoisers every replica's last frame also passes through, measured like the raw frames
    /// (the reference is never denoised): `none`, `oidn` (Intel Open Image Denoise, loaded at
    /// run time), `svgf` (built in), `all`, a comma-separated list, or `auto`: `svgf`, and `oidn`
    /// where it is installed.
    #[arg(long, value_name = "DENOISERS", default_value = "auto")]
    pub denoise: String,
    /// Write no trajectory videos (by default each method's replica-0 frames, raw and through
    /// each denoiser, are written beside the reference and the error as a looping animated PNG, and as MP4 where ffmpeg is on the
    /// PATH, and played in report.html).
    #[arg(long)]
    pub no_video: bool,
    /// Print results.json to stdout instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Render only shard i of n (0-based, i < n): the replicas of seeds S + ⌊i·N/n⌋ .. S +
    /// ⌊(i+1)·N/n⌋ of every method, written to <out>/shard-i-of-n.json and .bin after obtaining the
    /// references from --cache; `reshift merge` of all n writes the report of one run, every
    /// measured figure and image bit for bit (docs/cluster.md). Not with --equal-time.
    #[arg(long, value_name = "i/n")]
    pub shard: Option<String>,
    #[command(flatten)]
    pub backend: BackendArgs,
}

/// The denoisers of `--denoise` and whether they were named (a named one that fails is an
/// error; `auto` leaves out one that is not installed, with a note).
pub fn parse_denoise(text: &str) -> CliResult<(Vec<Denoiser>, bool)> {
    match text {
        "none" => Ok((Vec::new(), true)),
        "all" => Ok((Denoiser::ALL.to_vec(), true)),
        "auto" => {
            let mut found = Vec::new();
            for d in Denoiser::ALL {
                match d.available() {
                    Ok(()) => found.push(d),
                    Err(e) => eprintln!("note: --denoise auto leaves out {d}: {e}"),
                }
            }
            Ok((found, false))
        }
        list => {
            let mut named = Vec::new();
            for name in list.split(',') {
                let d = Denoiser::parse(name.trim()).ok_or_else(|| {
                    CliError(format!(
                        "--denoise {list}: unknown denoiser {name:?}; use none, oidn, svgf, all or auto"
                    ))
                })?;
                if !named.contains(&d) {
                    named.push(d);
                }
            }
            Ok((named, true))
        }
    }
}

/// Runs `compare` and prints the table (or the JSON), or with `--shard` writes the shard's
/// files; a comparison stopped by Ctrl-C prints its partial results and fails.
pub fn command(args: &CompareArgs) -> CliResult<()> {
    let (denoise, named) = parse_denoise(&args.denoise)?;
    let plan = Comparison {
        denoise,
        ..plan(args)?
    };
    if let Some(text) = &args.shard {
        let shard = Shard::parse(text, "--shard")?;
        let trajectory = args.trajectory.as_deref();
        let path = run_shard(&plan, &args.scene, trajectory, shard, &mut Bars::default())?;
        println!(
            "shard {}/{} of {} replicas: written to {} (and {})",
            shard.index,
            shard.count,
            args.replicas,
            path.display(),
            payload_path(&path).display()
        );
        return Ok(());
    }
    let outcome = compare::run(&plan, &mut Bars::default())?;
    write_report(&plan, &outcome, args.json)?;
    if outcome.interrupted {
        return Err(CliError("interrupted: partial results written".into()));
    }
    if named && !outcome.denoise_errors.is_empty() {
        return Err(CliError(format!(
            "--denoise {}: {} denoised row group(s) left out (see above); the raw results are \
             written",
            args.denoise,
            outcome.denoise_errors.len()
        )));
    }
    Ok(())
}

/// Writes the report of `outcome` into its folder and prints the table (or the JSON) and the
/// denoisers' and videos' notes.
fn write_report(plan: &Comparison, outcome: &Outcome, json: bool) -> CliResult<()> {
    let written = report::write(plan, outcome)?;
    for e in &outcome.denoise_errors {
        eprintln!("denoiser: {e}");
    }
    for note in &written.results.video_notes {
        eprintln!("note: videos: {note}");
    }
    if json {
        println!("{}", written.results.to_json_pretty());
    } else {
        println!("{}", written.markdown);
        if written.results.baseline.is_none() {
            println!(
                "No efficiency ratios: the baseline {:?} is not among the methods.",
                plan.baseline
            );
        }
        println!(
            "report.html, figure.png, convergence.png, tables, images and results.json are in {}",
            outcome.out.display()
        );
    }
    Ok(())
}

/// `reshift merge` of compare shards (their header files' JSON): writes the report one run
/// writes into `out` (default: the first shard's folder) and prints its table (or the JSON).
pub fn merge(files: Vec<(PathBuf, Value)>, out: Option<PathBuf>, json: bool) -> CliResult<()> {
    let parts = files
        .into_iter()
        .map(|(path, value)| {
            Ok((
                path.clone(),
                lab::shard::parse::<CompareShard>(&path, value)?,
            ))
        })
        .collect::<Result<Vec<_>, lab::Error>>()?;
    let out = out.unwrap_or_else(|| {
        let folder = parts[0].0.parent().map(Path::to_path_buf);
        folder.unwrap_or_default()
    });
    let (plan, outcome) = compare::shard::merge(parts, out, &mut Bars::default())?;
    write_report(&plan, &outcome, json)
}

/// The plan of `args`, checked with errors that name the flags.
fn plan(args: &CompareArgs) -> CliResult<Comparison> {
    let methods = parse_methods(&args.methods)?;
    if methods.is_empty() {
        return Err(CliError("--methods: no method given".into()));
    }
    lab::limits::replicas(command_line(), "--replicas", args.replicas)?;
    if args.first_seed.checked_add(args.replicas as u64).is_none() {
        return Err(CliError(format!(
            "--first-seed {}: with --replicas {} it passes the largest seed, {}",
            args.first_seed,
            args.replicas,
            u64::MAX
        )));
    }
    if let Some(t) = args.equal_time
        && !(t.is_finite() && t > 0.0)
    {
        return Err(CliError(format!(
            "--equal-time {t}: must be a positive number of seconds"
        )));
    }
    let (spp, batch) = (args.reference_spp, args.reference_batch_spp);
    let frame_spp = args
        .frame_reference_spp
        .unwrap_or_else(|| frame_reference_spp(spp, batch));
    if frame_spp != 0 && (batch == 0 || frame_spp < 2 * batch || !frame_spp.is_multiple_of(batch)) {
        return Err(CliError(format!(
            "--frame-reference-spp {frame_spp} must be 0 or a multiple ≥ 2× of --reference-batch-spp {batch}"
        )));
    }
    let reference = match &args.reference {
        Some(path) => ReferenceSource::File(path.clone()),
        None => {
            if batch == 0 || spp < 2 * batch || !spp.is_multiple_of(batch) {
                return Err(CliError(format!(
                    "--reference-spp {spp} must be a multiple ≥ 2× of --reference-batch-spp {batch}"
                )));
            }
            ReferenceSource::Cache {
                dir: args.cache.clone(),
                spp,
                batch_spp: batch,
            }
        }
    };
    let resolution = args
        .resolution
        .as_deref()
        .map(parse_resolution)
        .transpose()?;
    let backend = args.backend.open()?;
    let (LoadedScene { scene, key }, frames) = scene_and_frames(
        load_scene(&args.scene)?,
        args.trajectory.as_deref(),
        args.frames,
    )?;
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("out/compare-{}", file_stem(&key))));
    Ok(Comparison {
        scene: with_resolution(scene, resolution),
        scene_key: key,
        methods,
        baseline: args.baseline.clone(),
        replicas: args.replicas,
        first_seed: args.first_seed,
        frames,
        equal_time: args.equal_time,
        reference,
        frame_reference_spp: (frame_spp > 0).then_some(frame_spp),
        out,
        backend,
        video: !args.no_video,
        denoise: Vec::new(),
    })
}
