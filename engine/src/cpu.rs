//! The CPU backend (DESIGN §6): runs a preset's [`Plan`] — per frame, G-buffer → passes →
//! shade. Each pass is a pure per-pixel kernel that reads the previous buffers and writes a new
//! one (the plan's ping-pong between two reservoir buffers, plus the previous frame's final
//! buffer for temporal reuse), run with rayon over rows. No shared mutable state, so the output
//! is bit-identical for any thread count.

use std::convert::Infallible;
use std::time::Instant;

use glam::Vec3;
use rayon::prelude::*;
use restir::rng::StreamKey;
use shifts::{Hybrid, SssDomain, Target};
use sss::integrator::pt::{self, PtSettings, Shading};
use sss::scene::{GBuffer, Scene};

use restir::resample::ResampleError;
use restir::reservoir::InvalidCandidate;
use shifts::PixelReservoir;
use shifts::preset::{PassSpec, Preset, Shade};

use crate::candidates::{self, ProbeCounts};
use crate::diagnostics::{Counters, HybridChoice, Recorder};
use crate::image::Image;
use crate::plan::{PassKernel, Plan, Resource, Role, Rotation, Slot, Step};
use crate::reuse::{self, PassInput, Previous, Reused, ShiftCounts, StepTelemetry};
use crate::{PassTiming, PipelineError, Run, RunConfig, purpose};

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

/// Runs `preset` (already validated) for `config.frames` frames: its [`Plan`], step by step,
/// on three reservoir vectors that the plan's [`Rotation`] assigns to its slots.
pub(crate) fn run(
    scene: &Scene,
    preset: &Preset,
    config: &RunConfig,
) -> Result<Run, PipelineError> {
    let plan = Plan::lower(preset);
    let camera = &scene.camera;
    let (width, height) = (camera.width(), camera.height());
    let n = width as usize * height as usize;
    let mut seconds = vec![Vec::with_capacity(config.frames as usize); plan.steps.len()];
    let reuse_labels = plan
        .passes()
        .filter(|(_, step)| step.spec.is_some_and(|s| s.shift().is_some()))
        .map(|(_, step)| step.label.clone());
    let mut frame_state = Frame {
        scene,
        config,
        shade: preset.shade,
        target: preset.target,
        width,
        cells: vec![Cell::default(); n],
        rao_blackwellised: vec![None; n],
        reservoirs: std::array::from_fn(|_| vec![PixelReservoir::empty(); n]),
        rotation: Rotation::FIRST,
        gbuffer: None,
        previous_gbuffer: None,
        counters: config
            .collect_diagnostics
            .then(|| Counters::new(width, height, reuse_labels.collect())),
        recorder: None,
    };
    let pass_labels: Vec<String> = preset.passes.iter().map(PassSpec::label).collect();
    let mut frames = Vec::with_capacity(config.frames as usize);
    let mut nan_count = 0;
    for frame in 0..config.frames {
        if config.collect_diagnostics && frame + 1 == config.frames {
            frame_state.recorder = Some(Recorder::new(width, height, frame, pass_labels.clone()));
        }
        for (step, seconds) in plan.steps.iter().zip(&mut seconds) {
            let start = Instant::now();
            if let Some((image, nans)) = frame_state.step(frame, step)? {
                frames.push(image);
                nan_count += nans;
            }
            seconds.push(start.elapsed().as_secs_f64());
        }
        frame_state.rotation = frame_state.rotation.next(&plan);
        frame_state.previous_gbuffer = frame_state.gbuffer.take();
    }
    let timings = plan
        .steps
        .iter()
        .zip(seconds)
        .map(|(step, seconds)| PassTiming::new(step.label.clone(), seconds))
        .collect();
    let last = frame_state.rotation.buffer(Slot::Previous);
    let mut diagnostics = frame_state.counters.as_ref().map(Counters::finish);
    if let (Some(d), Some(recorder)) = (&mut diagnostics, frame_state.recorder.take()) {
        d.telemetry = Some(recorder.finish(&frame_state.reservoirs[last]));
    }
    Ok(Run {
        frames,
        timings,
        diagnostics,
        nan_count,
        reservoirs: std::mem::take(&mut frame_state.reservoirs[last]),
    })
}

