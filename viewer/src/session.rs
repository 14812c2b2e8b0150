//! What the viewer renders: the scene, the method and its options, the last displayed frame,
//! and the progressive path-traced reference at the current pose that the error view and the
//! running MSE compare it with.
//!
//! A displayed frame is the engine's own rendering of the method, never a copy of it. A ReSTIR
//! method runs live: the session keeps its preset's [`Stream`] and renders each new pose as the
//! stream's next frame ([`Stream::frame_at`]), so temporal reuse follows the path the user
//! flies (the previous frame's reservoirs and G-buffer, reprojected), and the panel shows that
//! frame's per-pass times; the frames of a flight are those `compare --trajectory` renders on
//! the recorded poses with the same seed. A new method, seed or field of view starts a new
//! stream. Any other method, and a ReSTIR method with the denoiser, renders each pose as a
//! camera at rest there for `window` frames and shows the last one ([`Method::render_on`], the
//! call `render` and `compare` make; with the denoiser, [`Method::render_trajectory_on`] and
//! [`engine::denoise::denoise`] as in `compare --denoise`).

use engine::denoise::{Denoiser, Guide};
use engine::{Backend, Image, PipelineError, RunConfig, Stream};
use glam::DVec3;
use lab::metrics::{error_maps, tonemapped_mse};
use methods::Method;
use sss::integrator::pt;
use sss::scene::{GBuffer, Scene};

use crate::camera::Pose;

/// Path-traced samples per pixel the reference gains per displayed frame while the camera rests.
pub const REFERENCE_BATCH: u32 = 4;

/// The seed of the progressive reference: that of the lab's cached references, so that no
/// method replica (seeds 0, 1, …) shares its random streams.
const REFERENCE_SEED: u64 = lab::reference_cache::REFERENCE_SEED;

/// One displayed frame of the method and what it cost.
#[derive(Clone, Debug)]
pub struct Frame {
    /// Linear RGB of the last frame of the window (denoised when the denoiser is on).
    pub image: Image,
    /// The pose it was rendered at.
    pub pose: Pose,
    /// Seconds per rendered frame of each pass (`gbuffer`, the preset's passes, `shade`) on the
    /// backend's clock, for a ReSTIR method; otherwise one entry `frame` for the whole method.
    pub timings: Vec<(String, f64)>,
    /// Wall-clock seconds of the whole window (and the denoiser).
    pub wall_seconds: f64,
    /// Frames rendered for it: 1 for a live stream's frame, else the window.
    pub window: u32,
    /// Shaded values that were NaN or infinite.
    pub nonfinite: u64,
    /// A live stream's frame: its index in the stream and the mean confidence of its final
    /// reservoirs ([`engine::Frame::confidence`]), which grows while temporal reuse carries
    /// history along the flight.
    pub live: Option<Live>,
}

/// What a live stream's frame adds to a [`Frame`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Live {
    pub index: u32,
    pub confidence: f64,
}

/// What a live stream was started for: a change of any of these starts a new one.
#[derive(Clone, Debug, PartialEq)]
struct StreamKey {
    method: String,
    seed: u64,
    size: (u32, u32),
    tan_half_fov: f32,
}

/// What selects the displayed frame: it is rendered again when any of these changes.
#[derive(Clone, Debug, PartialEq)]
struct Key {
    pose: Pose,
    method: String,
    denoise: bool,
}

/// The progressive reference at one pose: the sum of the path tracer's sample means.
struct Reference {
    pose: Pose,
    sum: Vec<DVec3>,
    spp: u32,
}

