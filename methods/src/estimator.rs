//! The [`Estimator`] trait a method implements, the [`Method`] handle that shares one, and the
//! [`Entry`] that registers a family of methods by name.

use std::cell::Cell;
use std::fmt;
use std::path::Path;
use std::sync::Arc;

use engine::clock::{Stopwatch, Timing};
use engine::image::Image;
use engine::{Backend, PassTiming, PipelineError};
use sss::integrator::pt::PtSettings;
use sss::limits::{self, MAX_SPP};
use sss::scene::Scene;

/// One family of methods: `family[:argument]`.
pub struct Entry {
    pub family: &'static str,
    /// How to write it, e.g. `pt[:spp]`.
    pub usage: &'static str,
    pub about: &'static str,
    /// Builds the method from the text after `family:` (`None` without a colon).
    pub build: fn(Option<&str>) -> Result<Method, String>,
}

/// What a method implements: one estimator of the final frame of a camera trajectory.
pub trait Estimator: fmt::Debug + Send + Sync + 'static {
    /// The canonical name, which [`Method::parse`] reads back (`pt:4`, `restir:hybrid`).
    fn name(&self) -> String;

    /// Samples per pixel per frame.
    fn spp(&self) -> u32;

    /// The same estimator at `spp` samples per pixel, or `None` when its per-frame cost is
    /// fixed (ReSTIR presets).
    fn with_spp(&self, spp: u32) -> Option<Method>;

    /// Renders replica `seed` of `frames ≥ 1` frames of `scene`'s trajectory on `backend` and
    /// returns frame `frames − 1` (the resolution is the camera's). A memoryless estimator
    /// renders only that frame.
    fn render(
        &self,
        backend: &Backend,
        scene: &Scene,
        frames: u32,
        seed: u64,
    ) -> Result<LastFrame, PipelineError>;

    /// [`Estimator::render`] with the per-pixel sample counts of the returned frame, for a
    /// method that chooses them itself (adaptive sampling). The default is `render` and `None`:
    /// every pixel with a primary hit takes [`Estimator::spp`] samples.
    fn render_counted(
        &self,
        backend: &Backend,
        scene: &Scene,
        frames: u32,
        seed: u64,
    ) -> Result<(LastFrame, Option<SampleCounts>), PipelineError> {
        Ok((self.render(backend, scene, frames, seed)?, None))
    }

    /// [`Estimator::render_counted`] that may end early: a method that streams its frames
    /// (`restir:<preset>`) asks `stop` before each frame after the first and, once it says yes,
    /// returns the last frame it finished ([`LastFrame::frames_rendered`] counts them). A method
    /// that sees `stop` say yes returns at once; one that is not streamed (the default:
    /// `render_counted`) and `restir:<preset>/channels=rgb` (three streams in turn) ignore it.
    fn render_until(
        &self,
        backend: &Backend,
        scene: &Scene,
        frames: u32,
        seed: u64,
        stop: &dyn Fn() -> bool,
    ) -> Result<(LastFrame, Option<SampleCounts>), PipelineError> {
        let _ = stop;
        self.render_counted(backend, scene, frames, seed)
    }

    /// Whether it renders scenes whose objects move (`sss::scene::motion`) on the CPU, each
    /// frame in the scene posed there; [`Method`] refuses a moving scene otherwise.
    fn renders_motion(&self) -> bool {
        false
    }

    /// The path-tracer settings whose converged image this method estimates, i.e. its
    /// reference in `bias` (DESIGN §7): the default path tracer (Burley BSSRDF) unless the
    /// method renders another transport model (`image-space`: the dipole profile).
    fn reference(&self) -> PtSettings {
        PtSettings::default()
    }

    /// Renders replica `seed` like [`Estimator::render`] and returns every frame `0..frames`,
    /// with the sample counts of the last (as [`Estimator::render_counted`]). The default
    /// renders each frame `f` on its own (`render_counted` of `f + 1` frames): right and cheap
    /// for a memoryless estimator. An estimator with memory across frames overrides it with
    /// one run of the trajectory.
    fn render_trajectory(
        &self,
        backend: &Backend,
        scene: &Scene,
        frames: u32,
        seed: u64,
    ) -> Result<Trajectory, PipelineError> {
        memoryless_trajectory(self, backend, scene, frames, seed)
    }
}

