//! Rendering a comparison's replicas: every method's replicas (the plan's seeds, in rounds of one
//! seed), each one's frames at the measured frames and its last frame through each denoiser,
//! with an equal-time budget first calibrated on the bare path tracer ([`equal_time_method`]).
//! Every replica is timed on every frame it renders, on its backend's clock
//! ([`engine::clock`]: process CPU time on the CPU backend) and on the wall clock.

use std::ops::Range;

use engine::Backend;
use engine::denoise::{self, DenoiseError, Denoiser, Guide};
use serde::{Deserialize, Serialize};
use sss::scene::Scene;

use super::{Comparison, EQUAL_TIME_SPEC};
use crate::error::Error;
use crate::method_result::Replica;
use crate::progress::Progress;
use methods::pt::Pt;
use methods::{Method, SampleCounts};

/// One method's replicas as rendered.
pub(super) struct MethodRuns {
    pub(super) spec: String,
    pub(super) method: Method,
    /// The measured frames of each replica.
    pub(super) replicas: Vec<Replica>,
    /// Per denoiser that denoised every replica so far, the denoised last frames.
    pub(super) denoised: Vec<(Denoiser, Vec<Replica>)>,
    /// Replica 0's every frame, kept for the videos (empty without the plan's `video`).
    pub(super) trajectory: Vec<engine::Image>,
    /// Replica 0's every frame through each denoiser that denoised it, for the videos (or why
    /// that failed).
    pub(super) denoised_trajectory: Vec<(Denoiser, Result<Vec<engine::Image>, String>)>,
}

/// What [`render_replicas`] rendered.
pub(super) struct Renders {
    pub(super) runs: Vec<MethodRuns>,
    pub(super) denoise_errors: Vec<DenoiseFailure>,
}

/// A denoiser that failed, and the line that says so: on every method (`method: None`: it is
/// not installed) or on one method's replica (its denoised row is left out).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(super) struct DenoiseFailure {
    pub(super) method: Option<String>,
    pub(super) denoiser: String,
    pub(super) line: String,
}

