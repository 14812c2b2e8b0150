//! The images a bias test compares: the final frame of every replica of a preset and of every
//! independent path-traced reference batch at the same frame.

use std::ops::Range;

use engine::{Backend, PipelineError, RunConfig};
use glam::DVec3;
use rayon::prelude::*;
use shifts::preset::Preset;
use sss::InputError;
use sss::integrator::pt::{self, PtSettings};
use sss::scene::{GBuffer, Scene};

/// Per-pixel linear RGB images of independent runs, and how many of their values were not
/// finite (the pipeline writes those as 0 and the path tracer leaves them out of its means: a
/// bias either way, which a test must not hide).
#[derive(Clone, Debug, PartialEq)]
pub struct Images {
    pub rgb: Vec<Vec<DVec3>>,
    pub nonfinite: u64,
}

/// Bytes per pixel one replica keeps until the test: its linear RGB image.
const REPLICA_BYTES_PER_PIXEL: u64 = size_of::<DVec3>() as u64;
/// Bytes per pixel one reference batch holds: its path-traced RGB image.
const BATCH_BYTES_PER_PIXEL: u64 = size_of::<DVec3>() as u64;

/// Bytes a bias test at `pixels` holds: every replica's image, every reference batch and one
/// run of `frames` frames (`engine::limits::run_bytes`); `None` on overflow.
pub fn test_bytes(pixels: u64, replicas: u32, batches: u32, frames: u32) -> Option<u64> {
    let kept = (replicas as u64 * REPLICA_BYTES_PER_PIXEL)
        .checked_add(batches as u64 * BATCH_BYTES_PER_PIXEL)?
        .checked_mul(pixels)?;
    kept.checked_add(engine::limits::run_bytes(pixels, frames)?)
}

/// The final frame (`frames − 1`) of replicas `0..replicas` of `preset` on `backend`; replica `i`
/// runs with seed `i`. On the CPU replicas run in parallel; a Vulkan backend runs them one after
/// another on its device. Each is a function of its seed alone.
pub fn replica_images(
    backend: &Backend,
    scene: &Scene,
    preset: &Preset,
    replicas: u64,
    frames: u32,
) -> Result<Images, PipelineError> {
    let replica = |seed| {
        let config = RunConfig {
            seed,
            frames,
            collect_diagnostics: false,
        };
        let mut result = backend.run(scene, preset, &config)?;
        let last = result.frames.pop().ok_or_else(|| {
            PipelineError::Config(format!("run with frames = {frames} returned no frame"))
        })?;
        Ok((
            last.pixels.iter().map(|p| p.as_dvec3()).collect(),
            result.nan_count,
        ))
    };
    let runs: Vec<(Vec<DVec3>, u64)> = match backend {
        Backend::Cpu => (0..replicas)
            .into_par_iter()
            .map(replica)
            .collect::<Result<_, PipelineError>>()?,
        Backend::Vulkan(_) => (0..replicas)
            .map(replica)
            .collect::<Result<_, PipelineError>>()?,
    };
    Ok(Images {
        nonfinite: runs.iter().map(|r| r.1).sum(),
        rgb: runs.into_iter().map(|r| r.0).collect(),
    })
}

/// The reference: `batches` independent batches of the path tracer (`sss::integrator::pt`, all
/// hits per probe) at `frame`, `spp_per_batch` samples each; batch `b` is samples
/// `b·spp_per_batch ..` under `seed`, so choose a seed no replica uses. Input errors: fewer than
/// two batches (no standard error), no samples per batch, more than 2³² samples per pixel (the
/// sample index is a `u32`).
pub fn reference_images(
    scene: &Scene,
    frame: u32,
    batches: u32,
    spp_per_batch: u32,
    seed: u64,
) -> Result<Images, InputError> {
    let settings = PtSettings::default();
    reference_images_with(&settings, scene, frame, batches, spp_per_batch, seed)
}

/// [`reference_images`] of the path tracer with `settings`: a method's own reference
/// (`methods::Method::reference`, e.g. the dipole profile of `image-space`).
pub fn reference_images_with(
    settings: &PtSettings,
    scene: &Scene,
    frame: u32,
    batches: u32,
    spp_per_batch: u32,
    seed: u64,
) -> Result<Images, InputError> {
    let bad = |field: &str, value: String, reason: &str| {
        Err(InputError::new("(bias reference)", field, value, reason))
    };
    if batches < 2 {
        return bad(
            "batches",
            batches.to_string(),
            "need ≥ 2 for a standard error",
        );
    }
    reference_batches(settings, scene, frame, 0..batches, spp_per_batch, seed)
}

/// Batches `batches` of the reference of [`reference_images_with`] (batch `b` is samples
/// `b·spp_per_batch ..` under `seed`), so that a reference can grow batch by batch. Input
/// errors: no samples per batch, more than 2³² samples per pixel.
pub fn reference_batches(
    settings: &PtSettings,
    scene: &Scene,
    frame: u32,
    batches: Range<u32>,
    spp_per_batch: u32,
    seed: u64,
) -> Result<Images, InputError> {
    let bad = |field: &str, value: String, reason: &str| {
        Err(InputError::new("(bias reference)", field, value, reason))
    };
    if spp_per_batch == 0 {
        return bad("spp_per_batch", "0".into(), "must be ≥ 1");
    }
    if batches.end as u64 * spp_per_batch as u64 > 1 << 32 {
        let value = format!("{} × {spp_per_batch}", batches.end);
        return bad(
            "batches",
            value,
            "batches × spp_per_batch must not exceed 2³² samples per pixel",
        );
    }
    let scene = &*scene.at_frame(frame);
    let gbuffer = GBuffer::render(scene, frame);
    let images: Vec<pt::SampleMeans> = batches
        .map(|b| {
            pt::render(
                scene,
                &gbuffer,
                settings,
                seed,
                b * spp_per_batch,
                spp_per_batch,
            )
        })
        .collect();
    Ok(Images {
        nonfinite: images.iter().map(|i| i.nonfinite).sum(),
        rgb: images.into_iter().map(|i| i.pixels).collect(),
    })
}