/// The default [`Estimator::render_trajectory`]: each frame `f` rendered on its own
/// (`render_counted` of `f + 1` frames).
pub fn memoryless_trajectory<E: Estimator + ?Sized>(
    estimator: &E,
    backend: &Backend,
    scene: &Scene,
    frames: u32,
    seed: u64,
) -> Result<Trajectory, PipelineError> {
    let mut trajectory = Trajectory {
        frames: Vec::with_capacity(frames as usize),
        frames_rendered: 0,
        nonfinite: 0,
        counts: None,
        passes: Vec::new(),
    };
    for f in 1..=frames {
        let (frame, counts) = estimator.render_counted(backend, scene, f, seed)?;
        trajectory.frames.push(frame.image);
        trajectory.frames_rendered += frame.frames_rendered;
        trajectory.nonfinite += frame.nonfinite;
        trajectory.counts = counts;
    }
    Ok(trajectory)
}

/// The samples each pixel of a frame took, for a method that chooses them per pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct SampleCounts {
    pub width: u32,
    pub height: u32,
    /// Samples per pixel, row-major from the top row (0 without a primary hit).
    pub counts: Vec<u32>,
    /// The most samples a pixel may take (the top of the count map's scale).
    pub max: u32,
}

impl SampleCounts {
    /// The mean count over `pixels` (indices into `counts`); 0 for none.
    pub fn mean_over(&self, pixels: &[usize]) -> f64 {
        let sum: u64 = pixels.iter().map(|&p| self.counts[p] as u64).sum();
        sum as f64 / pixels.len().max(1) as f64
    }

    /// The mean count over the pixels with a primary hit (those with a count > 0).
    pub fn mean(&self) -> f64 {
        let hit: Vec<usize> = (0..self.counts.len())
            .filter(|&p| self.counts[p] > 0)
            .collect();
        self.mean_over(&hit)
    }
}

/// The output of [`Estimator::render`].
#[derive(Clone, Debug)]
pub struct LastFrame {
    /// Linear RGB of frame `frames − 1`.
    pub image: Image,
    /// Frames rendered to produce `image` (1 for memoryless estimators).
    pub frames_rendered: u32,
    /// Shaded values that were NaN or infinite (written as 0 or left out of the mean).
    pub nonfinite: u64,
    /// Time of each pass of the frame pipeline over the rendered frames, in execution order
    /// (`gbuffer`, `candidates`, `temporal:…`, `spatial<n>:…`, `shade`), for a method that runs
    /// the engine's passes (`restir:…`); empty for the others.
    pub passes: Vec<PassTiming>,
}

/// The output of [`Estimator::render_trajectory`].
#[derive(Clone, Debug)]
pub struct Trajectory {
    /// Linear RGB of frames `0..frames`.
    pub frames: Vec<Image>,
    /// Frames rendered to produce them.
    pub frames_rendered: u32,
    /// Shaded values that were NaN or infinite, over all frames.
    pub nonfinite: u64,
    /// Per-pixel sample counts of the last frame (`None`: [`Estimator::spp`] everywhere).
    pub counts: Option<SampleCounts>,
    /// Time of each pass of the frame pipeline over the rendered frames, in execution order
    /// (`gbuffer`, `candidates`, `temporal:…`, `spatial<n>:…`, `shade`), for a method that runs
    /// the engine's passes (`restir:…`); empty for the others.
    pub passes: Vec<PassTiming>,
}

impl Trajectory {
    /// Its last frame, with what the trajectory cost.
    pub fn last_frame(mut self) -> Result<LastFrame, PipelineError> {
        let image = self
            .frames
            .pop()
            .ok_or_else(|| PipelineError::Config("the run returned no frame".into()))?;
        Ok(LastFrame {
            image,
            frames_rendered: self.frames_rendered,
            nonfinite: self.nonfinite,
            passes: self.passes,
        })
    }
}

