//! `reshift view`: the interactive window (the `viewer` crate) on the Vulkan backend, on one
//! scene with one method to start with; `--script` drives it, `--record` writes what was seen
//! and the camera path.

use std::path::PathBuf;

use clap::Args;
use methods::Method;
use sss::limits;

use super::common::{CliError, CliResult, command_line, interrupted, load_scene_at};

#[derive(Args, Clone, Debug)]
pub struct ViewArgs {
    /// Built-in scene name or path to a scene .toml.
    #[arg(long, default_value = "bumpy")]
    pub scene: String,
    /// The method to start with, e.g. pt:4 or restir:hybrid (see `reshift methods`).
    #[arg(long, default_value = "restir:hybrid")]
    pub method: String,
    /// Image size WxH [default: the scene's].
    #[arg(long)]
    pub resolution: Option<String>,
    /// Frames rendered per displayed frame, the camera at rest at the pose (temporal reuse
    /// over them); the last is shown.
    #[arg(long, default_value_t = 4)]
    pub window: u32,
    /// Replica seed.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Screen pixels per rendered pixel [default: the image about 512 pixels wide].
    #[arg(long)]
    pub scale: Option<u32>,
    /// Scripted input: one action a line (wait, key, preset, method, orbit, move, screenshot,
    /// close; docs/viewer.md).
    #[arg(long, value_name = "FILE")]
    pub script: Option<PathBuf>,
    /// Write the displayed frames (DIR/view.png, animated) and the camera path
    /// (DIR/trajectory.toml, for `compare --trajectory`) when the window closes.
    #[arg(long, value_name = "DIR")]
    pub record: Option<PathBuf>,
    /// Fail if the chosen device is a CPU implementation (lavapipe).
    #[arg(long)]
    pub require_gpu: bool,
    /// The Vulkan device whose name contains this text (as RESHIFT_VULKAN_DEVICE).
    #[arg(long, value_name = "SUBSTRING")]
    pub device: Option<String>,
}

/// The most screen pixels per rendered pixel.
const MAX_SCALE: u32 = 16;

pub fn command(args: &ViewArgs) -> CliResult<()> {
    limits::frames(command_line(), "--window", args.window)?;
    let method = Method::parse(&args.method)?;
    let scene = load_scene_at(&args.scene, args.resolution.as_deref())?.scene;
    let scale = match args.scale {
        Some(s) if (1..=MAX_SCALE).contains(&s) => s,
        Some(s) => {
            return Err(CliError(format!(
                "{}: --scale {s}: expected 1..={MAX_SCALE}",
                super::common::COMMAND_LINE
            )));
        }
        None => (512 / scene.camera.width()).clamp(1, MAX_SCALE),
    };
    viewer::check_display().map_err(CliError)?;
    let backend = engine::Backend::vulkan(args.device.as_deref(), args.require_gpu)?;
    let options = viewer::Options {
        camera: scene.camera.clone(),
        window: args.window,
        seed: args.seed,
        scale,
        script: args.script.clone(),
        record: args.record.clone(),
    };
    let written = viewer::run(scene, method, backend, options, interrupted).map_err(CliError)?;
    for path in written {
        println!("{}", path.display());
    }
    Ok(())
}
