//! A bias test as a job ([`run`]): replicas of one method against independent batches of the
//! path tracer with the method's reference settings, per region and channel; the job of
//! `reshift bias`. A fixed number of replicas runs here ([`Replicas::Fixed`]); a budget runs the
//! group-sequential design of `budgeted` ([`Replicas::Budget`]).

use std::ops::Range;
use std::path::Path;
use std::time::Duration;

use engine::Backend;
use glam::DVec3;
use methods::Method;
use sss::InputError;
use sss::integrator::pt::PtSettings;
use sss::limits::{self, MAX_SPP};
use sss::scene::{GBuffer, Scene};

use super::outcome::{
    BiasOutcome, NonFinite, PLANNED_POWER, Planned, ReferenceEntry, SCHEMA, SequentialEntry,
};
use super::{
    BiasRow, Images, Protocol, bias_rows, overall, reference_images_with, replicas_needed,
};
use super::{budgeted, summarize, test_bytes};
use crate::error::Error;
use crate::limits::MAX_REPLICAS;
use crate::progress::Progress;
use crate::reference_cache::REFERENCE_SEED;
use crate::regions::Regions;

/// How many replicas a bias test runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Replicas {
    /// Exactly this many (seeds `0..n`), one test at level α (`--replicas`).
    Fixed(u32),
    /// As many as the group-sequential design needs and this much time (on the backend's
    /// clock, `engine::clock`) allows (`--budget`).
    Budget(Duration),
}

/// What to test, where, and how strictly. [`BiasPlan::validate`] names the fields by the
/// `reshift bias` options that set them one to one (`--replicas`, `--delta`, …).
pub struct BiasPlan {
    /// The scene with the camera at the test's resolution.
    pub scene: Scene,
    /// The method under test as requested (the outcome's `method`), and the method.
    pub spec: String,
    pub method: Method,
    /// Independent replicas (seeds `0..n`), fixed or within a budget.
    pub replicas: Replicas,
    /// Frames of the camera trajectory; the last one is tested.
    pub frames: u32,
    /// Tolerance δ and level α.
    pub protocol: Protocol,
    /// Independent path-traced reference batches, and the samples per pixel of each.
    pub reference_batches: u32,
    pub reference_batch_spp: u32,
    pub backend: Backend,
}

impl BiasPlan {
    /// The plan's values within range, as one line that names the option at fault (in `origin`):
    /// δ finite and > 0, 0 < α < 1; at least two replicas and two reference batches (for their
    /// standard errors), a budget > 0, every count within `sss::limits` and [`MAX_REPLICAS`],
    /// and the test within the memory budget ([`test_bytes`]; a budgeted test keeps region means
    /// only, so its replicas count as two).
    pub fn validate(&self, origin: &Path) -> Result<(), InputError> {
        let Protocol { delta, alpha } = self.protocol;
        if !(delta.is_finite() && delta > 0.0) {
            let reason = "the tolerance must be a finite number > 0";
            return Err(InputError::new(
                origin,
                "--delta",
                delta.to_string(),
                reason,
            ));
        }
        if !(alpha > 0.0 && alpha < 1.0) {
            let reason = "the level must be in (0, 1)";
            return Err(InputError::new(
                origin,
                "--alpha",
                alpha.to_string(),
                reason,
            ));
        }
        let count = |field: &str, n: u32, min: u32, max: u32| {
            limits::count(origin, field, n as u64, min as u64, max as u64)
        };
        let kept = match self.replicas {
            Replicas::Fixed(n) => {
                count("--replicas", n, 2, MAX_REPLICAS)?;
                n
            }
            Replicas::Budget(budget) => {
                if budget.is_zero() {
                    let reason = "the time budget must be > 0";
                    return Err(InputError::new(origin, "--budget", "0s", reason));
                }
                2
            }
        };
        count(
            "--reference-batches",
            self.reference_batches,
            2,
            MAX_REPLICAS,
        )?;
        count(
            "--reference-batch-spp",
            self.reference_batch_spp,
            1,
            MAX_SPP,
        )?;
        limits::frames(origin, "--frames", self.frames)?;
        let (width, height) = (self.scene.camera.width(), self.scene.camera.height());
        let value = format!(
            "{kept} replicas, {} reference batches, {} frames at {width}×{height}",
            self.reference_batches, self.frames
        );
        let pixels = width as u64 * height as u64;
        let needed = test_bytes(pixels, kept, self.reference_batches, self.frames);
        limits::memory(origin, "--replicas", &value, needed, "the bias test")
    }
}

/// Runs the bias test of `plan`, reporting to `progress` (one phase, the replicas, named after
/// the method). The regions and the reference are those of the last frame; replica `i` renders
/// with seed `i`, one after another. A stop request ends the replicas after the current one:
/// the outcome of those rendered ([`BiasOutcome::interrupted`]), or [`Error::Interrupted`]
/// before two.
pub fn run(plan: &BiasPlan, progress: &mut dyn Progress) -> Result<BiasOutcome, Error> {
    plan.validate(Path::new("(bias plan)"))?;
    match plan.replicas {
        Replicas::Fixed(n) => fixed(plan, n, progress),
        Replicas::Budget(budget) => budgeted::run(plan, budget, progress),
    }
}

