//! The reduction of a bias test's images to region means: per region and [`Channel`], the
//! summary over replicas (or reference batches) of the region's mean.

use glam::DVec3;
use restir::stats::Summary;

use super::Channel;
use crate::regions::{Region, Regions};

/// Mean of `values` over the pixels of `region`; `None` when the region is empty or `values`
/// does not cover the classified image.
pub fn region_mean(values: &[DVec3], regions: &Regions, region: Region) -> Option<DVec3> {
    if values.len() != regions.len() {
        return None;
    }
    mean_over(values, &regions.pixels(region))
}

/// Mean of `values` at `pixels` (all in range); `None` for no pixels.
fn mean_over(values: &[DVec3], pixels: &[usize]) -> Option<DVec3> {
    (!pixels.is_empty())
        .then(|| pixels.iter().map(|&p| values[p]).sum::<DVec3>() / pixels.len() as f64)
}

/// One region's replica summaries, one per [`Channel`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RegionSummary {
    pub region: Region,
    pub pixels: usize,
    /// Over independent images (replicas or reference batches) of the region's mean, in the
    /// order of [`Channel::ALL`].
    pub channels: [Summary; 4],
}

impl RegionSummary {
    /// The summary of `channel`.
    pub fn channel(&self, channel: Channel) -> &Summary {
        &self.channels[channel as usize]
    }
}

/// Per non-empty region, its pixel count and the region's mean in every image (one `Vec` per
/// replica or batch, row-major like `regions`); an image of the wrong size gives a NaN mean.
pub(super) fn region_means(
    images: &[Vec<DVec3>],
    regions: &Regions,
) -> Vec<(Region, usize, Vec<DVec3>)> {
    Region::VISIBILITY
        .into_iter()
        .filter_map(|region| {
            let pixels = regions.pixels(region);
            let means = images
                .iter()
                .map(|image| {
                    let covers = image.len() == regions.len();
                    covers
                        .then(|| mean_over(image, &pixels))
                        .flatten()
                        .unwrap_or(DVec3::NAN)
                })
                .collect();
            (!pixels.is_empty()).then_some((region, pixels.len(), means))
        })
        .collect()
}

/// The summary of one channel of per-image region means.
pub(super) fn channel_summary(means: &[DVec3], channel: Channel) -> Summary {
    let values: Vec<f64> = means.iter().map(|&m| channel.of(m)).collect();
    Summary::from_samples(&values)
}

/// Per-region summaries of independent per-pixel RGB images (one `Vec` per replica or batch,
/// row-major like `regions`); empty regions are left out. An image of the wrong size counts as
/// a NaN replica, which the tests reject as a defect.
pub fn summarize(images: &[Vec<DVec3>], regions: &Regions) -> Vec<RegionSummary> {
    summaries(region_means(images, regions))
}

/// Per region, the summaries of its per-image means ([`region_means`]), in their order.
pub(super) fn summaries(means: Vec<(Region, usize, Vec<DVec3>)>) -> Vec<RegionSummary> {
    means
        .into_iter()
        .map(|(region, pixels, means)| RegionSummary {
            region,
            pixels,
            channels: Channel::ALL.map(|c| channel_summary(&means, c)),
        })
        .collect()
}
