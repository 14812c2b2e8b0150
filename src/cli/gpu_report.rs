//! `reshift gpu-report`: on the Vulkan device, the device and its limits, the parity of every
//! preset with the CPU, the time of every pass of every preset and method at each size, and an
//! equal-time `compare` against path tracing, in one markdown file for `docs/performance.md`
//! (`lab::gpu_report`). Fails after writing the file when a parity check failed.

use std::path::PathBuf;

use clap::Args;
use lab::gpu_report::{self, CompareSettings, Settings};

use sss::limits;

use super::common::{
    BackendArgs, BackendKind, Bars, CliError, CliResult, command_line, parse_size,
};

#[derive(Args, Clone, Debug)]
pub struct GpuReportArgs {
    /// Built-in scene name or path to a scene .toml.
    #[arg(long, default_value = "bumpy")]
    pub scene: String,
    /// Comma-separated resolutions WxH of the timing table.
    #[arg(long, value_delimiter = ',', default_value = "1280x720,1920x1080")]
    pub sizes: Vec<String>,
    /// Frames per timed run (frame 0 is left out of the statistics).
    #[arg(long, default_value_t = 16)]
    pub frames: u32,
    /// Resolution WxH of the parity runs.
    #[arg(long, default_value = "128x96")]
    pub parity_size: String,
    /// Frames of the parity runs.
    #[arg(long, default_value_t = 4)]
    pub parity_frames: u32,
    /// Resolution WxH of the equal-time comparison.
    #[arg(long, default_value = "1920x1080")]
    pub compare_size: String,
    /// Replicas of the comparison.
    #[arg(long, default_value_t = 2)]
    pub compare_replicas: u32,
    /// Frames of the comparison.
    #[arg(long, default_value_t = 4)]
    pub compare_frames: u32,
    /// Samples per pixel of the comparison's path-traced reference (a multiple ≥ 2× of
    /// --reference-batch-spp).
    #[arg(long, default_value_t = 256)]
    pub reference_spp: u32,
    /// Samples per pixel of one reference batch.
    #[arg(long, default_value_t = 64)]
    pub reference_batch_spp: u32,
    /// Folder of cached references.
    #[arg(long, default_value = "out/cache")]
    pub cache: PathBuf,
    /// Skip the equal-time comparison.
    #[arg(long)]
    pub no_compare: bool,
    /// The markdown file to write; the comparison's files go beside it, in `<stem>-compare/`.
    #[arg(long, default_value = "out/gpu-report.md")]
    pub out: PathBuf,
    /// With --backend vulkan (the only backend it runs on): fail on a CPU device (lavapipe).
    #[arg(long)]
    pub require_gpu: bool,
    /// The device whose name contains this text (as RESHIFT_VULKAN_DEVICE).
    #[arg(long, value_name = "SUBSTRING")]
    pub device: Option<String>,
}

/// Runs the report, writes the markdown file and prints it.
pub fn command(args: &GpuReportArgs) -> CliResult<()> {
    let settings = settings(args)?;
    // Refused before minutes of device time, not after.
    if args.out.is_dir() {
        return Err(CliError(format!(
            "--out {}: a folder; name the markdown file to write",
            args.out.display()
        )));
    }
    let backend = BackendArgs {
        backend: BackendKind::Vulkan,
        require_gpu: args.require_gpu,
        device: args.device.clone(),
    }
    .open()?;
    let report = gpu_report::run(&backend, &settings, &mut Bars::default())?;
    if let Some(dir) = args.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| CliError(format!("{}: {e}", dir.display())))?;
    }
    std::fs::write(&args.out, &report.markdown)
        .map_err(|e| CliError(format!("{}: {e}", args.out.display())))?;
    println!("{}", report.markdown);
    println!("written to {}", args.out.display());
    if !report.parity_failures.is_empty() {
        return Err(CliError(format!(
            "GPU parity failed for {}",
            report.parity_failures.join(", ")
        )));
    }
    Ok(())
}

/// The settings of `args`, with errors that name the flags.
fn settings(args: &GpuReportArgs) -> CliResult<Settings> {
    let sizes = args
        .sizes
        .iter()
        .map(|s| parse_size("--sizes", s))
        .collect::<CliResult<Vec<_>>>()?;
    if sizes.is_empty() {
        return Err(CliError("--sizes: no resolution given".into()));
    }
    limits::frames(command_line(), "--frames", args.frames)?;
    if args.frames < 2 {
        return Err(CliError(format!(
            "--frames {}: need at least 2 (frame 0 is left out of the statistics)",
            args.frames
        )));
    }
    limits::frames(command_line(), "--parity-frames", args.parity_frames)?;
    let (spp, batch) = (args.reference_spp, args.reference_batch_spp);
    if batch == 0 || spp < 2 * batch || !spp.is_multiple_of(batch) {
        return Err(CliError(format!(
            "--reference-spp {spp} must be a multiple ≥ 2× of --reference-batch-spp {batch}"
        )));
    }
    let compare = if args.no_compare {
        None
    } else {
        lab::limits::replicas(command_line(), "--compare-replicas", args.compare_replicas)?;
        limits::frames(command_line(), "--compare-frames", args.compare_frames)?;
        let stem = args
            .out
            .file_stem()
            .map_or("gpu-report".into(), |s| s.to_string_lossy().into_owned());
        Some(CompareSettings {
            size: parse_size("--compare-size", &args.compare_size)?,
            replicas: args.compare_replicas,
            frames: args.compare_frames,
            reference_spp: spp,
            reference_batch_spp: batch,
            cache: args.cache.clone(),
            out: args.out.with_file_name(format!("{stem}-compare")),
        })
    };
    Ok(Settings {
        scene: args.scene.clone(),
        sizes,
        frames: args.frames,
        parity_size: parse_size("--parity-size", &args.parity_size)?,
        parity_frames: args.parity_frames,
        compare,
    })
}