/// The replicas of `seeds` (of the plan's: all of them, or a shard's,
/// [`crate::compare::shard`]) of every method, in the plan's order, each with its images at
/// `frames` (ascending, the last frame last) and its last frame through each denoiser of the
/// plan; the replica of the plan's first seed (replica 0) also keeps its whole trajectory with
/// the plan's `video`.
///
/// Replicas are rendered in rounds: the first seed of every method, then the next, and so on, so the
/// replicas of one seed, which the intervals pair ([`crate::uncertainty`]), are timed close
/// together. After a stop request the current replica finishes and the round it belongs to is
/// dropped unless it is whole: every method keeps the same seeds, the rounds finished. A
/// denoiser that fails on a replica leaves that method's denoised row out with one line in
/// `denoise_errors`; one that is not installed is left out of every method with one line.
pub(super) fn render_replicas(
    plan: &Comparison,
    frames: &[u32],
    seeds: Range<u64>,
    progress: &mut dyn Progress,
) -> Result<Renders, Error> {
    let seconds_per_spp = match plan.equal_time {
        Some(_) if plan.methods.iter().any(|(s, _)| s == EQUAL_TIME_SPEC) => {
            calibrate_pt(&plan.backend, &plan.scene, plan.frames)?
        }
        _ => 0.0,
    };
    let guides = if plan.denoise.is_empty() {
        Vec::new()
    } else {
        Guide::trajectory(&plan.scene, plan.frames)
    };
    let mut denoise_errors = Vec::new();
    // Untimed warm-up: loading a library, creating a device or compiling kernels is not the
    // per-frame cost a renderer pays.
    if let Some(guide) = guides.last() {
        let black = engine::Image::black(guide.width, guide.height);
        for &d in &plan.denoise {
            let _ = denoise::denoise(d, &plan.backend, &guides, std::slice::from_ref(&black));
        }
    }
    let mut runs: Vec<MethodRuns> = plan
        .methods
        .iter()
        .map(|(spec, method)| MethodRuns {
            spec: spec.clone(),
            // `pt:N` pins its spp; a bare `pt` is scaled to the budget.
            method: match plan.equal_time {
                Some(b) if spec == EQUAL_TIME_SPEC => equal_time_method(method, b, seconds_per_spp),
                _ => method.clone(),
            },
            replicas: Vec::new(),
            denoised: plan.denoise.iter().map(|&d| (d, Vec::new())).collect(),
            trajectory: Vec::new(),
            denoised_trajectory: Vec::new(),
        })
        .collect();
    progress.begin("replicas", runs.len() as u64 * (seeds.end - seeds.start), 0);
    'rounds: for seed in seeds.clone() {
        for i in 0..runs.len() {
            if progress.stop_requested() {
                for run in &mut runs {
                    run.truncate((seed - seeds.start) as usize);
                }
                break 'rounds;
            }
            let run = &mut runs[i];
            progress.item(&run.method.name());
            let (replica, trajectory) = render_replica(plan, &run.method, frames, seed)?;
            let mut failed = Vec::new();
            for (d, denoised) in &mut run.denoised {
                match denoise_replica(*d, &plan.backend, &guides, &trajectory, &replica) {
                    Ok(r) => denoised.push(r),
                    Err(e) => failed.push((*d, e)),
                }
            }
            for (d, e) in failed {
                if matches!(e, DenoiseError::Unavailable(_)) {
                    for run in &mut runs {
                        run.denoised.retain(|(x, _)| *x != d);
                    }
                    denoise_errors.push(DenoiseFailure {
                        method: None,
                        denoiser: d.to_string(),
                        line: format!("{d}: {e}; its rows are left out"),
                    });
                } else {
                    runs[i].denoised.retain(|(x, _)| *x != d);
                    denoise_errors.push(DenoiseFailure {
                        method: Some(runs[i].spec.clone()),
                        denoiser: d.to_string(),
                        line: format!(
                            "{}, replica {seed}: {e}; its {d} row is left out",
                            runs[i].spec
                        ),
                    });
                }
            }
            runs[i].replicas.push(replica);
            if seed == plan.first_seed && plan.video {
                let denoisers: Vec<Denoiser> = runs[i].denoised.iter().map(|(d, _)| *d).collect();
                runs[i].denoised_trajectory = denoisers
                    .into_iter()
                    .map(|d| {
                        let every =
                            denoise::denoise_every_frame(d, &plan.backend, &guides, &trajectory);
                        (d, every.map_err(|e| e.to_string()))
                    })
                    .collect();
                runs[i].trajectory = trajectory;
            }
            progress.step();
        }
    }
    progress.end();
    Ok(Renders {
        runs,
        denoise_errors,
    })
}

impl MethodRuns {
    /// Keeps the first `n` replicas, raw and denoised.
    fn truncate(&mut self, n: usize) {
        self.replicas.truncate(n);
        for (_, denoised) in &mut self.denoised {
            denoised.truncate(n);
        }
        if n == 0 {
            self.trajectory.clear();
            self.denoised_trajectory.clear();
        }
    }
}

/// `replica`'s last frame through `denoiser`, from the frames of its `trajectory` (the last
/// frames of the trajectory that `guides` guide), with the denoiser's seconds per frame (a
/// temporal filter's time over every frame it filtered, per frame).
fn denoise_replica(
    denoiser: Denoiser,
    backend: &Backend,
    guides: &[Guide],
    trajectory: &[engine::Image],
    replica: &Replica,
) -> Result<Replica, DenoiseError> {
    let d = denoise::denoise(denoiser, backend, guides, trajectory)?;
    let per_frame = if denoiser.temporal() {
        d.timing.per(trajectory.len() as u32)
    } else {
        d.timing
    };
    Ok(Replica {
        frames: vec![d.image],
        denoiser_seconds_per_frame: per_frame.seconds,
        ..replica.clone()
    })
}

