//! `engine`: the reshift engine (DESIGN §6). This crate runs the ReSTIR SSS frame pipeline
//! described as data ([`Preset`], [`PassSpec`] of `shifts::preset`) on its deterministic CPU
//! backend ([`run`]), the path-traced baseline behind the same interface ([`run_pt`]),
//! diagnostics and images.
//!
//! Per frame: G-buffer → candidates [001 §3.1] → temporal reuse → spatial pass(es) → shade
//! `f(Y)·W`. Every random number comes from `StreamKey { pixel, frame, pass, purpose }` with the
//! purposes of [`purpose`]; a run is a function of `(scene, preset, seed, frames)`.

pub mod backend;
pub mod candidates;
pub mod clock;
/// What the kernels (`engine/glsl/`) and the scene twins (`sss/glsl/`) share with the host: the
/// device buffers' std430 structs, push constants, kinds, limits and diag codes
/// (`twin::contract!`; rendered to `contract/engine.glsl` and one header per push-constant block
/// by `build.rs`).
pub mod contract;
mod cpu;
pub mod denoise;
pub mod diagnostics;
pub mod duplication;
pub mod hash;
pub mod image;
pub mod limits;
pub mod plan;
/// `purpose` tags of the pipeline's random streams. Every random number of a pass comes from
/// `StreamKey { pixel, frame, pass, purpose }.stream(seed)`, with `pixel` the receiving pixel's
/// linear index, `pass` the pass's index in the preset (0 = candidates) and `purpose` one of
/// these (`PURPOSE_<NAME>` in GLSL). They stay below 2³⁰: the `shifts` crate keys its own
/// streams (probabilistic inversion's γ, the deferred uniform pick) with the top two bits set,
/// and the path tracer uses `sss::integrator::pt::PURPOSE_PT`.
pub mod purpose;
pub mod reciprocal;
pub mod reuse;
pub mod scene_lighting;
pub mod stream;
pub mod vulkan;

use std::fmt;

use glam::DVec3;
use restir::resample::ResampleError;
use restir::reservoir::InvalidCandidate;
use sss::integrator::pt::{self, PtSettings};
use sss::scene::{FRAMES, GBuffer, Scene};

pub use backend::Backend;
use clock::Stopwatch;
pub use diagnostics::Diagnostics;
pub use image::Image;
pub use restir::mis::MisKind;
pub use shifts::preset::{PassSpec, Preset, PresetError, RadiusRule, Shade};
pub use shifts::{PixelReservoir, ShiftKind, Target};
pub use stream::{Finished, Frame, Keep, Stream};

/// `f` on a rayon pool of `n` threads: the tests that output does not depend on the thread
/// count run the same work with 1 and 2.
#[cfg(test)]
pub(crate) fn with_threads<R: Send>(n: usize, f: impl FnOnce() -> R + Send) -> R {
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .unwrap()
        .install(f)
}

/// What a run does besides the preset: the replica seed, the number of frames of the camera
/// trajectory, and whether diagnostics are collected (they re-apply shifts and cost time).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RunConfig {
    pub seed: u64,
    pub frames: u32,
    pub collect_diagnostics: bool,
}

impl Default for RunConfig {
    /// Seed 0, the 16-frame trajectory, no diagnostics.
    fn default() -> Self {
        RunConfig {
            seed: 0,
            frames: FRAMES,
            collect_diagnostics: false,
        }
    }
}

/// Time of one pass, per frame and summed over the frames of a run: wall-clock and process CPU
/// time on the CPU backend ([`clock`]), GPU timestamps on Vulkan.
#[derive(Clone, Debug, PartialEq)]
pub struct PassTiming {
    /// `gbuffer`, a [`PassSpec::label`], `shade`, or `pt` for the baseline.
    pub label: String,
    /// The sum of `per_frame`.
    pub seconds: f64,
    /// Seconds of each frame, in order (wall-clock on the CPU backend).
    pub per_frame: Vec<f64>,
    /// CPU seconds of the process over all frames (all its threads; the CPU backend, where the
    /// platform has a process CPU clock).
    pub cpu_seconds: Option<f64>,
}

impl PassTiming {
    /// The timing of `label` from the seconds of each frame (a clock with no CPU time).
    pub fn new(label: String, per_frame: Vec<f64>) -> PassTiming {
        PassTiming {
            label,
            seconds: per_frame.iter().sum(),
            per_frame,
            cpu_seconds: None,
        }
    }

    /// The timing of `label` from both clocks' readings of each frame.
    pub fn timed(label: String, per_frame: &[clock::Timing]) -> PassTiming {
        let cpu = per_frame
            .iter()
            .all(|t| t.clock == clock::Clock::ProcessCpu);
        PassTiming {
            cpu_seconds: cpu.then(|| per_frame.iter().map(|t| t.seconds).sum()),
            ..PassTiming::new(label, per_frame.iter().map(|t| t.wall_seconds).collect())
        }
    }
}