/// The final frame of one replica of a method, and what it cost.
#[derive(Clone, Debug)]
pub struct Rendered {
    /// Linear RGB of frame `frames − 1`.
    pub image: Image,
    /// Seconds per rendered frame on the backend's clock ([`engine::clock`]: CPU time of the
    /// process on the CPU backend, wall time on Vulkan with read-back; G-buffer included).
    pub seconds_per_frame: f64,
    /// Wall-clock seconds per rendered frame.
    pub wall_seconds_per_frame: f64,
    /// Frames the method rendered to produce `image` (1 for memoryless estimators).
    pub frames_rendered: u32,
    /// Whether the run ended early at its stop check ([`Method::render_until`]): `image` is
    /// then frame `frames_rendered − 1`.
    pub stopped: bool,
    /// Shaded values that were NaN or infinite (written as 0 or left out of the mean).
    pub nonfinite: u64,
    /// Mean samples per pixel of the frame over the pixels with a primary hit: the method's
    /// [`Method::spp`], or the mean of `counts` for a method that chooses them per pixel. An
    /// equal-cost comparison holds this equal, not `spp`.
    pub spp: f64,
    /// Per-pixel sample counts of the frame (`None`: `spp` everywhere).
    pub counts: Option<SampleCounts>,
    /// Time of each pass of the frame pipeline over the rendered frames, in execution order
    /// (`gbuffer`, `candidates`, `temporal:…`, `spatial<n>:…`, `shade`), for a method that runs
    /// the engine's passes (`restir:…`); empty for the others.
    pub passes: Vec<PassTiming>,
}

/// A rendering method: a shared [`Estimator`]. Two methods are equal when their canonical
/// names are.
#[derive(Clone)]
pub struct Method(Arc<dyn Estimator>);

impl Method {
    /// The method of `estimator`.
    pub fn new(estimator: impl Estimator) -> Method {
        Method(Arc::new(estimator))
    }

    /// The canonical name (`pt:4`, `restir:hybrid`).
    pub fn name(&self) -> String {
        self.0.name()
    }

    /// Samples per pixel per frame: the path tracers' `spp`, 1 candidate for ReSTIR; for a method
    /// that chooses counts per pixel, the most a pixel may take (the mean is [`Rendered::spp`]).
    pub fn spp(&self) -> u32 {
        self.0.spp()
    }

    /// The same method with `spp` samples per pixel; a method with a fixed per-frame cost is
    /// returned unchanged.
    pub fn with_spp(&self, spp: u32) -> Method {
        self.0.with_spp(spp).unwrap_or_else(|| self.clone())
    }

    /// Renders replica `seed` on the CPU and returns frame `frames − 1` (the resolution is the
    /// camera's).
    pub fn render(&self, scene: &Scene, frames: u32, seed: u64) -> Result<Rendered, PipelineError> {
        self.render_on(&Backend::Cpu, scene, frames, seed)
    }

    /// The path-tracer settings of this method's reference ([`Estimator::reference`]).
    pub fn reference(&self) -> PtSettings {
        self.0.reference()
    }

    /// Whether it renders scenes whose objects move ([`Estimator::renders_motion`]).
    pub fn renders_motion(&self) -> bool {
        self.0.renders_motion()
    }

    /// [`Method::render`] on `backend`, timed per rendered frame on the backend's clock
    /// ([`engine::clock`]) and on the wall clock.
    pub fn render_on(
        &self,
        backend: &Backend,
        scene: &Scene,
        frames: u32,
        seed: u64,
    ) -> Result<Rendered, PipelineError> {
        self.render_until(backend, scene, frames, seed, &|| false)
    }

