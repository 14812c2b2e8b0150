//! The CPU backend (DESIGN §6): runs a preset's [`Plan`] — per frame, G-buffer → passes →
//! shade. Each pass is a pure per-pixel kernel that reads the previous buffers and writes a new
//! one (the plan's ping-pong between two reservoir buffers, plus the previous frame's final
//! buffer for temporal reuse), run with rayon over rows. No shared mutable state, so the output
//! is bit-identical for any thread count.

use std::borrow::Cow;
use std::convert::Infallible;

use glam::Vec3;
use rayon::prelude::*;
use restir::rng::StreamKey;
use shifts::{Hybrid, SssDomain, Target};
use sss::integrator::pt::{self, PtSettings, Shading};
use sss::scene::{GBuffer, Pose, Scene};

use restir::resample::ResampleError;
use restir::reservoir::InvalidCandidate;
use shifts::PixelReservoir;
use shifts::preset::{Duplication, Pairs, PassSpec, Preset, Shade};

use crate::candidates::{self, ProbeCounts};
use crate::clock::Stopwatch;
use crate::diagnostics::{Counters, HybridChoice, Recorder};
use crate::duplication;
use crate::image::Image;
use crate::plan::{PassKernel, Plan, Resource, Role, Rotation, Slot, Step};
use crate::reciprocal::{self, Combine, Exchanged};
use crate::reuse::{self, PassInput, Previous, Reused, ShiftCounts, StepTelemetry};
use crate::stream::frame::{Finished, Frame, mean_confidence};
use crate::{Backend, PipelineError, RunConfig, purpose};

/// Fills `out` (row-major, rows of `width`) with `kernel(pixel)` in parallel over rows; the
/// first error in pixel order wins, so errors are as deterministic as results.
fn per_pixel<T: Send, E: Send>(
    out: &mut [T],
    width: u32,
    kernel: impl Fn(u32, &mut T) -> Result<(), E> + Sync,
) -> Result<(), E> {
    let width = width.max(1) as usize;
    let errors: Vec<Option<E>> = out
        .par_chunks_mut(width)
        .enumerate()
        .map(|(row, cells)| {
            for (x, cell) in cells.iter_mut().enumerate() {
                if let Err(e) = kernel((row * width + x) as u32, cell) {
                    return Some(e);
                }
            }
            None
        })
        .collect();
    errors.into_iter().flatten().next().map_or(Ok(()), Err)
}

/// One pixel's output of a pass: the reservoir, its diagnostics and the Rao-Blackwellised value
/// ([`Shade::AllInputs`]).
#[derive(Clone, Copy, Default)]
struct Cell {
    reservoir: PixelReservoir,
    probes: ProbeCounts,
    hybrid: HybridChoice,
    shifts: ShiftCounts,
    telemetry: StepTelemetry,
    rao_blackwellised: Option<Vec3>,
}

impl From<Reused> for Cell {
    fn from(reused: Reused) -> Cell {
        let Reused {
            reservoir,
            shifts,
            telemetry,
            rao_blackwellised,
        } = reused;
        Cell {
            reservoir,
            shifts,
            telemetry,
            rao_blackwellised,
            ..Cell::default()
        }
    }
}

/// A preset's stream on the CPU: its [`Plan`], run step by step frame after frame on three
/// reservoir vectors that the plan's [`Rotation`] assigns to its slots, and the state the
/// frames share (the previous frame's G-buffer and reservoirs, the diagnostics).
pub(crate) struct CpuStream<'a> {
    plan: Plan,
    /// The scene, owned once a frame moves its camera ([`CpuStream::move_camera`]).
    scene: Cow<'a, Scene>,
    state: RunState,
    pass_labels: Vec<String>,
    /// The frame [`CpuStream::frame`] renders next.
    next: u32,
}

