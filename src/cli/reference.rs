//! `reshift reference` and the merge of its checkpoints (for `reshift merge`, `super::merge`):
//! progressive references with checkpoint/resume and shards `i/n` (e.g. one per Slurm array
//! task), merged bit-identically to an unsharded run (`sss::integrator::reference` sums
//! exactly).

use std::path::{Path, PathBuf};

use clap::Args;
use lab::output::output_dir;
use lab::reference_cache::{REFERENCE_SEED, accumulate, mean_image};
use serde_json::json;
use sss::integrator::pt::PtSettings;
use sss::integrator::{Reference, ReferenceConfig, Shard};
use sss::scene::FRAMES;

use super::common::{Bars, CliError, CliResult, interrupted, load_scene_at};

#[derive(Args, Clone, Debug)]
pub struct ReferenceArgs {
    /// Built-in scene name or path to a scene .toml.
    #[arg(long)]
    pub scene: String,
    /// Total samples per pixel of the whole (unsharded) reference.
    #[arg(long)]
    pub spp: u32,
    /// Samples per pixel of one batch (the unit of checkpoints and shards).
    #[arg(long, default_value_t = 16)]
    pub batch_spp: u32,
    /// Frame of the camera trajectory [default: the last, 15].
    #[arg(long, default_value_t = FRAMES - 1)]
    pub frame: u32,
    /// Image size WxH [default: the scene's].
    #[arg(long)]
    pub resolution: Option<String>,
    /// Seed of the batches.
    #[arg(long, default_value_t = REFERENCE_SEED)]
    pub seed: u64,
    /// Render only shard i of n (batches ⌊iB/n⌋..⌊(i+1)B/n⌋).
    #[arg(long, value_name = "i/n")]
    pub shard: Option<String>,
    /// Continue the checkpoint at --out instead of starting over.
    #[arg(long)]
    pub resume: bool,
    /// Render at most this many batches now, then checkpoint and exit 0 (time-sliced jobs).
    #[arg(long)]
    pub max_batches: Option<u32>,
    /// Checkpoint file; the mean is also written to <out>.exr when complete.
    #[arg(long)]
    pub out: PathBuf,
    /// Print a JSON summary.
    #[arg(long)]
    pub json: bool,
}

/// `<path>.exr`: the per-pixel mean.
fn write_mean(reference: &Reference, path: &Path) -> CliResult<PathBuf> {
    let mut name = path.as_os_str().to_owned();
    name.push(".exr");
    let exr = PathBuf::from(name);
    mean_image(reference).write_exr(&exr)?;
    Ok(exr)
}

fn summary(reference: &Reference, path: &Path, exr: Option<&Path>, json: bool) {
    let c = &reference.config;
    if json {
        let value = json!({
            "schema": "reshift-reference/1",
            "path": path.display().to_string(),
            "exr": exr.map(|p| p.display().to_string()),
            "scene": c.scene,
            "width": reference.width,
            "height": reference.height,
            "frame": c.frame,
            "seed": c.seed,
            "spp_per_batch": c.spp_per_batch,
            "batches_planned": c.batches,
            "batches": [reference.start, reference.next],
            "owned": [reference.start, reference.end],
            "complete": reference.is_complete(),
            "nonfinite": reference.nonfinite,
        });
        println!(
            "{}",
            serde_json::to_string_pretty(&value).expect("JSON values")
        );
    } else {
        println!(
            "{}: {} {}×{} frame {}, batches {}..{} of {}..{} ({} spp each){}{}",
            path.display(),
            c.scene,
            reference.width,
            reference.height,
            c.frame,
            reference.start,
            reference.next,
            reference.start,
            reference.end,
            c.spp_per_batch,
            if reference.is_complete() {
                ", complete"
            } else {
                ", partial"
            },
            exr.map_or(String::new(), |p| format!("; mean in {}", p.display())),
        );
    }
}

pub fn command(args: &ReferenceArgs) -> CliResult<()> {
    let scene = load_scene_at(&args.scene, args.resolution.as_deref())?.scene;
    if args.batch_spp == 0 || !args.spp.is_multiple_of(args.batch_spp) || args.spp < args.batch_spp
    {
        return Err(CliError(format!(
            "--spp {} must be a positive multiple of --batch-spp {}",
            args.spp, args.batch_spp
        )));
    }
    let shard = match &args.shard {
        Some(text) => Shard::parse(text, "--shard")?,
        None => Shard::WHOLE,
    };
    let config = ReferenceConfig {
        scene: scene.name.clone(),
        frame: args.frame,
        seed: args.seed,
        spp_per_batch: args.batch_spp,
        batches: args.spp / args.batch_spp,
        settings: PtSettings::default(),
    };
    let (width, height) = (scene.camera.width(), scene.camera.height());
    let fresh = Reference::new(config, width, height, shard)?;
    let mut reference = if args.resume && args.out.exists() {
        let loaded = Reference::load(&args.out)?;
        if loaded.config != fresh.config
            || (loaded.width, loaded.height, loaded.start, loaded.end)
                != (width, height, fresh.start, fresh.end)
        {
            return Err(CliError(format!(
                "{}: --resume: the checkpoint is of another reference or shard ({} {}×{} frame {}, batches {}..{})",
                args.out.display(),
                loaded.config.scene,
                loaded.width,
                loaded.height,
                loaded.config.frame,
                loaded.start,
                loaded.end
            )));
        }
        loaded
    } else {
        fresh
    };
    if let Some(parent) = args.out.parent().filter(|p| !p.as_os_str().is_empty()) {
        output_dir(parent)?;
    }
    accumulate(
        &mut reference,
        &scene,
        &args.out,
        "reference batches",
        args.max_batches,
        &mut Bars::default(),
    )?;
    let exr = if reference.is_complete() {
        Some(write_mean(&reference, &args.out)?)
    } else {
        None
    };
    summary(&reference, &args.out, exr.as_deref(), args.json);
    if interrupted() {
        return Err(CliError(format!(
            "interrupted; resume with --resume --out {}",
            args.out.display()
        )));
    }
    Ok(())
}

/// `reshift merge` of reference checkpoints: the merged checkpoint at `out` and its mean beside
/// it.
pub fn merge(shards: &[PathBuf], out: &Path, json: bool) -> CliResult<()> {
    let parts = shards
        .iter()
        .map(|p| Ok((p.clone(), Reference::load(p)?)))
        .collect::<Result<Vec<_>, CliError>>()?;
    let merged = Reference::merge(parts)?;
    if let Some(parent) = out.parent().filter(|p| !p.as_os_str().is_empty()) {
        output_dir(parent)?;
    }
    merged
        .save(out)
        .map_err(|e| CliError(format!("{}: {e}", out.display())))?;
    let exr = write_mean(&merged, out)?;
    summary(&merged, out, Some(&exr), json);
    Ok(())
}
