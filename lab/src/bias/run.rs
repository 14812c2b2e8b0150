//! A bias test as a job ([`run`]): N replicas of one method against independent batches of the
//! path tracer with the method's reference settings, per region and channel; the job of
//! `reshift bias`.

use std::path::Path;

use engine::Backend;
use glam::DVec3;
use methods::Method;
use sss::InputError;
use sss::limits::{self, MAX_SPP};
use sss::scene::{GBuffer, Scene};

use super::outcome::{BiasOutcome, NonFinite, PLANNED_POWER, Planned, ReferenceEntry, SCHEMA};
use super::{Images, Protocol, bias_rows, overall, reference_images_with, replicas_needed};
use super::{summarize, test_bytes};
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
    let scene = &plan.scene;
    let frame = plan.frames - 1;
    let regions = Regions::classify(scene, &GBuffer::render(scene, frame), REFERENCE_SEED);
    let settings = plan.method.reference();
    let reference = reference_images_with(
        &settings,
        scene,
        frame,
        plan.reference_batches,
        plan.reference_batch_spp,
        REFERENCE_SEED,
    )?;
    let name = plan.method.name();
    progress.begin(&name, plan.replicas as u64, 0);
    let replicas = render_replicas(plan, progress);
    progress.end();
    let replicas = replicas?;
    if replicas.rgb.len() < 2 {
        return Err(Error::Interrupted(
            "interrupted before 2 replicas finished".into(),
        ));
    }
    let protocol = plan.protocol;
    let rows = bias_rows(
        &name,
        &summarize(&replicas.rgb, &regions),
        &summarize(&reference.rgb, &regions),
        &protocol,
    );
    Ok(BiasOutcome {
        schema: SCHEMA,
        scene: scene.name.clone(),
        method: plan.spec.clone(),
        resolution: format!("{}x{}", scene.camera.width(), scene.camera.height()),
        frames: plan.frames,
        replicas: replicas.rgb.len(),
        delta: protocol.delta,
        alpha: protocol.alpha,
        confidence: 1.0 - protocol.alpha,
        reference: ReferenceEntry {
            batches: plan.reference_batches,
            spp_per_batch: plan.reference_batch_spp,
            profile: settings.profile.name().to_string(),
            seed: REFERENCE_SEED,
        },
        nonfinite: NonFinite {
            replicas: replicas.nonfinite,
            reference: reference.nonfinite,
        },
        interrupted: replicas.rgb.len() < plan.replicas as usize,
        verdict: overall(&rows),
        planned: Planned {
            power: PLANNED_POWER,
            replicas: replicas_needed(&rows, &protocol, PLANNED_POWER),
        },
        rows,
    })
}

/// The final frames of replicas `0..plan.replicas` until a stop request, one step each.
fn render_replicas(plan: &BiasPlan, progress: &mut dyn Progress) -> Result<Images, Error> {
    let mut images = Images {
        rgb: Vec::new(),
        nonfinite: 0,
    };
    for seed in 0..plan.replicas as u64 {
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
