//! The winit event loop: one window whose left part shows the displayed frame (scaled by
//! pixel replication, at the top-left corner) and whose right part is the control panel.
//! Each redraw runs this frame's scripted command and the queued input, renders the method
//! again if what selects its frame changed (else refines the reference while the camera rests),
//! draws egui into the swapchain and presents it. Ctrl-C (the `stop` flag), the window's close
//! button, `Q`/`Escape` and a script's `close` all end the loop the same way.

use std::sync::Arc;
use std::time::{Duration, Instant};

use egui::{Color32, ColorImage, TextureHandle, TextureOptions};
use engine::Preset;
use engine::image::tonemap;
use lab::draw::{false_colour, quantile};
use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow};
use winit::keyboard::Key;
use winit::window::{Window, WindowId};

use crate::Options;
use crate::camera::{Controls, Mode};
use crate::capture::Capture;
use crate::input::{Command, key_command};
use crate::panel::{PANEL_WIDTH, Panel, Status};
use crate::record::Recorder;
use crate::script::Script;
use crate::session::Session;
use crate::swapchain::{Presented, Presenter};

/// How often an idle loop wakes to look at the Ctrl-C flag.
const POLL: Duration = Duration::from_millis(50);

/// The quantile of the error that tops the false-colour scale (robust to fireflies, as the
/// lab's maps are).
const ERROR_SCALE_QUANTILE: f64 = 0.99;

/// The viewer before and after its window exists.
pub struct App {
    options: Options,
    stop: fn() -> bool,
    /// What the window needs, until it opens.
    pending: Option<(Session, Script, Option<Recorder>)>,
    live: Option<Live>,
    /// Why the viewer stopped, if it failed.
    pub error: Option<String>,
    /// Written when the loop ends.
    pub recorder: Option<Recorder>,
}

/// The open window and everything drawn in it.
struct Live {
    // Dropped before the window: its surface refers to it.
    presenter: Presenter,
    window: Arc<Window>,
    egui: egui_winit::State,
    texture: Option<TextureHandle>,
    session: Session,
    controls: Controls,
    panel: Panel,
    script: Script,
    /// Commands from keys and the panel, run at the next redraw.
    queued: Vec<Command>,
    error_view: bool,
    /// The last failure, shown in the panel.
    message: Option<String>,
    /// The left button is held: moves turn the camera.
    dragging: bool,
    cursor: Option<(f64, f64)>,
    /// The pose of the last redraw: the camera rests when it has not changed.
    last_pose: Option<crate::camera::Pose>,
    /// The displayed frame changed since it was last recorded.
    unrecorded: bool,
}

impl App {
    pub fn new(
        options: Options,
        session: Session,
        script: Script,
        recorder: Option<Recorder>,
        stop: fn() -> bool,
    ) -> App {
        App {
            options,
            stop,
            pending: Some((session, script, recorder)),
            live: None,
            error: None,
            recorder: None,
        }
    }

    /// Ends the loop with `error` (one line).
    fn fail(&mut self, event_loop: &ActiveEventLoop, error: String) {
        self.error.get_or_insert(error);
        event_loop.exit();
    }