/// The regions of the tested frame and the method's reference settings.
pub(super) struct Setup {
    pub regions: Regions,
    pub settings: PtSettings,
    pub frame: u32,
}

impl Setup {
    pub fn of(plan: &BiasPlan) -> Setup {
        let frame = plan.frames - 1;
        let gbuffer = GBuffer::render(&plan.scene, frame);
        Setup {
            regions: Regions::classify(&plan.scene, &gbuffer, REFERENCE_SEED),
            settings: plan.method.reference(),
            frame,
        }
    }
}

/// [`Replicas::Fixed`]: `n` replicas, one test of every row at level α.
fn fixed(plan: &BiasPlan, n: u32, progress: &mut dyn Progress) -> Result<BiasOutcome, Error> {
    let setup = Setup::of(plan);
    let reference = reference(plan, &setup)?;
    let name = plan.method.name();
    progress.begin(&name, n as u64, 0);
    let replicas = render_replicas(plan, 0..n as u64, progress);
    progress.end();
    let replicas = replicas?;
    if replicas.rgb.len() < 2 {
        return Err(Error::Interrupted(
            "interrupted before 2 replicas finished".into(),
        ));
    }
    let rows = bias_rows(
        &name,
        &summarize(&replicas.rgb, &setup.regions),
        &summarize(&reference.rgb, &setup.regions),
        &plan.protocol,
    );
    let counts = Counts {
        replicas: replicas.rgb.len(),
        reference_batches: plan.reference_batches,
        nonfinite: NonFinite {
            replicas: replicas.nonfinite,
            reference: reference.nonfinite,
        },
        interrupted: replicas.rgb.len() < n as usize,
    };
    Ok(outcome(plan, &setup, counts, rows, None))
}

/// The reference batches of `plan` at the tested frame, with the method's reference settings.
pub(super) fn reference(plan: &BiasPlan, setup: &Setup) -> Result<Images, Error> {
    Ok(reference_images_with(
        &setup.settings,
        &plan.scene,
        setup.frame,
        plan.reference_batches,
        plan.reference_batch_spp,
        REFERENCE_SEED,
    )?)
}

/// What a test rendered.
pub(super) struct Counts {
    pub replicas: usize,
    pub reference_batches: u32,
    pub nonfinite: NonFinite,
    pub interrupted: bool,
}

/// The outcome of `plan` with `rows` (the overall verdict and the plan of N from them).
pub(super) fn outcome(
    plan: &BiasPlan,
    setup: &Setup,
    counts: Counts,
    rows: Vec<BiasRow>,
    sequential: Option<SequentialEntry>,
) -> BiasOutcome {
    let scene = &plan.scene;
    let protocol = plan.protocol;
    BiasOutcome {
        schema: SCHEMA,
        scene: scene.name.clone(),
        method: plan.spec.clone(),
        resolution: format!("{}x{}", scene.camera.width(), scene.camera.height()),
        frames: plan.frames,
        replicas: counts.replicas,
        delta: protocol.delta,
        alpha: protocol.alpha,
        confidence: 1.0 - protocol.alpha,
        reference: ReferenceEntry {
            batches: counts.reference_batches,
            spp_per_batch: plan.reference_batch_spp,
            profile: setup.settings.profile.name().to_string(),
            seed: REFERENCE_SEED,
        },
        nonfinite: counts.nonfinite,
        interrupted: counts.interrupted,
        verdict: overall(&rows),
        planned: Planned {
            power: PLANNED_POWER,
            replicas: replicas_needed(&rows, &protocol, PLANNED_POWER),
        },
        rows,
        sequential,
    }
}

/// The final frame of replica `seed` as linear RGB, and its non-finite values.
pub(super) fn render_replica(plan: &BiasPlan, seed: u64) -> Result<(Vec<DVec3>, u64), Error> {
    let rendered = plan
        .method
        .render_on(&plan.backend, &plan.scene, plan.frames, seed)?;
    let rgb = rendered.image.pixels.iter().map(|p| p.as_dvec3()).collect();
    Ok((rgb, rendered.nonfinite))
}

/// The final frames of the replicas of `seeds` until a stop request, one step each.
pub(super) fn render_replicas(
    plan: &BiasPlan,
    seeds: Range<u64>,
    progress: &mut dyn Progress,
) -> Result<Images, Error> {
    let mut images = Images {
        rgb: Vec::new(),
        nonfinite: 0,
    };
    for seed in seeds {
        if progress.stop_requested() {
            break;
        }
        let (rgb, nonfinite) = render_replica(plan, seed)?;
        images.nonfinite += nonfinite;
        images.rgb.push(rgb);
        progress.step();
    }
    Ok(images)
}