    /// [`Method::render_on`] that a streamed method ends early once `stop` says yes
    /// ([`Estimator::render_until`]), e.g. at a Ctrl-C: the frames rendered so far are timed and
    /// the last of them returned, with [`Rendered::stopped`] set. Methods that are not streamed
    /// ignore `stop`.
    pub fn render_until(
        &self,
        backend: &Backend,
        scene: &Scene,
        frames: u32,
        seed: u64,
        stop: &dyn Fn() -> bool,
    ) -> Result<Rendered, PipelineError> {
        self.refuse_motion(scene)?;
        let origin = Path::new("(run)");
        let (width, height) = (scene.camera.width(), scene.camera.height());
        limits::frames(origin, "frames", frames)
            .and_then(|_| limits::resolution(origin, "width×height", width, height))
            .and_then(|_| {
                let bytes = engine::limits::run_bytes(width as u64 * height as u64, frames);
                let value = format!("{frames} frames at {width}×{height}");
                limits::memory(origin, "frames", &value, bytes, "the run")
            })
            .map_err(|e| PipelineError::Config(e.to_string()))?;
        // A method that sees `stop` say yes ends there, so a yes seen is a run stopped early.
        let stopped = Cell::new(false);
        let watched = || {
            let yes = stop();
            stopped.set(stopped.get() || yes);
            yes
        };
        let watch = Stopwatch::start(backend);
        let (frame, counts) = self
            .0
            .render_until(backend, scene, frames, seed, &watched)?;
        let timing = watch.read().per(frame.frames_rendered);
        Ok(Rendered {
            seconds_per_frame: timing.seconds,
            wall_seconds_per_frame: timing.wall_seconds,
            image: frame.image,
            frames_rendered: frame.frames_rendered,
            stopped: stopped.get(),
            nonfinite: frame.nonfinite,
            passes: frame.passes,
            spp: counts
                .as_ref()
                .map_or(self.spp() as f64, SampleCounts::mean),
            counts,
        })
    }

    /// The one-line refusal of a scene with a moving object for a method that renders only
    /// scenes at rest ([`Estimator::renders_motion`]; the Vulkan backend refuses them itself).
    fn refuse_motion(&self, scene: &Scene) -> Result<(), PipelineError> {
        match scene.moving_object() {
            Some(object) if !self.0.renders_motion() => Err(PipelineError::Config(format!(
                "{}: object {object:?} moves, and {} renders only scenes at rest",
                scene.file.display(),
                self.name()
            ))),
            _ => Ok(()),
        }
    }

    /// [`Estimator::render_trajectory`] of replica `seed` on `backend`, timed like
    /// [`Method::render_on`]: the returned timing is the whole trajectory's per rendered frame
    /// (a memoryless method renders every frame, so it is timed on every frame of the
    /// trajectory, like a method with memory).
    pub fn render_trajectory_on(
        &self,
        backend: &Backend,
        scene: &Scene,
        frames: u32,
        seed: u64,
    ) -> Result<(Trajectory, Timing), PipelineError> {
        if frames == 0 {
            return Err(PipelineError::Config("frames = 0; need at least 1".into()));
        }
        self.refuse_motion(scene)?;
        let watch = Stopwatch::start(backend);
        let trajectory = self.0.render_trajectory(backend, scene, frames, seed)?;
        let timing = watch.read().per(trajectory.frames_rendered);
        Ok((trajectory, timing))
    }
}

impl PartialEq for Method {
    fn eq(&self, other: &Method) -> bool {
        self.name() == other.name()
    }
}

impl fmt::Debug for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.0.fmt(f)
    }
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.pad(&self.name())
    }
}

/// `spp` of `family[:spp]`: 1 without an argument, else an integer in `1..=`[`MAX_SPP`].
pub fn parse_spp(arg: Option<&str>) -> Result<u32, String> {
    match arg {
        None => Ok(1),
        Some(text) => match text.parse::<u32>() {
            Ok(n) if (1..=MAX_SPP).contains(&n) => Ok(n),
            _ => Err(format!(
                "samples per pixel {text:?} is not an integer in 1..={MAX_SPP}"
            )),
        },
    }
}