/// The viewer's rendering state.
pub struct Session {
    backend: Backend,
    /// The scene; its camera is set to the pose's camera before every render.
    scene: Scene,
    method: Method,
    /// Frames rendered per displayed frame (the last one is shown).
    pub window: u32,
    pub seed: u64,
    /// Whether displayed frames are denoised (SVGF over the window, on the backend).
    pub denoise: bool,
    /// The most samples per pixel the reference accumulates at one pose.
    pub reference_cap: u32,
    frame: Option<(Key, Frame)>,
    reference: Option<Reference>,
    /// The ReSTIR method's live stream.
    stream: Option<(StreamKey, Stream<'static>)>,
}

impl Session {
    pub fn new(backend: Backend, scene: Scene, method: Method, window: u32, seed: u64) -> Session {
        Session {
            backend,
            scene,
            method,
            window,
            seed,
            denoise: false,
            reference_cap: 1024,
            frame: None,
            reference: None,
            stream: None,
        }
    }

    pub fn method(&self) -> &Method {
        &self.method
    }

    /// Switches to the method `spec` (`reshift methods`); an unknown one is refused with the
    /// parser's one-line reason and the current method kept.
    pub fn set_method(&mut self, spec: &str) -> Result<(), String> {
        self.method = Method::parse(spec).map_err(|e| e.to_string())?;
        Ok(())
    }

    pub fn backend(&self) -> &Backend {
        &self.backend
    }

    pub fn scene_name(&self) -> &str {
        &self.scene.name
    }

    /// The last displayed frame.
    pub fn frame(&self) -> Option<&Frame> {
        self.frame.as_ref().map(|(_, f)| f)
    }

    fn key(&self, pose: Pose) -> Key {
        Key {
            pose,
            method: self.method.name(),
            denoise: self.denoise,
        }
    }

    /// Whether the displayed frame is not that of `pose` with the current method and options.
    pub fn stale(&self, pose: Pose) -> bool {
        self.frame
            .as_ref()
            .is_none_or(|(k, _)| *k != self.key(pose))
    }

    /// Renders the displayed frame at `pose` with `camera` (at rest there). On failure (a
    /// method the backend has no kernel for, …) the method and denoiser of the last displayed
    /// frame are restored, so the next frame renders what rendered before.
    pub fn render(
        &mut self,
        pose: Pose,
        camera: sss::scene::Camera,
    ) -> Result<&Frame, PipelineError> {
        let rendered = self.render_at(pose, camera);
        if rendered.is_err() {
            if let Some((key, _)) = &self.frame {
                self.denoise = key.denoise;
                self.method =
                    Method::parse(&key.method).map_err(|e| PipelineError::Config(e.to_string()))?;
            }
        }
        rendered?;
        Ok(self.frame().expect("just rendered"))
    }

    fn render_at(&mut self, pose: Pose, camera: sss::scene::Camera) -> Result<(), PipelineError> {
        self.scene.camera = camera;
        let started = std::time::Instant::now();
        let (image, timings, nonfinite, live) = match self.live_preset()? {
            Some(preset) => self.render_live(&preset)?,
            None => self.render_at_rest()?,
        };
        let frame = Frame {
            image,
            pose,
            timings,
            wall_seconds: started.elapsed().as_secs_f64(),
            window: if live.is_some() { 1 } else { self.window },
            nonfinite,
            live,
        };
        self.frame = Some((self.key(pose), frame));
        Ok(())
    }

    /// The preset of a ReSTIR method without the denoiser: the methods that run live.
    fn live_preset(&mut self) -> Result<Option<engine::Preset>, PipelineError> {
        let name = self.method.name();
        let Some(spec) = name.strip_prefix("restir:").filter(|_| !self.denoise) else {
            self.stream = None;
            return Ok(None);
        };
        let preset = methods::restir::preset(Some(spec)).map_err(PipelineError::Config)?;
        Ok(Some(preset))
    }

