//! A bias test as a job ([`run`]): N replicas of one method against independent batches of the
//! path tracer with the method's reference settings, per region and channel; the job of
//! `reshift bias`.

use std::ops::Range;
use std::path::Path;

use engine::Backend;
use glam::DVec3;
use methods::Method;
use sss::InputError;
use sss::limits::{self, MAX_SPP};
use sss::scene::{GBuffer, Scene};

use super::outcome::{BiasOutcome, NonFinite, PLANNED_POWER, Planned, ReferenceEntry, SCHEMA};
use super::{Images, Protocol, bias_rows, overall, reference_images_with, replicas_needed};
use super::{RegionSummary, summarize, test_bytes};
use crate::error::Error;
use crate::limits::MAX_REPLICAS;
use crate::progress::Progress;
use crate::reference_cache::REFERENCE_SEED;
use crate::regions::Regions;

/// What to test, where, and how strictly. [`BiasPlan::validate`] names the fields by the
/// `reshift bias` options that set them one to one (`--replicas`, `--delta`, …).
pub struct BiasPlan {
    /// The scene with the camera at the test's resolution.
    pub scene: Scene,
    /// The method under test as requested (the outcome's `method`), and the method.
    pub spec: String,
    pub method: Method,
    /// Independent replicas (seeds `0..replicas`).
    pub replicas: u32,
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
    /// standard errors), every count within `sss::limits` and [`MAX_REPLICAS`], and the test
    /// within the memory budget ([`test_bytes`]).
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
        count("--replicas", self.replicas, 2, MAX_REPLICAS)?;
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
            "{} replicas, {} reference batches, {} frames at {width}×{height}",
            self.replicas, self.reference_batches, self.frames
        );
        let pixels = width as u64 * height as u64;
        let needed = test_bytes(pixels, self.replicas, self.reference_batches, self.frames);
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
    let regions = tested_regions(plan);
    let reference = reference(plan)?;
    let name = plan.method.name();
    progress.begin(&name, plan.replicas as u64, 0);
    let replicas = render_replicas(plan, 0..plan.replicas as u64, progress);
    progress.end();
    let replicas = replicas?;
    if replicas.rgb.len() < 2 {
        return Err(Error::Interrupted(
            "interrupted before 2 replicas finished".into(),
        ));
    }
    let tested = Tested {
        replicas: summarize(&replicas.rgb, &regions),
        count: replicas.rgb.len(),
        reference: summarize(&reference.rgb, &regions),
        nonfinite: NonFinite {
            replicas: replicas.nonfinite,
            reference: reference.nonfinite,
        },
    };
    Ok(outcome(plan, tested))
}

/// The regions of the tested frame, the last.
pub(super) fn tested_regions(plan: &BiasPlan) -> Regions {
    let scene = &plan.scene;
    Regions::classify(
        scene,
        &GBuffer::render(scene, plan.frames - 1),
        REFERENCE_SEED,
    )
}

/// The reference batches of `plan` at the tested frame, with the method's reference settings.
pub(super) fn reference(plan: &BiasPlan) -> Result<Images, Error> {
    Ok(reference_images_with(
        &plan.method.reference(),
        &plan.scene,
        plan.frames - 1,
        plan.reference_batches,
        plan.reference_batch_spp,
        REFERENCE_SEED,
    )?)
}

/// What a test measured: the region summaries of its `count` replicas and of its reference.
pub(super) struct Tested {
    pub(super) replicas: Vec<RegionSummary>,
    pub(super) count: usize,
    pub(super) reference: Vec<RegionSummary>,
    pub(super) nonfinite: NonFinite,
}

/// The outcome of `plan` from what it measured: the rows, their verdicts and the plan for
/// the next run; interrupted when fewer replicas than planned were measured.
pub(super) fn outcome(plan: &BiasPlan, tested: Tested) -> BiasOutcome {
    let scene = &plan.scene;
    let protocol = plan.protocol;
    let rows = bias_rows(
        &plan.method.name(),
        &tested.replicas,
        &tested.reference,
        &protocol,
    );
    BiasOutcome {
        schema: SCHEMA,
        scene: scene.name.clone(),
        method: plan.spec.clone(),
        resolution: format!("{}x{}", scene.camera.width(), scene.camera.height()),
        frames: plan.frames,
        replicas: tested.count,
        delta: protocol.delta,
        alpha: protocol.alpha,
        confidence: 1.0 - protocol.alpha,
        reference: ReferenceEntry {
            batches: plan.reference_batches,
            spp_per_batch: plan.reference_batch_spp,
            profile: plan.method.reference().profile.name().to_string(),
            seed: REFERENCE_SEED,
        },
        nonfinite: tested.nonfinite,
        interrupted: tested.count < plan.replicas as usize,
        verdict: overall(&rows),
        planned: Planned {
            power: PLANNED_POWER,
            replicas: replicas_needed(&rows, &protocol, PLANNED_POWER),
        },
        rows,
    }
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
        let rendered = plan
            .method
            .render_on(&plan.backend, &plan.scene, plan.frames, seed)?;
        images.nonfinite += rendered.nonfinite;
        let rgb: Vec<DVec3> = rendered.image.pixels.iter().map(|p| p.as_dvec3()).collect();
        images.rgb.push(rgb);
        progress.step();
    }
    Ok(images)
}
