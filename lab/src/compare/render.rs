//! Rendering a comparison's replicas: every method's replicas (seeds `0..K`), each one's frames
//! at the measured frames and its last frame through each denoiser, with an equal-time budget
//! first calibrated on the bare path tracer ([`equal_time_method`]).

use engine::Backend;
use engine::denoise::{self, DenoiseError, Denoiser, Guide};
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
}

/// What [`render_replicas`] rendered.
pub(super) struct Renders {
    pub(super) runs: Vec<MethodRuns>,
    pub(super) denoise_errors: Vec<String>,
}

/// The replicas of every method, in order, each with its images at `frames` (ascending, the
/// last frame last) and its last frame through each denoiser of the plan; after a stop request
/// the list ends with the method that was rendering, with the replicas it finished. A denoiser
/// that fails on a replica leaves that method's denoised row out with one line in
/// `denoise_errors`; one that is not installed is left out of every method with one line.
pub(super) fn render_replicas(
    plan: &Comparison,
    frames: &[u32],
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
    let whole_trajectory = plan.denoise.iter().any(|d| d.temporal());
    let mut denoisers = plan.denoise.clone();
    let mut denoise_errors = Vec::new();
    // Untimed warm-up: loading a library, creating a device or compiling kernels is not the
    // per-frame cost a renderer pays.
    if let Some(guide) = guides.last() {
        let black = engine::Image::black(guide.width, guide.height);
        for &d in &plan.denoise {
            let _ = denoise::denoise(d, &plan.backend, &guides, std::slice::from_ref(&black));
        }
    }
    progress.begin(
        "replicas",
        plan.methods.len() as u64 * plan.replicas as u64,
        0,
    );
    let mut runs = Vec::new();
    'methods: for (spec, method) in &plan.methods {
        // `pt:N` pins its spp; a bare `pt` is scaled to the budget.
        let method = match plan.equal_time {
            Some(b) if spec == EQUAL_TIME_SPEC => equal_time_method(method, b, seconds_per_spp),
            _ => method.clone(),
        };
        progress.item(&method.name());
        let mut run = MethodRuns {
            spec: spec.clone(),
            method: method.clone(),
            replicas: Vec::new(),
            denoised: denoisers.iter().map(|&d| (d, Vec::new())).collect(),
        };
        for seed in 0..plan.replicas as u64 {
            if progress.stop_requested() {
                runs.push(run);
                break 'methods;
            }
            let (replica, trajectory) =
                render_replica(plan, &method, frames, seed, whole_trajectory)?;
            let mut failed = Vec::new();
            for (d, denoised) in &mut run.denoised {
                match denoise_replica(*d, &plan.backend, &guides, &trajectory, &replica) {
                    Ok(r) => denoised.push(r),
                    Err(e) => failed.push((*d, e)),
                }
            }
            for (d, e) in failed {
                run.denoised.retain(|(x, _)| *x != d);
                if matches!(e, DenoiseError::Unavailable(_)) {
                    denoisers.retain(|x| *x != d);
                    denoise_errors.push(format!("{d}: {e}; its rows are left out"));
                } else {
                    denoise_errors.push(format!(
                        "{spec}, replica {seed}: {e}; its {d} row is left out"
                    ));
                }
            }
            run.replicas.push(replica);
            progress.step();
        }
        runs.push(run);
    }
    progress.end();
    Ok(Renders {
        runs,
        denoise_errors,
    })
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
        d.seconds / trajectory.len() as f64
    } else {
        d.seconds
    };
    Ok(Replica {
        frames: vec![d.image],
        denoiser_seconds_per_frame: per_frame,
        ..replica.clone()
    })
}

/// Replica `seed` of `method` at `frames`, and the frames a denoiser reads: the whole
/// trajectory when earlier frames are measured or `whole_trajectory` is asked for (a temporal
/// denoiser), else only the last frame (which a memoryless method renders alone).
fn render_replica(
    plan: &Comparison,
    method: &Method,
    frames: &[u32],
    seed: u64,
    whole_trajectory: bool,
) -> Result<(Replica, Vec<engine::Image>), Error> {
    let (backend, scene) = (&plan.backend, &plan.scene);
    if frames.len() == 1 && !whole_trajectory {
        let r = method.render_on(backend, scene, plan.frames, seed)?;
        let replica = Replica {
            frames: vec![r.image.clone()],
            seconds_per_frame: r.seconds_per_frame,
            denoiser_seconds_per_frame: 0.0,
            frames_rendered: r.frames_rendered,
            nonfinite: r.nonfinite,
            spp: r.spp,
        };
        return Ok((replica, vec![r.image]));
    }
    let (trajectory, seconds_per_frame) =
        method.render_trajectory_on(backend, scene, plan.frames, seed)?;
    let images = (0..)
        .zip(&trajectory.frames)
        .filter_map(|(f, image)| frames.contains(&f).then(|| image.clone()))
        .collect();
    let replica = Replica {
        frames: images,
        seconds_per_frame,
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

/// Seconds per sample per pixel of the path tracer on this scene (median of 3 runs at 4 spp).
fn calibrate_pt(backend: &Backend, scene: &Scene, frames: u32) -> Result<f64, Error> {
    let pt = Method::new(Pt { spp: 4 });
    let mut times = Vec::new();
    for seed in 0..3 {
        times.push(
            pt.render_on(backend, scene, frames, 1_000_000 + seed)?
                .seconds_per_frame
                / 4.0,
        );
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