    /// The next frame of the live stream of `preset` at the scene camera's pose, starting the
    /// stream when there is none for the method, seed and camera.
    #[allow(clippy::type_complexity)]
    fn render_live(
        &mut self,
        preset: &engine::Preset,
    ) -> Result<(Image, Vec<(String, f64)>, u64, Option<Live>), PipelineError> {
        let camera = &self.scene.camera;
        let key = StreamKey {
            method: self.method.name(),
            seed: self.seed,
            size: (camera.width(), camera.height()),
            tan_half_fov: camera.tan_half_fov(),
        };
        let pose = camera.pose(0);
        if self.stream.as_ref().is_none_or(|(k, _)| *k != key) {
            self.stream = None;
            let config = RunConfig {
                seed: self.seed,
                frames: 1,
                collect_diagnostics: false,
            };
            let stream = Stream::live(&self.backend, self.scene.clone(), preset, &config)?;
            self.stream = Some((key, stream));
        }
        let (_, stream) = self.stream.as_mut().expect("just started");
        let frame = stream.frame_at(pose)?;
        let timings = (stream.labels().iter().zip(&frame.steps))
            .map(|(label, t)| (label.clone(), t.seconds))
            .collect();
        let live = Live {
            index: frame.index,
            confidence: frame.confidence,
        };
        Ok((frame.image, timings, frame.nan_count, Some(live)))
    }

    /// The last frame of `window` frames at rest at the scene camera's pose (denoised when
    /// the denoiser is on).
    #[allow(clippy::type_complexity)]
    fn render_at_rest(
        &self,
    ) -> Result<(Image, Vec<(String, f64)>, u64, Option<Live>), PipelineError> {
        let (frames, timings, nonfinite) = self.render_window()?;
        let image = if self.denoise {
            let guides = Guide::trajectory(&self.scene, self.window);
            engine::denoise::denoise(Denoiser::Svgf, &self.backend, &guides, &frames)
                .map_err(|e| PipelineError::Config(e.to_string()))?
                .image
        } else {
            frames
                .into_iter()
                .last()
                .ok_or_else(|| PipelineError::Config("the method returned no frame".into()))?
        };
        Ok((image, timings, nonfinite, None))
    }

    /// The window's frames (only the last unless the denoiser needs them all), the timings of
    /// [`Frame::timings`] and the non-finite count.
    #[allow(clippy::type_complexity)]
    fn render_window(&self) -> Result<(Vec<Image>, Vec<(String, f64)>, u64), PipelineError> {
        let scene = &self.scene;
        let name = self.method.name();
        if let Some(spec) = name.strip_prefix("restir:") {
            let preset = methods::restir::preset(Some(spec)).map_err(PipelineError::Config)?;
            let config = RunConfig {
                seed: self.seed,
                frames: self.window,
                collect_diagnostics: false,
            };
            let run = self.backend.run(scene, &preset, &config)?;
            let frames = self.window.max(1) as f64;
            let timings = run
                .timings
                .iter()
                .map(|t| (t.label.clone(), t.seconds / frames))
                .collect();
            return Ok((run.frames, timings, run.nan_count));
        }
        if self.denoise {
            let (trajectory, timing) =
                self.method
                    .render_trajectory_on(&self.backend, scene, self.window, self.seed)?;
            let timings = vec![("frame".to_string(), timing.seconds)];
            return Ok((trajectory.frames, timings, trajectory.nonfinite));
        }
        let rendered = self
            .method
            .render_on(&self.backend, scene, self.window, self.seed)?;
        let timings = vec![("frame".to_string(), rendered.seconds_per_frame)];
        Ok((vec![rendered.image], timings, rendered.nonfinite))
    }

    /// Adds [`REFERENCE_BATCH`] path-traced samples per pixel to the reference at `pose` (a new
    /// pose starts it again), up to [`Session::reference_cap`]. The reference renders the frame
    /// the method shows (frame `window − 1`, its jitter) with the path tracer of the method's own
    /// transport model ([`Method::reference`]), on the CPU, deterministically. `false` when the
    /// cap is reached and nothing was added.
    pub fn refine_reference(&mut self, pose: Pose, camera: sss::scene::Camera) -> bool {
        if self.reference.as_ref().is_none_or(|r| r.pose != pose) {
            self.reference = None;
        }
        let spp = self.reference.as_ref().map_or(0, |r| r.spp);
        if spp >= self.reference_cap {
            return false;
        }
        self.scene.camera = camera;
        let scene = self.scene.at_frame(self.window - 1);
        let gbuffer = GBuffer::render(&scene, self.window - 1);
        let settings = self.method.reference();
        let means = pt::render(
            &scene,
            &gbuffer,
            &settings,
            REFERENCE_SEED,
            spp,
            REFERENCE_BATCH,
        );
        let reference = self.reference.get_or_insert_with(|| Reference {
            pose,
            sum: vec![DVec3::ZERO; means.pixels.len()],
            spp: 0,
        });
        for (s, m) in reference.sum.iter_mut().zip(&means.pixels) {
            *s += *m * REFERENCE_BATCH as f64;
        }
        reference.spp += REFERENCE_BATCH;
        true
    }

