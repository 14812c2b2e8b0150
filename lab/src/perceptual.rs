//! How the field judges an image beyond its MSE, per area over replicas: FLIP, NVIDIA's
//! perceptual difference of the tonemapped frames ([`crate::flip`]), and the low-frequency
//! error, the energy of the error after a Gaussian blur ([`crate::low_frequency`]) — the
//! "blotches and discontinuities" a denoiser leaves where it smooths noise into patches
//! [001 §6]. Both are means over the area's pixels of replica k's map, then means over
//! replicas with their 95% intervals ([`crate::uncertainty`]); the low-frequency error has the
//! blurred reference's noise subtracted (as [`crate::metrics`] does for the MSE).

use engine::Image;

use crate::flip::{area_mean, flip_map};
use crate::low_frequency::{SIGMA_PIXELS, low_frequency_error};
use crate::metrics::Area;
use crate::reference_cache::FrameReference;
use crate::regions::Regions;
use crate::uncertainty::Estimate;

/// FLIP and the low-frequency error of one method in one area.
#[derive(Clone, Debug, PartialEq)]
pub struct PerceptualMetrics {
    pub area: Area,
    /// Mean LDR-FLIP over the area's pixels, over replicas.
    pub flip: Estimate,
    /// Mean squared error after a Gaussian blur of [`SIGMA_PIXELS`], the blurred reference's
    /// noise subtracted, over replicas.
    pub low_frequency: Estimate,
}

/// The per-replica maps of one image: FLIP and the low-frequency error per pixel.
pub struct Maps {
    pub flip: Vec<f32>,
    pub low_frequency: Vec<f64>,
}

impl Maps {
    /// The maps of `image` against `reference`; `None` on a size mismatch.
    pub fn new(image: &Image, reference: &FrameReference) -> Option<Maps> {
        Some(Maps {
            flip: flip_map(image, &reference.mean)?,
            low_frequency: low_frequency_error(
                image,
                &reference.mean,
                &reference.std_err,
                SIGMA_PIXELS,
            )?,
        })
    }
}

/// FLIP and the low-frequency error of `replicas` (one frame each, indexed by seed) in every
/// non-empty area of `regions`; `None` on a size mismatch or without replicas.
pub fn perceptual_metrics(
    replicas: &[&Image],
    reference: &FrameReference,
    regions: &Regions,
) -> Option<Vec<PerceptualMetrics>> {
    if replicas.is_empty() {
        return None;
    }
    let maps: Vec<Maps> = replicas
        .iter()
        .map(|image| Maps::new(image, reference))
        .collect::<Option<_>>()?;
    let metrics = Area::non_empty(regions)
        .map(|(area, pixels)| {
            let flip: Vec<f64> = maps.iter().map(|m| area_mean(&m.flip, &pixels)).collect();
            let low: Vec<f64> = maps
                .iter()
                .map(|m| {
                    pixels.iter().map(|&p| m.low_frequency[p]).sum::<f64>() / pixels.len() as f64
                })
                .collect();
            PerceptualMetrics {
                area,
                flip: Estimate::mean(&flip),
                low_frequency: Estimate::mean(&low),
            }
        })
        .collect();
    Some(metrics)
}