impl<'a> CpuStream<'a> {
    /// The stream of `preset` (already validated) on `scene`; `config.frames` is the frame
    /// whose reuse telemetry is recorded (the last of a run) when diagnostics are collected.
    pub(crate) fn new(scene: Cow<'a, Scene>, preset: &Preset, config: &RunConfig) -> CpuStream<'a> {
        let plan = Plan::lower(preset);
        let camera = &scene.camera;
        let (width, height) = (camera.width(), camera.height());
        let n = width as usize * height as usize;
        let reuse_labels = plan
            .passes()
            .filter(|(_, step)| step.spec.is_some_and(|s| s.shift().is_some()))
            .map(|(_, step)| step.label.clone());
        let state = RunState {
            config: *config,
            duplication: preset.duplication,
            sharing: None,
            shade: preset.shade,
            target: preset.target,
            width,
            cells: vec![Cell::default(); n],
            exchanged: Vec::new(),
            rao_blackwellised: vec![None; n],
            reservoirs: std::array::from_fn(|_| vec![PixelReservoir::empty(); n]),
            rotation: Rotation::FIRST,
            gbuffer: None,
            previous_gbuffer: None,
            previous_scene: None,
            counters: config
                .collect_diagnostics
                .then(|| Counters::new(width, height, reuse_labels.collect())),
            recorder: None,
        };
        CpuStream {
            plan,
            scene,
            state,
            pass_labels: preset.passes.iter().map(PassSpec::label).collect(),
            next: 0,
        }
    }

    /// The labels of the plan's steps, in execution order.
    pub(crate) fn labels(&self) -> Vec<String> {
        self.plan.steps.iter().map(|s| s.label.clone()).collect()
    }

    /// Renders the next frame: each step of the plan, timed.
    pub(crate) fn frame(&mut self) -> Result<Frame, PipelineError> {
        let frame = self.next;
        let (width, height) = (self.state.width, self.scene.camera.height());
        let config = self.state.config;
        if config.collect_diagnostics && frame + 1 == config.frames {
            let labels = self.pass_labels.clone();
            self.state.recorder = Some(Recorder::new(width, height, frame, labels));
        }
        let mut steps = Vec::with_capacity(self.plan.steps.len());
        let mut shaded = None;
        // The scene posed at the frame (a new BVH where objects move) is timed with the first
        // step, the G-buffer's.
        let mut watch = Stopwatch::start(&Backend::Cpu);
        let scene = self.scene.at_frame(frame);
        for step in &self.plan.steps {
            if let Some(image) = self.state.step(&scene, frame, step)? {
                shaded = Some(image);
            }
            steps.push(watch.read());
            watch = Stopwatch::start(&Backend::Cpu);
        }
        // Temporal reuse evaluates its history in the scene of its frame.
        self.state.previous_scene = scene.motion.is_some().then(|| scene.into_owned());
        let (image, nan_count) =
            shaded.ok_or_else(|| PipelineError::Config("a plan without a shade step".into()))?;
        self.state.rotation = self.state.rotation.next(&self.plan);
        self.state.previous_gbuffer = self.state.gbuffer.take();
        self.next += 1;
        let last = self.state.rotation.buffer(Slot::Previous);
        if self.state.duplication == Duplication::Divides {
            self.state.sharing = Some(duplication::sharing(&self.state.reservoirs[last]));
        }
        Ok(Frame {
            index: frame,
            image,
            nan_count,
            steps,
            confidence: mean_confidence(&self.state.reservoirs[last]),
        })
    }

    /// Moves the camera to `pose` from the next frame on ([`sss::scene::Camera::moved_to`]).
    pub(crate) fn move_camera(&mut self, pose: Pose) {
        let camera = &mut self.scene.to_mut().camera;
        *camera = camera.moved_to(self.next, pose);
    }

    /// The last frame's final reservoirs and the diagnostics of the frames so far.
    pub(crate) fn finish(mut self) -> Finished {
        let last = self.state.rotation.buffer(Slot::Previous);
        let mut diagnostics = self.state.counters.as_ref().map(Counters::finish);
        if let (Some(d), Some(recorder)) = (&mut diagnostics, self.state.recorder.take()) {
            d.telemetry = Some(recorder.finish(&self.state.reservoirs[last]));
        }
        Finished {
            diagnostics,
            reservoirs: std::mem::take(&mut self.state.reservoirs[last]),
        }
    }
}

/// The CPU backend's state across the frames of a run: the plan's frame resources (reservoirs,
/// G-buffers, their rotation) and the diagnostics.
struct RunState {
    config: RunConfig,
    duplication: Duplication,
    /// With [`Duplication::Divides`], the duplication map of the previous frame's final
    /// reservoirs.
    sharing: Option<Vec<u32>>,
    shade: Shade,
    target: Target,
    width: u32,
    /// The output of the running pass per pixel (its reservoir and diagnostics).
    cells: Vec<Cell>,
    /// What each pixel sent its partners in a reciprocal spatial pass (`engine::reciprocal`),
    /// one entry per neighbour slot; kept between passes so it is allocated once.
    exchanged: Vec<Exchanged>,
    /// Per pixel, the Rao-Blackwellised value of this frame's last reuse pass that resampled it
    /// ([`Shade::AllInputs`]; `None` everywhere for [`Shade::Selected`]).
    rao_blackwellised: Vec<Option<Vec3>>,
    reservoirs: [Vec<PixelReservoir>; 3],
    rotation: Rotation,
    gbuffer: Option<GBuffer>,
    previous_gbuffer: Option<GBuffer>,
    /// The previous frame's scene where objects move (posed there); `None` where nothing moves.
    previous_scene: Option<Scene>,
    counters: Option<Counters>,
    /// The reuse telemetry, during the last frame of a run with diagnostics.
    recorder: Option<Recorder>,
}

impl RunState {
    /// Runs `step` of frame `frame` of `scene` (posed at `frame`); shade returns the frame's image and its
    /// non-finite count.
    fn step(
        &mut self,
        scene: &Scene,
        frame: u32,
        step: &Step,
    ) -> Result<Option<(Image, u64)>, PipelineError> {
        if step.kernel == PassKernel::GBuffer {
            self.gbuffer = Some(GBuffer::render(scene, frame));
            if step.clears.contains(&Resource::RaoBlackwellised) {
                self.rao_blackwellised.fill(None);
            }
            return Ok(None);
        }
        let gbuffer = self
            .gbuffer
            .as_ref()
            .ok_or_else(|| PipelineError::Config("a plan step before the G-buffer".into()))?;
        // The reservoirs of the slot `step` binds in `role`; empty if it binds none.
        let bound = |role| match step.resource(role) {
            Some(Resource::Reservoirs(slot)) => &self.reservoirs[self.rotation.buffer(slot)][..],
            _ => &[],
        };
        let seed = self.config.seed;
        let Some(spec) = step.spec else {
            let reservoirs = bound(Role::ReservoirsIn);
            let rao_blackwellised = &self.rao_blackwellised;
            return Ok(Some(shade(
                scene,
                gbuffer,
                reservoirs,
                rao_blackwellised,
                step.pass,
                seed,
                self.target,
            )));
        };
        let input = PassInput {
            scene,
            gbuffer,
            reservoirs: bound(Role::ReservoirsIn),
            pass: step.pass,
            seed,
            collect_diagnostics: self.config.collect_diagnostics,
            target: self.target,
        };
        let previous = self.previous_gbuffer.as_ref().map(|gbuffer| Previous {
            scene: self.previous_scene.as_ref().unwrap_or(scene),
            gbuffer,
            reservoirs: bound(Role::PreviousReservoirs),
            sharing: self.sharing.as_deref(),
        });
        let cells = &mut self.cells;
        run_pass(
            &input,
            previous.as_ref(),
            &spec,
            self.shade,
            self.width,
            cells,
            &mut self.exchanged,
        )
        .map_err(|e| e.at(frame, step.pass as usize))?;
        if let Some(Resource::Reservoirs(slot)) = step.resource(Role::ReservoirsOut) {
            let out = &mut self.reservoirs[self.rotation.buffer(slot)];
            for (r, c) in out.iter_mut().zip(cells.iter()) {
                *r = c.reservoir;
            }
        }
        for (v, c) in self.rao_blackwellised.iter_mut().zip(cells.iter()) {
            if c.rao_blackwellised.is_some() {
                *v = c.rao_blackwellised;
            }
        }
        if let Some(counters) = &mut self.counters {
            if spec.shift().is_some() {
                let shifts: Vec<ShiftCounts> = cells.iter().map(|c| c.shifts).collect();
                // Candidates are pass 0 and every later pass reuses (Preset::validate).
                counters.add_shifts(step.pass as usize - 1, &shifts);
            } else {
                let probes: Vec<_> = cells.iter().map(|c| (c.probes, c.hybrid)).collect();
                counters.add_candidates(&probes);
            }
        }
        if let Some(recorder) = &mut self.recorder {
            if spec.shift().is_some() {
                let observed = cells
                    .iter()
                    .map(|c| (&c.reservoir, &c.telemetry, c.shifts.shifted));
                recorder.reuse(step.pass, observed);
            } else {
                recorder.candidates(cells.iter().map(|c| &c.reservoir));
            }
        }
        Ok(None)
    }
}

/// Why a pixel of a pass failed, before the frame and pass are known.
enum PixelError {
    Candidate(u32, InvalidCandidate),
    Resample(u32, ResampleError),
}

impl PixelError {
    fn at(self, frame: u32, pass: usize) -> PipelineError {
        match self {
            PixelError::Candidate(pixel, error) => PipelineError::Candidate {
                frame,
                pixel,
                error,
            },
            PixelError::Resample(pixel, error) => PipelineError::Resample {
                frame,
                pass,
                pixel,
                error,
            },
        }
    }
}

/// One preset pass over every pixel into `cells` (`exchanged`: the buffer of a reciprocal
/// spatial pass's first phase).
fn run_pass(
    input: &PassInput,
    previous: Option<&Previous>,
    spec: &PassSpec,
    shade: Shade,
    width: u32,
    cells: &mut [Cell],
    exchanged: &mut Vec<Exchanged>,
) -> Result<(), PixelError> {
    let seed = input.seed;
    let collect = input.collect_diagnostics;
    match *spec {
        PassSpec::Spatial {
            shift,
            mis,
            neighbours,
            confidence_cap,
            radius,
            pairs: Pairs::Reciprocal,
        } => {
            let domains = reciprocal::domains(input);
            let radius = reciprocal::frame_radius(input, &domains, radius);
            let pairings = reciprocal::pairings(input, radius, neighbours);
            let slots = pairings.len().max(1);
            exchanged.resize(cells.len() * slots, Exchanged::Untaken);
            // Phase 1: every pixel's sample shifted into its partners, rows in parallel.
            exchanged
                .par_chunks_mut(width.max(1) as usize * slots)
                .enumerate()
                .for_each(|(row, out)| {
                    for (x, out) in out.chunks_mut(slots).enumerate() {
                        let pixel = (row * width as usize + x) as u32;
                        reciprocal::shift_to_partners(
                            input, &domains, &pairings, shift, pixel, out,
                        );
                    }
                });
            let pass = Combine {
                domains: &domains,
                pairings: &pairings,
                exchanged: &exchanged[..],
                shift,
                mis: mis.scheme(),
                cap: confidence_cap,
                shade,
            };
            // Phase 2: every pixel resampled from what it sent and received.
            per_pixel(cells, width, |pixel, cell| {
                let reused = reciprocal::combine(input, &pass, pixel)
                    .map_err(|e| PixelError::Resample(pixel, e))?;
                *cell = Cell::from(reused);
                Ok(())
            })
        }
        PassSpec::Candidates {
            bssrdf_samples,
            shared_light,
        } => per_pixel(cells, width, |pixel, cell| {
            *cell = Cell::default();
            let Some((domain, _)) = input.domain(pixel) else {
                return Ok(());
            };
            let mut hits = Vec::new();
            let (mut canonical, probes) =
                candidates::generate(&domain, bssrdf_samples, shared_light, seed, &mut hits)
                    .map_err(|e| PixelError::Candidate(pixel, e))?;
            candidates::shadow_test(&domain, &mut canonical);
            cell.reservoir = PixelReservoir::from(&canonical);
            if collect {
                cell.probes = probes;
                cell.hybrid = hybrid_choice(&domain, &cell.reservoir);
            }
            Ok(())
        }),
        PassSpec::Temporal { .. } | PassSpec::Spatial { .. } => {
            per_pixel(cells, width, |pixel, cell| {
                if let Some(result) = reuse::pass(input, previous, pixel, spec, shade) {
                    let reused = result.map_err(|e| PixelError::Resample(pixel, e))?;
                    *cell = Cell::from(reused);
                }
                Ok(())
            })
        }
    }
}

/// Which shift the hybrid criterion picks for the canonical sample [001 Fig. 4].
fn hybrid_choice(domain: &SssDomain, reservoir: &PixelReservoir) -> HybridChoice {
    let hybrid = Hybrid::for_material(domain.material());
    match reservoir
        .get()
        .y
        .and_then(|y| hybrid.uses_reconnection(&y, domain))
    {
        Some(true) => HybridChoice::Reconnection,
        Some(false) => HybridChoice::Delayed,
        None => HybridChoice::None,
    }
}

/// The frame's image: on translucent pixels `f(Y)·W`, or the Rao-Blackwellised value where
/// `rao_blackwellised` has one ([`Shade::AllInputs`]); other primary hits get one sample of the
/// path tracer's estimator (Lambert direct lighting by NEE), so a ReSTIR image and a
/// path-traced one estimate the same radiance everywhere. Non-finite values are counted and
/// written as 0.
fn shade(
    scene: &Scene,
    gbuffer: &GBuffer,
    reservoirs: &[PixelReservoir],
    rao_blackwellised: &[Option<Vec3>],
    pass: u32,
    seed: u64,
    target: Target,
) -> (Image, u64) {
    let mut pixels = vec![Vec3::ZERO; reservoirs.len()];
    let settings = PtSettings::default();
    let input = PassInput {
        scene,
        gbuffer,
        reservoirs,
        pass,
        seed,
        collect_diagnostics: false,
        target,
    };
    let nans = std::sync::atomic::AtomicU64::new(0);
    let Ok(()) = per_pixel::<_, Infallible>(&mut pixels, gbuffer.width, |pixel, out| {
        let Some(g) = &gbuffer.pixels[pixel as usize] else {
            return Ok(());
        };
        // A Rao-Blackwellised value exists only where a reuse pass built the pixel's domain,
        // so the domain is built here only for the selected sample's `f(Y)·W`.
        let value = match rao_blackwellised[pixel as usize] {
            Some(value) => value,
            None => match input.domain(pixel) {
                Some((domain, _)) => reuse::shade(&domain, &reservoirs[pixel as usize]),
                None => {
                    let mut rng =
                        StreamKey::new(pixel, gbuffer.frame, pass, purpose::OPAQUE).stream(seed);
                    pt::estimate(
                        scene,
                        &Shading::new(scene, g),
                        &settings,
                        &mut rng,
                        &mut Vec::new(),
                    )
                }
            },
        };
        if value.is_finite() {
            *out = value;
        } else {
            nans.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        }
        Ok(())
    });
    (
        Image {
            width: gbuffer.width,
            height: gbuffer.height,
            pixels,
        },
        nans.into_inner(),
    )
}

#[cfg(test)]
mod tests;
