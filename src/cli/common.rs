//! What every subcommand shares: the one-line error type, scene and resolution arguments,
//! output folders, progress bars and the Ctrl-C flag.

use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::Duration;

use clap::{Args, ValueEnum};
use engine::Backend;
use indicatif::{ProgressBar, ProgressStyle};
use lab::compare::fnv1a;
use sss::InputError;
use sss::scene::Scene;

/// A failed command: printed as one line, `reshift: <message>`, with a non-zero exit status.
#[derive(Debug)]
pub struct CliError(pub String);

impl fmt::Display for CliError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // One line: messages from lower layers may carry newlines (e.g. TOML parse errors).
        f.write_str(&self.0.split_whitespace().collect::<Vec<_>>().join(" "))
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
    lab::methods::MethodError,
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
                        "(command line)",
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

/// A scene as named on the command line, with its cache key.
pub struct LoadedScene {
    pub scene: Scene,
    /// The built-in name, or `file-<stem>-<FNV-1a of the text>` for a scene file.
    pub key: String,
}

/// `--scene`: a built-in name, or a path to a scene file (anything with a `/` or ending in
/// `.toml`). Unknown names list the built-ins.
pub fn load_scene(spec: &str) -> CliResult<LoadedScene> {
    if let Some(scene) = Scene::builtin(spec) {
        return Ok(LoadedScene {
            scene,
            key: spec.to_string(),
        });
    }
    let path = Path::new(spec);
    if spec.ends_with(".toml") || spec.contains('/') || path.exists() {
        let text = std::fs::read(path)
            .map_err(|e| InputError::new(path, "(file)", format!("{spec:?}"), e.to_string()))?;
        let scene = Scene::load(path)?;
        let key = format!("file-{}-{:016x}", scene.name, fnv1a(&text));
        return Ok(LoadedScene { scene, key });
    }
    let names: Vec<&str> = Scene::BUILTIN.iter().map(|(n, _)| *n).collect();
    Err(InputError::new(
        "(command line)",
        "--scene",
        format!("{spec:?}"),
        format!(
            "unknown scene; built-in: {} (or a path to a .toml file)",
            names.join(", ")
        ),
    )
    .into())
}

/// Parses `WxH` (both ≥ 1 and at most 16384).
pub fn parse_resolution(text: &str) -> CliResult<(u32, u32)> {
    let bad = |reason: &str| {
        CliError::from(InputError::new(
            "(command line)",
            "--resolution",
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
            .filter(|&v| (1..=16384).contains(&v))
    };
    match (parse(w), parse(h)) {
        (Some(w), Some(h)) => Ok((w, h)),
        _ => Err(bad("width and height must be integers in 1..=16384")),
    }
}

/// The scene with the camera at `resolution` (`None`: the scene file's own).
pub fn with_resolution(scene: Scene, resolution: Option<(u32, u32)>) -> Scene {
    match resolution {
        Some((w, h)) => Scene {
            camera: scene.camera.with_resolution(w, h),
            ..scene
        },
        None => scene,
    }
}

/// Creates `dir` (and parents) and checks that a file can be written in it.
pub fn output_dir(dir: &Path) -> CliResult<PathBuf> {
    let fail = |e: std::io::Error| CliError(format!("output folder {}: {e}", dir.display()));
    std::fs::create_dir_all(dir).map_err(fail)?;
    let probe = dir.join(".reshift-write-test");
    std::fs::write(&probe, b"").map_err(fail)?;
    std::fs::remove_file(&probe).map_err(fail)?;
    Ok(dir.to_path_buf())
}

/// Writes `text` to `path`, naming the file in the error.
pub fn write_file(path: &Path, text: &str) -> CliResult<()> {
    std::fs::write(path, text).map_err(|e| CliError(format!("{}: {e}", path.display())))
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

/// A file-name-safe form of a method name (`restir:hybrid` → `restir-hybrid`).
pub fn file_stem(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '.' {
                c
            } else {
                '-'
            }
        })
        .collect()
}

/// `serde_json` number or `null` for a non-finite value.
pub fn json_number(v: f64) -> serde_json::Value {
    serde_json::Number::from_f64(v).map_or(serde_json::Value::Null, serde_json::Value::Number)
}

/// [`json_number`] of an optional value.
pub fn json_opt(v: Option<f64>) -> serde_json::Value {
    v.map_or(serde_json::Value::Null, json_number)
}
