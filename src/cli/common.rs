//! What every subcommand shares: the one-line error type, the backend and resolution
//! arguments, progress bars and the Ctrl-C flag (also as a `lab::progress::Progress`).

use std::fmt;
use std::path::Path;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::Duration;

use clap::{Args, ValueEnum};
use engine::Backend;
use indicatif::{ProgressBar, ProgressStyle};
use sss::InputError;
use sss::error::{MAX_MESSAGE_CHARS, one_line};
use sss::limits::{self, MAX_IMAGE_SIDE};
use sss::scene::FRAMES;

pub use lab::scenes::{LoadedScene, load_scene, with_resolution};

/// A failed command: printed as one line, `reshift: <message>`, with a non-zero exit status.
#[derive(Debug)]
pub struct CliError(pub String);

impl fmt::Display for CliError {
    /// One line of at most `sss::error::MAX_MESSAGE_CHARS` characters, elided in the middle.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&one_line(&self.0, MAX_MESSAGE_CHARS))
    }
}

macro_rules! from_error {
    ($($t:ty),*) => {$(
        impl From<$t> for CliError {
            fn from(e: $t) -> Self {
                CliError(e.to_string())
            }
        }
    )*};
}

from_error!(
    InputError,
    engine::PipelineError,
    methods::MethodError,
    lab::Error,
    engine::image::WriteError,
    engine::vulkan::VulkanError,
    restir::resample::ResampleError
);

pub type CliResult<T> = Result<T, CliError>;

/// `--backend`: where runs execute.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, ValueEnum)]
pub enum BackendKind {
    /// The deterministic CPU implementation.
    #[default]
    Cpu,
    /// A Vulkan device (a GPU, or Mesa's CPU device lavapipe).
    Vulkan,
}

/// The backend options every rendering subcommand takes.
#[derive(Args, Clone, Debug, Default)]
pub struct BackendArgs {
    /// Where to render.
    #[arg(long, value_enum, default_value_t = BackendKind::Cpu)]
    pub backend: BackendKind,
    /// With --backend vulkan: fail if the chosen device is a CPU implementation (lavapipe).
    #[arg(long)]
    pub require_gpu: bool,
    /// With --backend vulkan: the device whose name contains this text (as
    /// RESHIFT_VULKAN_DEVICE).
    #[arg(long, value_name = "SUBSTRING")]
    pub device: Option<String>,
}

impl BackendArgs {
    /// Opens the backend: a Vulkan error (no loader, no device, no SPIR-V in this build, a CPU
    /// device with --require-gpu) is one line; GPU options without `--backend vulkan` are an
    /// input error rather than ignored.
    pub fn open(&self) -> CliResult<Backend> {
        match self.backend {
            BackendKind::Cpu => {
                let stray = if self.require_gpu {
                    Some(("--require-gpu", "true".to_string()))
                } else {
                    self.device.clone().map(|d| ("--device", d))
                };
                match stray {
                    Some((field, value)) => Err(InputError::new(
                        COMMAND_LINE,
                        field,
                        value,
                        "only applies with --backend vulkan",
                    )
                    .into()),
                    None => Ok(Backend::Cpu),
                }
            }
            BackendKind::Vulkan => Ok(Backend::vulkan(self.device.as_deref(), self.require_gpu)?),
        }
    }
}

/// The command line as the "file" of flag errors.
pub const COMMAND_LINE: &str = "(command line)";

/// [`COMMAND_LINE`] as a path, for `sss::limits` checks of flags.
pub fn command_line() -> &'static Path {
    Path::new(COMMAND_LINE)
}

/// Parses `--resolution WxH` within `sss::limits` (sides, pixels).
pub fn parse_resolution(text: &str) -> CliResult<(u32, u32)> {
    parse_size("--resolution", text)
}

/// The scene `spec` (built-in name or file) at `--resolution` `resolution` (`None`: the
/// scene's own).
pub fn load_scene_at(spec: &str, resolution: Option<&str>) -> CliResult<LoadedScene> {
    let loaded = load_scene(spec)?;
    let resolution = resolution.map(parse_resolution).transpose()?;
    Ok(LoadedScene {
        scene: with_resolution(loaded.scene, resolution),
        ..loaded
    })
}

