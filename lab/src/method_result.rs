//! One method's row group of a comparison: its metrics per area over its replicas' final
//! frames against the reference.

use sss::integrator::Reference;

use crate::methods::Rendered;
use crate::metrics::{AreaMetrics, area_metrics, tonemapped_mse};
use crate::regions::Regions;

#[derive(Clone, Debug, PartialEq)]
pub struct MethodResult {
    /// The method as requested (`pt`, `restir:hybrid`).
    pub method: String,
    /// Samples per pixel per frame actually used (after equal-time calibration); for a method
    /// that chooses counts per pixel, the most a pixel may take.
    pub spp: u32,
    /// Mean over replicas of the mean samples per pixel of the final frame
    /// ([`Rendered::spp`]): `spp` unless the method chooses counts per pixel (`adaptive`).
    pub mean_spp: f64,
    pub replicas: usize,
    /// Mean over replicas.
    pub seconds_per_frame: f64,
    pub frames_rendered: u32,
    pub metrics: Vec<AreaMetrics>,
    /// Seed 001's metric over whole frames, mean over replicas ([`tonemapped_mse`]).
    pub tonemapped_mse: f64,
    pub nonfinite: u64,
}

impl MethodResult {
    /// The row group of `method` from its replicas' final frames; `None` when there is no
    /// replica or a size disagrees with the reference.
    pub fn from_replicas(
        method: &str,
        spp: u32,
        replicas: &[Rendered],
        reference: &Reference,
        regions: &Regions,
    ) -> Option<MethodResult> {
        let images: Vec<_> = replicas.iter().map(|r| r.image.clone()).collect();
        let mean = reference.mean();
        let metrics = area_metrics(&images, &mean, &reference.std_err(), regions)?;
        let k = replicas.len() as f64;
        let tonemapped = images
            .iter()
            .map(|i| tonemapped_mse(i, &mean))
            .sum::<Option<f64>>()?;
        Some(MethodResult {
            method: method.to_string(),
            spp,
            mean_spp: replicas.iter().map(|r| r.spp).sum::<f64>() / k,
            replicas: replicas.len(),
            seconds_per_frame: replicas.iter().map(|r| r.seconds_per_frame).sum::<f64>() / k,
            frames_rendered: replicas
                .iter()
                .map(|r| r.frames_rendered)
                .max()
                .unwrap_or(0),
            metrics,
            tonemapped_mse: tonemapped / k,
            nonfinite: replicas.iter().map(|r| r.nonfinite).sum(),
        })
    }
}