    /// Opens the window and its presentation.
    fn open(&mut self, event_loop: &ActiveEventLoop) -> Result<(), String> {
        let Some((session, script, recorder)) = self.pending.take() else {
            return Ok(());
        };
        self.recorder = recorder;
        let controls = Controls::new(&self.options.camera);
        let (w, h) = (controls.camera().width(), controls.camera().height());
        let scale = self.options.scale;
        let size =
            winit::dpi::PhysicalSize::new(w * scale + PANEL_WIDTH as u32, (h * scale).max(480));
        let attributes = Window::default_attributes()
            .with_title(format!("reshift view: {}", session.scene_name()))
            .with_inner_size(size);
        let window = Arc::new(
            event_loop
                .create_window(attributes)
                .map_err(|e| format!("cannot open a window: {e}"))?,
        );
        let device = session.backend().device().map(|d| d.name);
        let presenter = Presenter::new(&window, device.as_deref())?;
        let context = egui::Context::default();
        let egui = egui_winit::State::new(
            context,
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            None,
        );
        self.live = Some(Live {
            presenter,
            window,
            egui,
            texture: None,
            panel: Panel::new(&session.method().name()),
            session,
            controls,
            script,
            queued: Vec::new(),
            error_view: false,
            message: None,
            dragging: false,
            cursor: None,
            last_pose: None,
            unrecorded: false,
        });
        Ok(())
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if let Err(e) = self.open(event_loop) {
            self.fail(event_loop, e);
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        let Some(live) = self.live.as_mut() else {
            return;
        };
        let consumed = live.egui.on_window_event(&live.window, &event).consumed;
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(_) => live.presenter.resized(),
            WindowEvent::RedrawRequested => {
                match live.redraw(self.options.scale, &mut self.recorder) {
                    Ok(true) => {}
                    Ok(false) => event_loop.exit(),
                    Err(e) => self.fail(event_loop, e),
                }
            }
            _ if consumed => {}
            WindowEvent::KeyboardInput { event, .. } if event.state == ElementState::Pressed => {
                let name = match &event.logical_key {
                    Key::Named(named) => format!("{named:?}"),
                    Key::Character(c) => c.to_string(),
                    _ => String::new(),
                };
                live.queued.extend(key_command(&name));
            }
            WindowEvent::MouseInput {
                state,
                button: MouseButton::Left,
                ..
            } => live.dragging = state == ElementState::Pressed,
            WindowEvent::CursorMoved { position, .. } => {
                if let (true, Some((x, y))) = (live.dragging, live.cursor) {
                    live.queued.push(Command::Turn(
                        (position.x - x) as f32,
                        (position.y - y) as f32,
                    ));
                }
                live.cursor = Some((position.x, position.y));
            }
            WindowEvent::MouseWheel { delta, .. } => {
                let lines = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => (p.y / 40.0) as f32,
                };
                live.queued.push(Command::Move(0.1 * lines, 0.0));
            }
            _ => {}
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        if (self.stop)() {
            event_loop.exit();
            return;
        }
        if let Some(live) = &self.live {
            if live.busy() {
                live.window.request_redraw();
            }
        }
        event_loop.set_control_flow(ControlFlow::WaitUntil(Instant::now() + POLL));
    }
}

impl Live {
    /// Whether a redraw has work: a script step, queued input, a frame to render, a reference
    /// to refine.
    fn busy(&self) -> bool {
        self.script.pending()
            || !self.queued.is_empty()
            || self.session.stale(self.controls.pose)
            || self.session.reference_spp(self.controls.pose) < self.session.reference_cap
    }

    /// Runs `command`; `false` to close. A screenshot is returned to be taken after drawing.
    fn run(&mut self, command: Command) -> (bool, Option<std::path::PathBuf>) {
        match command {
            Command::Turn(dx, dy) => self.controls.turn(dx, dy),
            Command::Move(forward, right) => {
                let d = self.controls.distance();
                self.controls.advance(forward * d, right * d);
            }
            Command::ToggleMode => {
                self.controls.mode = match self.controls.mode {
                    Mode::Orbit => Mode::Fly,
                    Mode::Fly => Mode::Orbit,
                }
            }
            Command::ToggleError => self.error_view = !self.error_view,
            Command::ToggleDenoise => self.session.denoise = !self.session.denoise,
            Command::Method(spec) => self.set_method(&spec),
            Command::NextPreset => {
                let names: Vec<String> = Preset::all().into_iter().map(|p| p.name).collect();
                let current = self.session.method().name();
                let at = current
                    .strip_prefix("restir:")
                    .and_then(|s| names.iter().position(|n| n == s));
                let next = at.map_or(0, |i| (i + 1) % names.len());
                self.set_method(&format!("restir:{}", names[next]));
            }
            Command::Screenshot(path) => return (true, Some(path)),
            Command::Close => return (false, None),
        }
        (true, None)
    }

    fn set_method(&mut self, spec: &str) {
        match self.session.set_method(spec) {
            Ok(()) => {
                self.panel.follow(spec);
                self.message = None;
            }
            Err(e) => self.message = Some(e),
        }
    }