/// Parses the `WxH` of `flag` within `sss::limits` (sides, pixels).
pub fn parse_size(flag: &str, text: &str) -> CliResult<(u32, u32)> {
    let bad = |reason: &str| {
        CliError::from(InputError::new(
            COMMAND_LINE,
            flag,
            format!("{text:?}"),
            reason,
        ))
    };
    let (w, h) = text
        .split_once(['x', 'X', '×'])
        .ok_or_else(|| bad("expected WxH, e.g. 64x48"))?;
    let parse = |v: &str| {
        v.trim()
            .parse::<u32>()
            .ok()
            .filter(|&v| (1..=MAX_IMAGE_SIDE).contains(&v))
    };
    match (parse(w), parse(h)) {
        (Some(w), Some(h)) => {
            limits::resolution(command_line(), flag, w, h)?;
            Ok((w, h))
        }
        _ => Err(bad(&format!(
            "width and height must be integers in 1..={MAX_IMAGE_SIDE}"
        ))),
    }
}

/// Set by the first Ctrl-C: loops finish their current unit of work and write partial output.
static INTERRUPTED: AtomicBool = AtomicBool::new(false);
static PRESSES: AtomicUsize = AtomicUsize::new(0);

/// Installs the Ctrl-C handler: the first press asks loops to stop after the current frame or
/// replica, the second exits at once (status 130).
pub fn install_interrupt_handler() {
    // An error means a handler is already installed (only possible in tests); keep it.
    let _ = ctrlc::set_handler(|| {
        if PRESSES.fetch_add(1, Ordering::SeqCst) > 0 {
            std::process::exit(130);
        }
        INTERRUPTED.store(true, Ordering::SeqCst);
        eprintln!("\nreshift: interrupted; finishing the current step (Ctrl-C again to abort)");
    });
}

/// Whether Ctrl-C was pressed.
pub fn interrupted() -> bool {
    INTERRUPTED.load(Ordering::SeqCst)
}

/// A progress bar with ETA on stderr (drawn only on a terminal).
pub fn progress(len: u64, what: &str) -> ProgressBar {
    let bar = ProgressBar::new(len);
    bar.set_style(
        ProgressStyle::with_template(
            "{msg:24} [{bar:30}] {pos}/{len} {elapsed_precise} (ETA {eta})",
        )
        .expect("static template")
        .progress_chars("=> "),
    );
    bar.set_message(what.to_string());
    bar.enable_steady_tick(Duration::from_millis(250));
    bar
}

/// Progress bars on stderr and the Ctrl-C flag, for the lab's long jobs: one bar per phase.
#[derive(Default)]
pub struct Bars(Option<ProgressBar>);

impl lab::progress::Progress for Bars {
    fn begin(&mut self, what: &str, total: u64, done: u64) {
        let bar = progress(total, what);
        bar.set_position(done);
        self.0 = Some(bar);
    }

    fn item(&mut self, name: &str) {
        if let Some(bar) = &self.0 {
            bar.set_message(name.to_string());
        }
    }

    fn step(&mut self) {
        if let Some(bar) = &self.0 {
            bar.inc(1);
        }
    }

    fn end(&mut self) {
        if let Some(bar) = self.0.take() {
            bar.finish_and_clear();
        }
    }

    fn stop_requested(&self) -> bool {
        interrupted()
    }
}

/// `serde_json` number or `null` for a non-finite value.
pub fn json_number(v: f64) -> serde_json::Value {
    serde_json::Number::from_f64(v).map_or(serde_json::Value::Null, serde_json::Value::Number)
}

/// The scene of `--scene`, on the camera path of `--trajectory` if given, and the frames to
/// render: `--frames`, else the trajectory's poses, else the scene camera's [`FRAMES`]; checked
/// against the frame limit.
pub fn scene_and_frames(
    loaded: LoadedScene,
    trajectory: Option<&Path>,
    frames: Option<u32>,
) -> CliResult<(LoadedScene, u32)> {
    let (loaded, poses) = match trajectory {
        Some(path) => {
            let (loaded, poses) = loaded.on_trajectory(path)?;
            (loaded, Some(poses))
        }
        None => (loaded, None),
    };
    let frames = frames.or(poses).unwrap_or(FRAMES);
    limits::frames(command_line(), "--frames", frames)?;
    Ok((loaded, frames))
}