/// The result of a run.
#[derive(Clone, Debug)]
pub struct Run {
    /// Per-frame shaded linear RGB, one image per frame of the trajectory (only the last for a
    /// stream's run that keeps [`Keep::Last`]).
    pub frames: Vec<Image>,
    /// Frames rendered: the trajectory's, or fewer where a stream's run was stopped
    /// ([`Stream::run_until`]).
    pub frames_rendered: u32,
    /// Per-pass seconds, summed over frames, in execution order.
    pub timings: Vec<PassTiming>,
    pub diagnostics: Option<Diagnostics>,
    /// Shaded values that were NaN or infinite (written as 0).
    pub nan_count: u64,
    /// The final reservoirs of the last frame (empty for the path tracer).
    pub reservoirs: Vec<PixelReservoir>,
}

impl Run {
    /// The mean of all frames, accumulated in f64.
    pub fn accumulated(&self) -> Option<Image> {
        let first = self.frames.first()?;
        let mut sum = vec![DVec3::ZERO; first.pixels.len()];
        for frame in &self.frames {
            for (s, p) in sum.iter_mut().zip(&frame.pixels) {
                *s += p.as_dvec3();
            }
        }
        let n = self.frames.len() as f64;
        Some(Image {
            width: first.width,
            height: first.height,
            pixels: sum.into_iter().map(|s| (s / n).as_vec3()).collect(),
        })
    }

    /// Seconds per frame of the pass labelled `label`.
    pub fn seconds_per_frame(&self, label: &str) -> Option<f64> {
        let frames = self.frames.len().max(1) as f64;
        self.timings
            .iter()
            .find(|t| t.label == label)
            .map(|t| t.seconds / frames)
    }
}

/// Why a run failed.
#[derive(Clone, Debug, PartialEq)]
pub enum PipelineError {
    Preset(PresetError),
    /// `frames = 0` or another unusable setting.
    Config(String),
    /// Candidate generation produced an invalid candidate.
    Candidate {
        frame: u32,
        pixel: u32,
        error: InvalidCandidate,
    },
    /// A reuse pass failed (an invalid Jacobian, weight or confidence).
    Resample {
        frame: u32,
        pass: usize,
        pixel: u32,
        error: ResampleError,
    },
    /// The Vulkan backend could not run.
    Vulkan(vulkan::VulkanError),
}

impl fmt::Display for PipelineError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Preset(e) => e.fmt(f),
            Self::Config(reason) => write!(f, "run configuration: {reason}"),
            Self::Candidate {
                frame,
                pixel,
                error,
            } => {
                write!(f, "frame {frame}, pixel {pixel}, candidates: {error}")
            }
            Self::Resample {
                frame,
                pass,
                pixel,
                error,
            } => {
                write!(f, "frame {frame}, pass {pass}, pixel {pixel}: {error}")
            }
            Self::Vulkan(e) => e.fmt(f),
        }
    }
}

impl std::error::Error for PipelineError {}

impl From<PresetError> for PipelineError {
    fn from(e: PresetError) -> Self {
        PipelineError::Preset(e)
    }
}

impl From<vulkan::VulkanError> for PipelineError {
    fn from(e: vulkan::VulkanError) -> Self {
        PipelineError::Vulkan(e)
    }
}

/// Renders `config.frames` frames of `scene`'s camera trajectory with `preset` on the CPU.
/// The resolution is the scene camera's (set it with `Camera::with_resolution`); for the GPU
/// see [`Backend::run`].
pub fn run(scene: &Scene, preset: &Preset, config: &RunConfig) -> Result<Run, PipelineError> {
    Backend::Cpu.run(scene, preset, config)
}

/// The path-traced baseline (`sss::integrator::pt`, all hits per probe) at `spp` samples per
/// pixel for the same frames, so methods are interchangeable. Diagnostics are not collected.
pub fn run_pt(scene: &Scene, spp: u32, config: &RunConfig) -> Run {
    let settings = PtSettings::default();
    let (mut gbuffer_seconds, mut pt_seconds, mut nan_count) = (Vec::new(), Vec::new(), 0);
    let frames = (0..config.frames)
        .map(|frame| {
            let watch = Stopwatch::start(&Backend::Cpu);
            let gbuffer = GBuffer::render(scene, frame);
            gbuffer_seconds.push(watch.read());
            let watch = Stopwatch::start(&Backend::Cpu);
            let image = pt::render(scene, &gbuffer, &settings, config.seed, 0, spp);
            pt_seconds.push(watch.read());
            nan_count += image.nonfinite;
            Image {
                width: image.width,
                height: image.height,
                pixels: image.pixels.iter().map(|p| p.as_vec3()).collect(),
            }
        })
        .collect();
    Run {
        frames,
        frames_rendered: config.frames,
        timings: vec![
            PassTiming::timed("gbuffer".into(), &gbuffer_seconds),
            PassTiming::timed("pt".into(), &pt_seconds),
        ],
        diagnostics: None,
        nan_count,
        reservoirs: Vec::new(),
    }
}