    /// Samples per pixel of the reference at `pose` (0: none yet).
    pub fn reference_spp(&self, pose: Pose) -> u32 {
        self.reference
            .as_ref()
            .filter(|r| r.pose == pose)
            .map_or(0, |r| r.spp)
    }

    /// The reference's per-pixel mean at the displayed frame's pose, if it has samples.
    fn reference_mean(&self) -> Option<Vec<DVec3>> {
        let (_, frame) = self.frame.as_ref()?;
        let r = self.reference.as_ref().filter(|r| r.pose == frame.pose)?;
        (r.spp > 0).then(|| r.sum.iter().map(|s| *s / r.spp as f64).collect())
    }

    /// Paper 001's tonemapped MSE of the displayed frame against the reference so far
    /// ([`tonemapped_mse`]). The reference's own noise adds to it, shrinking as its samples
    /// grow, so it is an upper estimate that settles while the camera rests.
    pub fn mse(&self) -> Option<f64> {
        let (_, frame) = self.frame.as_ref()?;
        tonemapped_mse(&frame.image, &self.reference_mean()?)
    }

    /// Per-pixel luminance of `|I − R|` of the displayed frame against the reference so far
    /// (`compare`'s absolute error map), if the reference has samples.
    pub fn error(&self) -> Option<Vec<f64>> {
        let (_, frame) = self.frame.as_ref()?;
        error_maps(&frame.image, &self.reference_mean()?).map(|(absolute, _)| absolute)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Controls;

    fn session(method: &str) -> (Session, Controls) {
        let mut scene = Scene::builtin("bumpy").expect("built-in scene");
        scene.camera = scene.camera.with_resolution(8, 6);
        let controls = Controls::new(&scene.camera);
        let method = Method::parse(method).unwrap();
        (Session::new(Backend::Cpu, scene, method, 2, 0), controls)
    }

    #[test]
    fn a_frame_is_rendered_again_only_when_what_selects_it_changes() {
        let (mut s, mut c) = session("pt");
        assert!(s.stale(c.pose));
        let image = s.render(c.pose, c.camera()).unwrap().image.clone();
        assert!(!s.stale(c.pose));
        assert!(image.pixels.iter().any(|p| p.max_element() > 0.0));
        // The same call is the same image: the method, not the viewer, decides it.
        let expected = Method::parse("pt")
            .unwrap()
            .render(&s.scene, 2, 0)
            .unwrap()
            .image;
        assert_eq!(image.pixels, expected.pixels);
        s.set_method("restir:hybrid").unwrap();
        assert!(s.stale(c.pose));
        let frame = s.render(c.pose, c.camera()).unwrap();
        let labels: Vec<&str> = frame.timings.iter().map(|(l, _)| l.as_str()).collect();
        assert!(labels.contains(&"shade") && labels.len() > 2, "{labels:?}");
        c.turn(10.0, 0.0);
        assert!(s.stale(c.pose));
        assert!(s.set_method("nope").is_err());
        assert_eq!(s.method().name(), "restir:hybrid");
        // A render that fails restores the method of the displayed frame.
        s.set_method("pt:0").unwrap_err();
        s.window = 0;
        s.set_method("pt:2").unwrap();
        assert!(s.render(c.pose, c.camera()).is_err());
        assert_eq!(s.method().name(), "restir:hybrid");
    }

    /// A ReSTIR method runs live: the frames of a flight are one stream's, its history carried
    /// (the live frames' mean confidence grows past the first frame's), and the recording's
    /// trajectory replayed as `compare --trajectory` replays it, with the same method and seed,
    /// renders the same frames bit for bit.
    #[test]
    fn a_recorded_flight_replays_bit_for_bit() {
        let (mut s, mut c) = session("restir:hybrid");
        s.seed = 3;
        let dir = std::env::temp_dir().join(format!("reshift-flight-{}", std::process::id()));
        let (width, height) = (8, 6);
        let mut recorder =
            crate::record::Recorder::new(&dir, (width, height), c.vfov_degrees(), c.up()).unwrap();
        let mut shown = Vec::new();
        for step in 0..5 {
            if step > 0 {
                c.turn(12.0, 3.0);
            }
            let frame = s.render(c.pose, c.camera()).unwrap().clone();
            let rgb = vec![0; 3 * (width * height) as usize];
            recorder.push(rgb, &frame, &s.method().name());
            shown.push(frame);
        }
        let live: Vec<Live> = shown.iter().map(|f| f.live.unwrap()).collect();
        assert_eq!(
            live.iter().map(|l| l.index).collect::<Vec<_>>(),
            [0, 1, 2, 3, 4]
        );
        assert!(live[4].confidence > live[0].confidence, "{live:?}");
        let written = recorder.finish().unwrap();
        let loaded = lab::scenes::LoadedScene {
            scene: s.scene.clone(),
            key: "bumpy".into(),
        };
        let (replay, frames) = loaded.on_trajectory(&written[1]).unwrap();
        let (trajectory, _) = Method::parse("restir:hybrid")
            .unwrap()
            .render_trajectory_on(&Backend::Cpu, &replay.scene, frames, 3)
            .unwrap();
        assert_eq!(trajectory.frames.len(), shown.len());
        for (f, (replayed, frame)) in trajectory.frames.iter().zip(&shown).enumerate() {
            assert_eq!(replayed.bits(), frame.image.bits(), "frame {f}");
        }
        // Control: the last pose rendered at rest for as many frames (the same frame index,
        // jitter and seed; only the history differs) is not the flight's last frame.
        let at_rest = Method::parse("restir:hybrid")
            .unwrap()
            .render_on(&Backend::Cpu, &s.scene, 5, 3)
            .unwrap();
        assert_ne!(at_rest.image.bits(), shown[4].image.bits(), "control");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn the_reference_restarts_at_a_new_pose_and_stops_at_its_cap() {
        let (mut s, mut c) = session("pt:4");
        s.reference_cap = 2 * REFERENCE_BATCH;
        s.render(c.pose, c.camera()).unwrap();
        assert_eq!(s.mse(), None);
        assert!(s.refine_reference(c.pose, c.camera()));
        let first = s.mse().expect("a reference");
        assert!(first.is_finite() && first > 0.0);
        assert_eq!(s.error().unwrap().len(), 8 * 6);
        assert!(s.refine_reference(c.pose, c.camera()));
        assert!(!s.refine_reference(c.pose, c.camera()));
        assert_eq!(s.reference_spp(c.pose), 2 * REFERENCE_BATCH);
        c.turn(5.0, 5.0);
        assert_eq!(s.reference_spp(c.pose), 0);
        assert!(s.refine_reference(c.pose, c.camera()));
        assert_eq!(s.reference_spp(c.pose), REFERENCE_BATCH);
        // The displayed frame is of the old pose: no error against another pose's reference.
        assert_eq!(s.mse(), None);
    }

    #[test]
    fn the_denoiser_filters_the_window() {
        let (mut s, c) = session("pt");
        let noisy = s.render(c.pose, c.camera()).unwrap().image.clone();
        s.denoise = true;
        assert!(s.stale(c.pose));
        let denoised = s.render(c.pose, c.camera()).unwrap().image.clone();
        assert_eq!(denoised.pixels.len(), noisy.pixels.len());
        assert_ne!(denoised.pixels, noisy.pixels);
    }
}