/// Replica `seed` of `method` at `frames`, and the whole trajectory (which a temporal
/// denoiser reads). Every frame of the trajectory is rendered and timed, by a memoryless
/// method too (each frame on its own, the last one the image a single render returns), so
/// that every method's time per frame is its mean over the same frames of the camera's path.
fn render_replica(
    plan: &Comparison,
    method: &Method,
    frames: &[u32],
    seed: u64,
) -> Result<(Replica, Vec<engine::Image>), Error> {
    let (trajectory, timing) =
        method.render_trajectory_on(&plan.backend, &plan.scene, plan.frames, seed)?;
    let images = (0..)
        .zip(&trajectory.frames)
        .filter_map(|(f, image)| frames.contains(&f).then(|| image.clone()))
        .collect();
    let replica = Replica {
        frames: images,
        seconds_per_frame: timing.seconds,
        wall_seconds_per_frame: timing.wall_seconds,
        denoiser_seconds_per_frame: 0.0,
        frames_rendered: trajectory.frames_rendered,
        nonfinite: trajectory.nonfinite,
        spp: trajectory
            .counts
            .as_ref()
            .map_or(method.spp() as f64, SampleCounts::mean),
    };
    Ok((replica, trajectory.frames))
}

/// Seconds per sample per pixel of the path tracer on this scene and backend, on the clock its
/// replicas are timed with: the median of 3 trajectories of `frames` frames at 4 spp.
fn calibrate_pt(backend: &Backend, scene: &Scene, frames: u32) -> Result<f64, Error> {
    let pt = Method::new(Pt { spp: 4 });
    let mut times = Vec::new();
    for seed in 0..3 {
        let (_, timing) = pt.render_trajectory_on(backend, scene, frames, 1_000_000 + seed)?;
        times.push(timing.seconds / 4.0);
    }
    times.sort_by(f64::total_cmp);
    Ok(times[1])
}

/// Equal time: `method` at the spp that fits `budget` seconds per frame, from its measured
/// `seconds_per_spp` (at least 1 spp); methods of fixed cost are returned unchanged.
pub fn equal_time_method(method: &Method, budget: f64, seconds_per_spp: f64) -> Method {
    if seconds_per_spp > 0.0 && budget.is_finite() {
        let spp = (budget / seconds_per_spp).round().clamp(1.0, 1e6) as u32;
        method.with_spp(spp)
    } else {
        method.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenes::with_resolution;

    #[test]
    fn equal_time_scales_the_spp_of_a_path_tracer() {
        let pt = Method::parse("pt").unwrap();
        assert_eq!(
            equal_time_method(&pt, 0.1, 0.02),
            Method::parse("pt:5").unwrap()
        );
        assert_eq!(equal_time_method(&pt, 0.001, 0.02), pt, "at least 1 spp");
        let hybrid = Method::parse("restir:hybrid").unwrap();
        assert_eq!(equal_time_method(&hybrid, 0.1, 0.02), hybrid);
    }

    /// A replica whose last frame holds a NaN is not denoised: one line naming the frame and
    /// the count, and its seconds are left alone.
    #[test]
    fn a_nan_frame_is_refused_by_every_denoiser() {
        let scene = with_resolution(Scene::builtin("bumpy").unwrap(), Some((8, 6)));
        let guides = Guide::trajectory(&scene, 2);
        let mut frames = vec![engine::Image::black(8, 6); 2];
        frames[1].pixels[5].y = f32::NAN;
        let replica = Replica {
            frames: vec![frames[1].clone()],
            seconds_per_frame: 0.5,
            wall_seconds_per_frame: 0.5,
            denoiser_seconds_per_frame: 0.0,
            frames_rendered: 2,
            nonfinite: 1,
            spp: 1.0,
        };
        for d in Denoiser::ALL {
            let e = denoise_replica(d, &Backend::Cpu, &guides, &frames, &replica).unwrap_err();
            assert_eq!(
                e.to_string(),
                "frame 1: 1 pixel(s) with a NaN or infinite value, not denoised"
            );
        }
    }
}