    /// One displayed frame; `false` when a command closed the window.
    fn redraw(&mut self, scale: u32, recorder: &mut Option<Recorder>) -> Result<bool, String> {
        let mut commands: Vec<Command> = std::mem::take(&mut self.queued);
        commands.extend(self.script.next());
        let mut screenshot = None;
        for command in commands {
            let (open, shot) = self.run(command);
            if !open {
                return Ok(false);
            }
            screenshot = shot.or(screenshot);
        }
        self.update_frame()?;
        let (rgb, size) = self.displayed();
        if self.unrecorded {
            if let (Some(recorder), Some(frame)) = (recorder.as_mut(), self.session.frame()) {
                recorder.push(rgb.clone(), frame, &self.session.method().name());
            }
            self.unrecorded = false;
        }
        let image = ColorImage::from_rgb([size.0 as usize, size.1 as usize], &rgb);
        match &mut self.texture {
            Some(texture) => texture.set(image, TextureOptions::NEAREST),
            None => {
                let ctx = self.egui.egui_ctx().clone();
                self.texture = Some(ctx.load_texture("frame", image, TextureOptions::NEAREST));
            }
        }
        let input = self.egui.take_egui_input(&self.window);
        let ctx = self.egui.egui_ctx().clone();
        let mut commands = Vec::new();
        let status = Status {
            scene: self.session.scene_name(),
            backend: self.session.backend().to_string(),
            presenter: &self.presenter.device_name(),
            method: self.session.method().name(),
            frame: self.session.frame(),
            mse: self.session.mse(),
            reference_spp: self.session.reference_spp(self.controls.pose),
            mode: self.controls.mode.name(),
            error_view: self.error_view,
            denoise: self.session.denoise,
            message: self.message.as_deref(),
        };
        let texture = self.texture.as_ref().map(|t| t.id());
        let panel = &mut self.panel;
        let output = ctx.run_ui(input, |ui| {
            egui::Panel::right("panel")
                .exact_size(PANEL_WIDTH)
                .resizable(false)
                .show(ui, |ui| commands = panel.show(ui, &status));
            egui::CentralPanel::default()
                .frame(egui::Frame::NONE)
                .show(ui, |ui| {
                    if let Some(texture) = texture {
                        let origin = ui.max_rect().min;
                        let extent = egui::vec2((size.0 * scale) as f32, (size.1 * scale) as f32)
                            / ui.ctx().pixels_per_point();
                        let rect = egui::Rect::from_min_size(origin, extent);
                        let uv =
                            egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0));
                        ui.painter().image(texture, rect, uv, Color32::WHITE);
                    }
                });
        });
        self.queued.extend(commands);
        self.egui
            .handle_platform_output(&self.window, output.platform_output);
        let primitives = ctx.tessellate(output.shapes, output.pixels_per_point);
        let size = self.window.inner_size();
        let presented = self.presenter.draw(
            &output.textures_delta,
            &primitives,
            output.pixels_per_point,
            screenshot.is_some(),
            (size.width, size.height),
        )?;
        match (presented, screenshot) {
            (Presented::Shown(Some(capture)), Some(path)) => save(&capture, &path)?,
            // Not shown: run the screenshot again at the next redraw.
            (Presented::Skipped, Some(path)) => self.queued.push(Command::Screenshot(path)),
            _ => {}
        }
        Ok(true)
    }

    /// Renders the frame if what selects it changed; else, while the camera rests, refines the
    /// reference. A render failure keeps the previous frame and method and shows the reason;
    /// it ends the viewer only when there is no frame to show.
    fn update_frame(&mut self) -> Result<(), String> {
        let pose = self.controls.pose;
        if self.session.stale(pose) {
            match self
                .session
                .render(pose, self.controls.camera())
                .map(|_| ())
            {
                Ok(_) => {
                    self.message = None;
                    self.unrecorded = true;
                }
                // Nothing to show yet: the method cannot run here at all.
                Err(e) if self.session.frame().is_none() => return Err(e.to_string()),
                Err(e) => self.message = Some(e.to_string()),
            }
        } else if self.last_pose == Some(pose) {
            self.session.refine_reference(pose, self.controls.camera());
        }
        self.last_pose = Some(pose);
        Ok(())
    }

    /// The displayed frame as RGB bytes and its size: tonemapped, or in the error view the
    /// false-colour `|I − R|` (0 to its 99th percentile) once the reference has samples.
    fn displayed(&self) -> (Vec<u8>, (u32, u32)) {
        let Some(frame) = self.session.frame() else {
            let camera = self.controls.camera();
            let (w, h) = (camera.width(), camera.height());
            return (vec![0; 3 * (w * h) as usize], (w, h));
        };
        let size = (frame.image.width, frame.image.height);
        if self.error_view {
            if let Some(error) = self.session.error() {
                let max = quantile(&error, ERROR_SCALE_QUANTILE);
                return (
                    false_colour(&error, if max > 0.0 { max } else { 1.0 }),
                    size,
                );
            }
        }
        (
            frame
                .image
                .pixels
                .iter()
                .flat_map(|&p| tonemap(p))
                .collect(),
            size,
        )
    }
}

/// Writes `capture` to `path` as PNG (its folder created).
fn save(capture: &Capture, path: &std::path::Path) -> Result<(), String> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    }
    image::save_buffer(
        path,
        &capture.rgb,
        capture.width,
        capture.height,
        image::ColorType::Rgb8,
    )
    .map_err(|e| format!("{}: {e}", path.display()))
}
