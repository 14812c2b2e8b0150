//! `reshift compare`: K replicas of several methods on one scene against a cached reference
//! (`lab::compare`); writes `table.md`, `table.csv`, `results.json` (docs/results-schema.md) and
//! images, and prints the table or the JSON.

use std::path::PathBuf;

use clap::Args;
use lab::compare::{self, DEFAULT_METHODS, Plan, parse_methods};
use lab::reference_cache::ReferenceSource;
use lab::report::file_stem;

use sss::limits;

use super::common::{
    BackendArgs, Bars, CliError, CliResult, LoadedScene, command_line, load_scene,
    parse_resolution, with_resolution,
};

#[derive(Args, Clone, Debug)]
pub struct CompareArgs {
    /// Built-in scene name or path to a scene .toml.
    #[arg(long, default_value = "bumpy")]
    pub scene: String,
    /// Comma-separated methods (see `reshift methods`).
    #[arg(long, value_delimiter = ',', default_value = DEFAULT_METHODS)]
    pub methods: Vec<String>,
    /// Independent replicas per method (seeds 0..K).
    #[arg(long, default_value_t = 8)]
    pub replicas: u32,
    /// Frames of the camera trajectory; errors are measured on the last one.
    #[arg(long, default_value_t = 16)]
    pub frames: u32,
    /// Every method at its own samples per pixel (the default).
    #[arg(long, conflicts_with = "equal_time")]
    pub equal_spp: bool,
    /// Scale a bare `pt` to this many seconds per frame (`pt:N` and ReSTIR presets keep their cost).
    #[arg(long, value_name = "SECONDS")]
    pub equal_time: Option<f64>,
    /// Image size WxH.
    #[arg(long, default_value = "128x96")]
    pub resolution: String,
    /// Output folder [default: out/compare-<scene>].
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Folder of cached references.
    #[arg(long, default_value = "out/cache")]
    pub cache: PathBuf,
    /// Use this reference checkpoint (from `reshift reference`) instead of the cache.
    #[arg(long)]
    pub reference: Option<PathBuf>,
    /// Samples per pixel of the reference (a multiple of --reference-batch-spp).
    #[arg(long, default_value_t = 8192)]
    pub reference_spp: u32,
    /// Samples per pixel of one reference batch.
    #[arg(long, default_value_t = 128)]
    pub reference_batch_spp: u32,
    /// Print results.json to stdout instead of the table.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub backend: BackendArgs,
}

/// Runs `compare` and prints the table (or the JSON); a comparison stopped by Ctrl-C prints
/// its partial results and fails.
pub fn command(args: &CompareArgs) -> CliResult<()> {
    let outcome = compare::run(&plan(args)?, &mut Bars::default())?;
    if args.json {
        println!("{}", outcome.results.to_json_pretty());
    } else {
        println!("{}", outcome.markdown);
        println!(
            "Images, table.md, table.csv and results.json are in {}",
            outcome.out.display()
        );
    }
    if outcome.results.interrupted {
        return Err(CliError("interrupted: partial results written".into()));
    }
    Ok(())
}

/// The plan of `args`, checked with errors that name the flags.
fn plan(args: &CompareArgs) -> CliResult<Plan> {
    let methods = parse_methods(&args.methods)?;
    if methods.is_empty() {
        return Err(CliError("--methods: no method given".into()));
    }
    limits::replicas(command_line(), "--replicas", args.replicas)?;
    limits::frames(command_line(), "--frames", args.frames)?;
    if let Some(t) = args.equal_time
        && !(t.is_finite() && t > 0.0)
    {
        return Err(CliError(format!(
            "--equal-time {t}: must be a positive number of seconds"
        )));
    }
    let reference = match &args.reference {
        Some(path) => ReferenceSource::File(path.clone()),
        None => {
            let (spp, batch) = (args.reference_spp, args.reference_batch_spp);
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
    let resolution = parse_resolution(&args.resolution)?;
    let backend = args.backend.open()?;
    let LoadedScene { scene, key } = load_scene(&args.scene)?;
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("out/compare-{}", file_stem(&key))));
    Ok(Plan {
        scene: with_resolution(scene, Some(resolution)),
        scene_key: key,
        methods,
        replicas: args.replicas,
        frames: args.frames,
        equal_time: args.equal_time,
        reference,
        out,
        backend,
    })
}