/// The CPU backend's buffers of a run: the plan's frame resources, and the diagnostics.
struct Frame<'a> {
    scene: &'a Scene,
    config: &'a RunConfig,
    shade: Shade,
    target: Target,
    width: u32,
    /// The output of the running pass per pixel (its reservoir and diagnostics).
    cells: Vec<Cell>,
    /// Per pixel, the Rao-Blackwellised value of this frame's last reuse pass that resampled it
    /// ([`Shade::AllInputs`]; `None` everywhere for [`Shade::Selected`]).
    rao_blackwellised: Vec<Option<Vec3>>,
    reservoirs: [Vec<PixelReservoir>; 3],
    rotation: Rotation,
    gbuffer: Option<GBuffer>,
    previous_gbuffer: Option<GBuffer>,
    counters: Option<Counters>,
    /// The reuse telemetry, during the last frame of a run with diagnostics.
    recorder: Option<Recorder>,
}

impl Frame<'_> {
    /// Runs `step` of frame `frame`; shade returns the frame's image and its non-finite count.
    fn step(&mut self, frame: u32, step: &Step) -> Result<Option<(Image, u64)>, PipelineError> {
        let scene = self.scene;
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
            gbuffer,
            reservoirs: bound(Role::PreviousReservoirs),
        });
        let cells = &mut self.cells;
        run_pass(
            &input,
            previous.as_ref(),
            &spec,
            self.shade,
            self.width,
            cells,
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

/// One preset pass over every pixel into `cells`.
fn run_pass(
    input: &PassInput,
    previous: Option<&Previous>,
    spec: &PassSpec,
    shade: Shade,
    width: u32,
    cells: &mut [Cell],
) -> Result<(), PixelError> {
    let seed = input.seed;
    let collect = input.collect_diagnostics;
    match *spec {
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
                    let Reused {
                        reservoir,
                        shifts,
                        telemetry,
                        rao_blackwellised,
                    } = result.map_err(|e| PixelError::Resample(pixel, e))?;
                    *cell = Cell {
                        reservoir,
                        shifts,
                        telemetry,
                        rao_blackwellised,
                        ..Cell::default()
                    };
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
        let value = match input.domain(pixel) {
            Some((domain, _)) => rao_blackwellised[pixel as usize]
                .unwrap_or_else(|| reuse::shade(&domain, &reservoirs[pixel as usize])),
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
mod tests {
    use super::*;
    use crate::with_threads;
    use crate::{run, run_pt};

    fn scene(name: &str, size: u32) -> Scene {
        let mut scene = Scene::builtin(name).unwrap();
        scene.camera = scene.camera.with_resolution(size, size);
        scene
    }

    fn luminance_mean(image: &Image) -> f64 {
        let [r, g, b] = image.mean();
        0.2126 * r + 0.7152 * g + 0.0722 * b
    }

    fn bits(run: &Run) -> (Vec<u32>, Vec<u8>) {
        let pixels = run
            .frames
            .iter()
            .flat_map(|f| &f.pixels)
            .flat_map(|p| p.to_array().map(f32::to_bits));
        (
            pixels.collect(),
            bytemuck::cast_slice(&run.reservoirs).to_vec(),
        )
    }

    /// Same seed → bit-identical frames and final reservoirs with 1 and 2 threads, for a preset
    /// with every pass kind (sequential, deferred index), the hybrid and the hybrid with
    /// Rao-Blackwellised shading, diagnostics on.
    /// Control: another seed changes the output, so the comparison can see a difference.
    #[test]
    fn output_is_bit_identical_for_any_thread_count() {
        let scene = scene("bumpy", 24);
        let config = RunConfig {
            seed: 3,
            frames: 4,
            collect_diagnostics: true,
        };
        let rao_blackwellised = Preset {
            name: "hybrid/shade=all".into(),
            shade: Shade::AllInputs,
            ..Preset::named("hybrid").unwrap()
        };
        let presets = [
            Preset::named("sequential").unwrap(),
            Preset::named("hybrid").unwrap(),
            rao_blackwellised,
        ];
        for preset in presets {
            let name = &preset.name;
            let one = with_threads(1, || run(&scene, &preset, &config).unwrap());
            let two = with_threads(2, || run(&scene, &preset, &config).unwrap());
            assert_eq!(bits(&one), bits(&two), "{name}: 1 vs 2 threads");
            assert_eq!(one.diagnostics, two.diagnostics, "{name}: diagnostics");
            assert_eq!(one.reservoirs.len(), 24 * 24);
            let other = RunConfig { seed: 4, ..config };
            let reseeded = with_threads(2, || run(&scene, &preset, &other).unwrap());
            assert_ne!(
                bits(&one).0,
                bits(&reseeded).0,
                "{name}: control, another seed"
            );
        }
    }

    /// Rao-Blackwellised shading changes only the colour of the shaded value: for every preset,
    /// the reservoirs are bit-identical to [`Shade::Selected`]'s (later frames are unaffected),
    /// every pixel has the same luminance up to f32 rounding (`p̂ = luminance(f)`, so
    /// `Σ_i p̂(y_i)·m_i·W_i·J_i = w_sum = p̂(Y)·W`), and the colours differ in more than 10% of
    /// the pixels (control: the option does something).
    #[test]
    fn rao_blackwellised_shading_keeps_reservoirs_and_luminance() {
        let scene = scene("bumpy", 24);
        let config = RunConfig {
            seed: 5,
            frames: 3,
            collect_diagnostics: false,
        };
        let luminance = |p: Vec3| 0.2126 * p.x as f64 + 0.7152 * p.y as f64 + 0.0722 * p.z as f64;
        for preset in Preset::all() {
            let rb = Preset {
                shade: Shade::AllInputs,
                ..preset.clone()
            };
            let (a, b) = (
                run(&scene, &preset, &config).unwrap(),
                run(&scene, &rb, &config).unwrap(),
            );
            assert_eq!(bits(&a).1, bits(&b).1, "{}: reservoirs", preset.name);
            let (mut differing, mut compared) = (0, 0);
            for (fa, fb) in a.frames.iter().zip(&b.frames) {
                for (pa, pb) in fa.pixels.iter().zip(&fb.pixels) {
                    let (la, lb) = (luminance(*pa), luminance(*pb));
                    assert!(
                        (la - lb).abs() <= 1e-4 * la.max(lb) + 1e-7,
                        "{}: luminance {la} vs {lb}",
                        preset.name
                    );
                    compared += 1;
                    differing += (pa != pb) as u32;
                }
            }
            println!(
                "{}: {differing} of {compared} pixels change colour",
                preset.name
            );
            assert!(
                differing * 10 > compared,
                "{}: only {differing} of {compared} changed",
                preset.name
            );
        }
    }

    /// Every preset runs the 16-frame trajectory at 32×32 on `bumpy` and `half-shadow` with no
    /// NaN, finite non-negative pixels, and an accumulated mean luminance within a factor 1.5 of
    /// the path tracer's (16 spp per frame). A plausibility bound, not the unbiasedness test
    /// (that is `lab/tests/unbiased.rs`).
    #[test]
    fn every_preset_renders_plausible_frames() {
        for name in ["bumpy", "half-shadow"] {
            let scene = scene(name, 32);
            let config = RunConfig {
                seed: 1,
                ..RunConfig::default()
            };
            let pt = luminance_mean(&run_pt(&scene, 16, &config).accumulated().unwrap());
            for preset in Preset::all() {
                let r = run(&scene, &preset, &config).unwrap();
                assert_eq!(r.frames.len(), 16);
                assert_eq!(r.nan_count, 0, "{name} {}", preset.name);
                for frame in &r.frames {
                    assert_eq!((frame.width, frame.height), (32, 32));
                    assert!(
                        frame
                            .pixels
                            .iter()
                            .all(|p| p.is_finite() && p.min_element() >= 0.0)
                    );
                }
                let mean = luminance_mean(&r.accumulated().unwrap());
                println!(
                    "{name} {}: mean luminance {mean:.5}, path tracer {pt:.5}",
                    preset.name
                );
                assert!(
                    (pt / 1.5..pt * 1.5).contains(&mean),
                    "{name} {}: mean {mean} vs path tracer {pt}",
                    preset.name
                );
            }
        }
    }

    /// Reuse telemetry on a tiny scene: it leaves every frame and the final reservoirs
    /// bit-identical (diagnostics on vs off); its counts are consistent (origins account for
    /// every pixel with a sample, failures by kind ≤ shifts, `m_0 ∈ [0, 1]`, `Σ 1/sharing` =
    /// the number of distinct x2); every origin occurs. Control: reconnection copies x2, so
    /// pixels share samples (mean sharing > 1), and the failure kinds sum to the diagnostics'
    /// failure count of the last frame (a one-frame run, where both see the same frame).
    #[test]
    fn telemetry_observes_without_changing_the_output() {
        let scene = scene("bumpy", 24);
        let quiet = RunConfig {
            seed: 9,
            frames: 4,
            collect_diagnostics: false,
        };
        let loud = RunConfig {
            collect_diagnostics: true,
            ..quiet
        };
        for name in ["hybrid", "reconnection", "sequential"] {
            let preset = Preset::named(name).unwrap();
            let (a, b) = (
                run(&scene, &preset, &quiet).unwrap(),
                run(&scene, &preset, &loud).unwrap(),
            );
            assert_eq!(bits(&a), bits(&b), "{name}: telemetry changed the output");
            let t = b.diagnostics.unwrap().telemetry.unwrap();
            assert_eq!((t.frame, t.passes.len()), (3, preset.passes.len() - 1));
            let with_sample = b.reservoirs.iter().filter(|r| r.has_sample != 0).count();
            let mut origins = vec![0usize; preset.passes.len()];
            for o in t.origin.iter().flatten() {
                origins[*o as usize] += 1;
            }
            assert_eq!(origins.iter().sum::<usize>(), with_sample, "{name}");
            assert!(origins.iter().all(|&n| n > 0), "{name}: {origins:?}");
            for p in &t.passes {
                for (shifted, failed) in p.shifted.iter().zip(&p.failed_by) {
                    assert!(failed.iter().sum::<u32>() <= *shifted);
                }
                assert!(
                    p.canonical_mis
                        .iter()
                        .flatten()
                        .all(|m| (0.0..=1.0).contains(m))
                );
            }
            let distinct: f64 = t
                .sharing
                .iter()
                .filter(|&&k| k > 0)
                .map(|&k| 1.0 / k as f64)
                .sum();
            let keys: std::collections::HashSet<_> = b
                .reservoirs
                .iter()
                .filter(|r| r.has_sample != 0)
                .map(|r| (r.y.prim(), r.y.bary().x.to_bits(), r.y.bary().y.to_bits()))
                .collect();
            assert!((distinct - keys.len() as f64).abs() < 1e-6, "{name}");
            let mean_sharing =
                t.sharing.iter().map(|&k| k as f64).sum::<f64>() / with_sample as f64;
            println!("{name}: origins {origins:?}, mean sharing {mean_sharing:.3}");
            if name == "reconnection" {
                assert!(mean_sharing > 1.0, "control: {mean_sharing}");
            }
        }
        let one = RunConfig { frames: 1, ..loud };
        let d = run(&scene, &Preset::named("hybrid").unwrap(), &one)
            .unwrap()
            .diagnostics
            .unwrap();
        let t = d.telemetry.as_ref().unwrap();
        for (pass, f) in t.passes.iter().zip(&d.failures) {
            let by_kind: u64 = pass.failed_by.iter().flatten().map(|&n| n as u64).sum();
            let shifted: u64 = pass.shifted.iter().map(|&n| n as u64).sum();
            assert_eq!(shifted, f.shifted, "{}", f.label);
            assert_eq!(
                by_kind as f64,
                (f.rate * f.shifted as f64).round(),
                "{}",
                f.label
            );
        }
    }

    /// Timings name every pass; a bad configuration is a typed error.
    #[test]
    fn timings_and_configuration_errors() {
        let scene = scene("half-shadow", 8);
        let preset = Preset::named("sequential").unwrap();
        let r = run(
            &scene,
            &preset,
            &RunConfig {
                seed: 0,
                frames: 2,
                collect_diagnostics: false,
            },
        )
        .unwrap();
        let labels: Vec<&str> = r.timings.iter().map(|t| t.label.as_str()).collect();
        assert_eq!(labels.len(), preset.passes.len() + 2);
        assert_eq!((labels[0], labels[labels.len() - 1]), ("gbuffer", "shade"));
        assert!(r.diagnostics.is_none());
        assert!(r.seconds_per_frame("candidates").unwrap() >= 0.0);
        let zero = RunConfig {
            frames: 0,
            ..RunConfig::default()
        };
        assert!(matches!(
            run(&scene, &preset, &zero),
            Err(PipelineError::Config(_))
        ));
        let bad = Preset {
            name: "bad".into(),
            passes: preset.passes[1..].to_vec(),
            ..preset.clone()
        };
        assert!(matches!(
            run(&scene, &bad, &RunConfig::default()),
            Err(PipelineError::Preset(_))
        ));
    }

    /// Diagnostics on the flat `half-shadow` plane: a probe along the normal hits the plane once,
    /// along a tangent never, so hits per probe estimate P(normal axis) = 0.5 (binomial z over
    /// all N probes, two-sided α = 1e-3). Control: on the curved `bumpy` object the same test
    /// rejects 0.5. Failure rates are ratios of counts, per-pass images lie in [0, 1], and the
    /// hybrid map shows both shifts on `bumpy` [001 Fig. 4].
    #[test]
    fn diagnostics_count_hits_failures_and_hybrid_choices() {
        let config = RunConfig {
            seed: 2,
            frames: 4,
            collect_diagnostics: true,
        };
        let preset = Preset::named("hybrid").unwrap();
        let z = |d: &crate::Diagnostics| {
            let n = d.probes as f64;
            ((d.mean_hits_per_probe - 0.5) / (0.25 / n).sqrt(), n)
        };
        let flat = run(&scene("half-shadow", 24), &preset, &config).unwrap();
        let d = flat.diagnostics.unwrap();
        let (z_flat, n) = z(&d);
        assert!(z_flat.abs() < 3.2905, "α = 1e-3, N ≈ {n}: z = {z_flat}");
        let curved = run(&scene("bumpy", 24), &preset, &config).unwrap();
        let d = curved.diagnostics.unwrap();
        let (z_curved, n_curved) = z(&d);
        println!(
            "hits per probe: half-shadow z = {z_flat:.3} (N = {n}), bumpy {:.4} z = {z_curved:.1} (N = {n_curved})",
            d.mean_hits_per_probe
        );
        assert!(
            z_curved.abs() > 3.2905,
            "control: α = 1e-3, N ≈ {n}: z = {z_curved}"
        );
        assert_eq!(d.failures.len(), 2);
        for f in &d.failures {
            assert!(f.shifted > 0 && (0.0..=1.0).contains(&f.rate), "{f:?}");
            assert!(f.image.pixels.iter().all(|p| (0.0..=1.0).contains(&p.x)));
        }
        assert!(
            d.improved_fraction
                .pixels
                .iter()
                .all(|p| (0.0..=1.0).contains(&p.x))
        );
        let blue = d.hybrid_choice.pixels.iter().filter(|p| p.z > 0.5).count();
        let yellow = d.hybrid_choice.pixels.iter().filter(|p| p.x > 0.5).count();
        assert!(
            blue > 0 && yellow > 0,
            "hybrid map: {blue} reconnection, {yellow} delayed"
        );
        let names: std::collections::HashSet<String> =
            d.images().into_iter().map(|(n, _)| n).collect();
        assert_eq!(names.len(), 3 + d.failures.len());
        assert!(names.contains("failures-2-spatial4-hybrid"), "{names:?}");
    }
}
