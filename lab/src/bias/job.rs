//! The pieces every form of the bias test shares (the fixed design of `run`, the budgeted
//! design of `budgeted`, the shards of `shard`): the tested frame's regions ([`Setup`]), the
//! reference batches, the replicas' final frames, and the outcome from the rows.

use std::ops::Range;

use engine::Backend;
use glam::DVec3;
use rayon::prelude::*;
use sss::integrator::pt::PtSettings;
use sss::scene::GBuffer;

use super::outcome::{
    BiasOutcome, NonFinite, PLANNED_POWER, Planned, ReferenceEntry, SCHEMA, SequentialEntry,
};
use super::plan::{BiasPlan, ReferenceBatches};
use super::{BiasRow, Images, overall, replicas_needed};
use crate::error::Error;
use crate::progress::Progress;
use crate::reference_cache::REFERENCE_SEED;
use crate::regions::Regions;

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

/// The reference batches of `plan` at the tested frame, with the method's reference settings:
/// those given in the plan when they are the ones it would render ([`ReferenceBatches::render`]).
pub(super) fn reference(plan: &BiasPlan) -> Result<Images, Error> {
    match &plan.reference {
        Some(given) => {
            given.check(plan)?;
            Ok(given.images.clone())
        }
        None => Ok(ReferenceBatches::render(plan)?.images),
    }
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
        first_seed: plan.first_seed,
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
fn render_replica(plan: &BiasPlan, seed: u64) -> Result<(Vec<DVec3>, u64), Error> {
    let rendered = plan
        .method
        .render_on(&plan.backend, &plan.scene, plan.frames, seed)?;
    let rgb = rendered.image.pixels.iter().map(|p| p.as_dvec3()).collect();
    Ok((rgb, rendered.nonfinite))
}

/// Replicas rendered at once: on the CPU a chunk of them runs in parallel (each is a function of
/// its seed, so the images do not depend on the chunking; a small image parallelises poorly
/// within one replica), two per worker thread; a Vulkan device renders one at a time.
pub(super) fn chunk(plan: &BiasPlan) -> u64 {
    match plan.backend {
        Backend::Cpu => 2 * rayon::current_num_threads() as u64,
        Backend::Vulkan(_) => 1,
    }
}

/// The final frames of the replicas of `seeds` in seed order, [`chunk`] at a time, until a stop
/// request (checked between chunks); one progress step each.
pub(super) fn render_replicas(
    plan: &BiasPlan,
    seeds: Range<u64>,
    progress: &mut dyn Progress,
) -> Result<Images, Error> {
    let mut images = Images {
        rgb: Vec::new(),
        nonfinite: 0,
    };
    let mut next = seeds.start;
    while next < seeds.end && !progress.stop_requested() {
        let end = seeds.end.min(next + chunk(plan));
        for (rgb, nonfinite) in render_chunk(plan, next..end)? {
            images.nonfinite += nonfinite;
            images.rgb.push(rgb);
            progress.step();
        }
        next = end;
    }
    Ok(images)
}

/// The final frames of the replicas of `seeds`, in seed order (in parallel on the CPU).
pub(super) fn render_chunk(
    plan: &BiasPlan,
    seeds: Range<u64>,
) -> Result<Vec<(Vec<DVec3>, u64)>, Error> {
    match plan.backend {
        Backend::Cpu => seeds
            .into_par_iter()
            .map(|seed| render_replica(plan, seed))
            .collect(),
        Backend::Vulkan(_) => seeds.map(|seed| render_replica(plan, seed)).collect(),
    }
}
