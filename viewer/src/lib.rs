//! `viewer`: `reshift view`, an interactive window on the Vulkan backend (docs/viewer.md).
//!
//! The window (`window`: winit) shows the frame the engine renders for the current method at
//! the current camera pose (`session`; `camera`: orbit and fly controls), with an egui control
//! panel (`panel`) drawn through `egui-ash-renderer` into a swapchain (`swapchain`). Keys, the
//! panel and scripts (`script`) give the same commands (`input`); `--record` writes what was
//! seen and the camera path (`record`). The viewer drives the engine as `render` and `compare`
//! do; it has no renderer of its own.

mod camera;
mod capture;
mod input;
mod panel;
mod record;
mod script;
mod session;
mod swapchain;
mod window;

use std::path::PathBuf;

use engine::Backend;
use methods::Method;
use sss::scene::{Camera, Scene};

/// A Vulkan failure of the window's presentation (`swapchain`, `capture`), as one line.
fn vulkan_failure(what: &'static str) -> impl Fn(ash::vk::Result) -> String {
    move |e| format!("window presentation: {what}: {e}")
}

/// What `reshift view` was asked for.
pub struct Options {
    /// The scene camera (resolution set); the viewer starts at its trajectory's end pose.
    pub camera: Camera,
    /// Frames rendered per displayed frame (the camera at rest at the pose; the last is shown).
    pub window: u32,
    pub seed: u64,
    /// Screen pixels per rendered pixel.
    pub scale: u32,
    /// Scripted input, run one step per displayed frame.
    pub script: Option<PathBuf>,
    /// Where `view.png` and `trajectory.toml` go.
    pub record: Option<PathBuf>,
}

/// Whether this process names a display to open a window on: `DISPLAY` set and non-empty (a
/// Wayland session provides it through XWayland). One line saying what to do when not; call it
/// before opening the Vulkan device, so a headless machine hears about the display first.
pub fn check_display() -> Result<(), String> {
    match std::env::var_os("DISPLAY") {
        Some(display) if !display.is_empty() => Ok(()),
        _ => Err(
            "no display: DISPLAY is not set (run it in a desktop session, or under Xvfb: xvfb-run reshift view …)"
                .into(),
        ),
    }
}

/// Opens the window on `scene` with `method` rendered on `backend` (a Vulkan backend) and runs
/// until the window closes or `stop()` (Ctrl-C); then writes the recording. Every failure is
/// one line: no display, a display that cannot be opened, no presentable Vulkan device, a bad
/// script or record folder.
pub fn run(
    scene: Scene,
    method: Method,
    backend: Backend,
    options: Options,
    stop: fn() -> bool,
) -> Result<Vec<PathBuf>, String> {
    check_display()?;
    if backend.device().is_none() {
        return Err("reshift view renders on the Vulkan backend; no Vulkan device is open".into());
    }
    let script = match &options.script {
        Some(path) => script::Script::load(path)?,
        None => script::Script::default(),
    };
    let controls = camera::Controls::new(&options.camera);
    let recorder = match &options.record {
        Some(dir) => Some(record::Recorder::new(
            dir,
            (options.camera.width(), options.camera.height()),
            controls.vfov_degrees(),
            controls.up(),
        )?),
        None => None,
    };
    let event_loop = winit::event_loop::EventLoop::new().map_err(|e| {
        let display = std::env::var("DISPLAY").unwrap_or_default();
        format!("cannot open the display {display:?}: {e}")
    })?;
    let session = session::Session::new(
        backend,
        Scene {
            camera: options.camera.clone(),
            ..scene
        },
        method,
        options.window,
        options.seed,
    );
    let mut app = window::App::new(options, session, script, recorder, stop);
    event_loop
        .run_app(&mut app)
        .map_err(|e| format!("window event loop: {e}"))?;
    if let Some(error) = app.error.take() {
        return Err(error);
    }
    match app.recorder.take() {
        Some(recorder) => recorder.finish(),
        None => Ok(Vec::new()),
    }
}
