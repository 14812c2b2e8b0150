//! Error metrics of K replicas of a method against a reference (DESIGN §7 `compare`).
//!
//! Per area A (the whole frame, or a region of [`crate::regions`]), with replica images `I_k`
//! (linear RGB, the final frame) and the reference mean `R` (`f64`), over the pixels `p ∈ A` and
//! the three channels `c`:
//!
//! * `mse` = mean_k mean_{p,c} (I_k − R)²;
//! * `rel_mse` = mean_k mean_{p,c} (I_k − R)² / (R² + ε), ε = [`REL_EPSILON`];
//! * `bias` = mean_k b_k, `b_k` = mean_p Y(I_k) − mean_p Y(R) (Y: Rec. 709 luminance), with the
//!   half-width of its 99% Student-t CI over the K replicas (the replica, not the pixel, is the
//!   unit of independence: reuse correlates pixels);
//! * `variance` = mean_{p,c} of the per-pixel sample variance over replicas;
//! * `reference_mse` = mean_{p,c} s.e.(R)²: the part of `mse` that is the reference's own noise.
//!
//! Seed 001's own metric is [`tonemapped_mse`]: the MSE of Reinhard-tonemapped 8-bit sRGB frames
//! (values /255), over whole frames.

use glam::DVec3;
use restir::stats::{Summary, student_t_quantile};

use crate::bias::luminance;
use crate::regions::{Region, Regions};
use engine::image::{Image, tonemap};

/// ε in the denominator of the relative MSE, in squared radiance units: `(I − R)² / (R² + ε)`
/// weighs errors of pixels darker than √ε = 0.1 as absolute errors.
pub const REL_EPSILON: f64 = 1e-2;

/// Confidence of the bias interval.
pub const BIAS_CONFIDENCE: f64 = 0.99;

/// Where a metric is measured.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Area {
    /// Every pixel of the frame.
    Image,
    Region(Region),
}

impl Area {
    /// The whole frame, then the regions in table order.
    pub const ALL: [Area; 5] = [
        Area::Image,
        Area::Region(Region::Translucent),
        Area::Region(Region::Lit),
        Area::Region(Region::Penumbra),
        Area::Region(Region::Shadowed),
    ];

    pub fn name(self) -> &'static str {
        match self {
            Area::Image => "image",
            Area::Region(r) => r.name(),
        }
    }

    /// The pixels of this area, ascending.
    pub fn pixels(self, regions: &Regions) -> Vec<usize> {
        match self {
            Area::Image => (0..regions.len()).collect(),
            Area::Region(r) => regions.pixels(r),
        }
    }
}

/// The metrics of one method in one area.
#[derive(Clone, Debug, PartialEq)]
pub struct AreaMetrics {
    pub area: Area,
    pub pixels: usize,
    pub replicas: usize,
    pub mse: f64,
    /// Half-width of the [`BIAS_CONFIDENCE`] Student-t CI of `mse` over the replicas' MSEs;
    /// `None` with fewer than 2 replicas.
    pub mse_ci: Option<f64>,
    pub rel_mse: f64,
    /// Mean luminance of the reference over the area.
    pub reference_mean: f64,
    pub bias: f64,
    /// Half-width of the [`BIAS_CONFIDENCE`] CI of `bias`; `None` with fewer than 2 replicas.
    pub bias_ci: Option<f64>,
    /// `None` with fewer than 2 replicas.
    pub variance: Option<f64>,
    pub reference_mse: f64,
}

/// Metrics of `replicas` (final frames, all of the reference's size) in every non-empty area.
/// `reference` and `reference_std_err` are per pixel, row-major like `regions`. `None` when the
/// sizes disagree or there is no replica.
pub fn area_metrics(
    replicas: &[Image],
    reference: &[DVec3],
    reference_std_err: &[DVec3],
    regions: &Regions,
) -> Option<Vec<AreaMetrics>> {
    let n = regions.len();
    let sizes_agree = reference.len() == n
        && reference_std_err.len() == n
        && replicas.iter().all(|i| i.pixels.len() == n);
    if !sizes_agree || replicas.is_empty() {
        return None;
    }
    let k = replicas.len();
    let metrics = Area::ALL
        .into_iter()
        .filter_map(|area| {
            let pixels = area.pixels(regions);
            if pixels.is_empty() {
                return None;
            }
            let count = pixels.len() as f64;
            let channels = 3.0 * count;
            let reference_mean = pixels
                .iter()
                .map(|&p| luminance(reference[p].as_vec3()))
                .sum::<f64>()
                / count;
            let (mut mses, mut rel_mse, mut biases) =
                (Vec::with_capacity(k), 0.0, Vec::with_capacity(k));
            for image in replicas {
                let (mut se, mut rel, mut y) = (0.0, 0.0, 0.0);
                for &p in &pixels {
                    let (x, r) = (image.pixels[p].as_dvec3(), reference[p]);
                    let d2 = (x - r) * (x - r);
                    se += d2.element_sum();
                    rel += (d2 / (r * r + DVec3::splat(REL_EPSILON))).element_sum();
                    y += luminance(image.pixels[p]);
                }
                mses.push(se / channels);
                rel_mse += rel / channels;
                biases.push(y / count - reference_mean);
            }
            let (mse, bias) = (Summary::from_samples(&mses), Summary::from_samples(&biases));
            let t = student_t_quantile(0.5 + 0.5 * BIAS_CONFIDENCE, (k - 1) as f64);
            let bias_ci = (k >= 2).then_some(t * bias.std_err);
            let mse_ci = (k >= 2).then_some(t * mse.std_err);
            let variance = (k >= 2).then(|| pixel_variance(replicas, &pixels) / channels);
            let reference_mse = pixels
                .iter()
                .map(|&p| (reference_std_err[p] * reference_std_err[p]).element_sum())
                .sum::<f64>()
                / channels;
            Some(AreaMetrics {
                area,
                pixels: pixels.len(),
                replicas: k,
                mse: mse.mean,
                mse_ci,
                rel_mse: rel_mse / k as f64,
                reference_mean,
                bias: bias.mean,
                bias_ci,
                variance,
                reference_mse,
            })
        })
        .collect();
    Some(metrics)
}

/// Σ over `pixels` and channels of the sample variance over replicas (needs ≥ 2 replicas).
fn pixel_variance(replicas: &[Image], pixels: &[usize]) -> f64 {
    let k = replicas.len() as f64;
    pixels
        .iter()
        .map(|&p| {
            let mean = replicas
                .iter()
                .map(|i| i.pixels[p].as_dvec3())
                .sum::<DVec3>()
                / k;
            let ss: DVec3 = replicas
                .iter()
                .map(|i| {
                    let d = i.pixels[p].as_dvec3() - mean;
                    d * d
                })
                .sum();
            (ss / (k - 1.0)).element_sum()
        })
        .sum()
}

/// Efficiency `1 / (MSE · seconds per frame)`; `None` when the product is not positive and
/// finite (an exact estimator, or a zero timing).
pub fn efficiency(mse: f64, seconds_per_frame: f64) -> Option<f64> {
    let cost = mse * seconds_per_frame;
    (cost.is_finite() && cost > 0.0).then(|| 1.0 / cost)
}

/// Seed 001's metric: MSE between the Reinhard-tonemapped 8-bit sRGB frames of `image` and
/// `reference` ([`tonemap`]), values scaled to [0, 1], over every pixel and channel; RMSE is its
/// square root. `None` when the sizes differ or the image is empty.
pub fn tonemapped_mse(image: &Image, reference: &[DVec3]) -> Option<f64> {
    if image.pixels.len() != reference.len() || reference.is_empty() {
        return None;
    }
    let sum: f64 = image
        .pixels
        .iter()
        .zip(reference)
        .map(|(&x, r)| {
            let (a, b) = (tonemap(x), tonemap(r.as_vec3()));
            (0..3)
                .map(|c| ((a[c] as f64 - b[c] as f64) / 255.0).powi(2))
                .sum::<f64>()
        })
        .sum();
    Some(sum / (3 * reference.len()) as f64)
}

/// Per-pixel luminance of `|I − R|` (absolute) and `|I − R| / (R + √ε)` (relative, with the
/// same ε as [`REL_EPSILON`]): the error maps of `compare`.
pub fn error_maps(image: &Image, reference: &[DVec3]) -> Option<(Vec<f64>, Vec<f64>)> {
    if image.pixels.len() != reference.len() {
        return None;
    }
    let floor = REL_EPSILON.sqrt();
    Some(
        image
            .pixels
            .iter()
            .zip(reference)
            .map(|(&x, &r)| {
                let abs = luminance((x.as_dvec3() - r).abs().as_vec3());
                (abs, abs / (luminance(r.as_vec3()) + floor))
            })
            .unzip(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::regions::VISIBILITY_SAMPLES;
    use glam::Vec3;
    use restir::rng::StreamKey;

    /// 4 × 2: top row lit, bottom row shadowed.
    fn regions() -> Regions {
        let visible = (0..8)
            .map(|p| Some(if p < 4 { VISIBILITY_SAMPLES } else { 0 }))
            .collect();
        Regions::from_visible_samples(4, 2, visible).expect("consistent")
    }

    fn image(pixels: Vec<Vec3>) -> Image {
        Image {
            width: 4,
            height: 2,
            pixels,
        }
    }

    /// Hand-computed values: a constant reference of 1 and two replicas at 1 ± 0.5 give MSE
    /// 0.25, relMSE 0.25/1.01, zero bias and a per-pixel variance of 0.5 (sample variance of
    /// {0.5, 1.5}); a replica shifted by +0.5 in the shadowed row only is biased there by
    /// exactly 0.5 (the negative control) and not in the lit row.
    #[test]
    fn metrics_match_hand_computed_values() {
        let regions = regions();
        let reference = vec![DVec3::ONE; 8];
        let std_err = vec![DVec3::splat(0.1); 8];
        let pair = [
            image(vec![Vec3::splat(0.5); 8]),
            image(vec![Vec3::splat(1.5); 8]),
        ];
        let m = area_metrics(&pair, &reference, &std_err, &regions).unwrap();
        assert_eq!(
            m.len(),
            4,
            "image, translucent, lit, shadowed (no penumbra)"
        );
        for a in &m {
            assert!((a.mse - 0.25).abs() < 1e-12, "{a:?}");
            assert!((a.rel_mse - 0.25 / 1.01).abs() < 1e-12, "{a:?}");
            assert!(a.bias.abs() < 1e-12, "{a:?}");
            assert!((a.variance.unwrap() - 0.5).abs() < 1e-12, "{a:?}");
            assert!((a.reference_mse - 0.01).abs() < 1e-12, "{a:?}");
            assert_eq!(a.mse_ci, Some(0.0), "both replicas have MSE 0.25: {a:?}");
        }
        // Replica MSEs {0.25, 0}: mean 0.125, s.e. 0.125, CI half-width t(0.995, 1) · 0.125.
        let unequal = [
            image(vec![Vec3::splat(0.5); 8]),
            image(vec![Vec3::splat(1.0); 8]),
        ];
        let m = area_metrics(&unequal, &reference, &std_err, &regions).unwrap();
        let t = student_t_quantile(0.5 + 0.5 * BIAS_CONFIDENCE, 1.0);
        assert!((m[0].mse - 0.125).abs() < 1e-12, "{:?}", m[0]);
        assert!(
            (m[0].mse_ci.unwrap() - t * 0.125).abs() < 1e-9,
            "{:?}",
            m[0]
        );
        let shifted: Vec<Vec3> = (0..8)
            .map(|p| Vec3::splat(if p < 4 { 1.0 } else { 1.5 }))
            .collect();
        let m = area_metrics(&[image(shifted)], &reference, &std_err, &regions).unwrap();
        let get = |r| m.iter().find(|a| a.area == Area::Region(r)).unwrap();
        assert!((get(Region::Shadowed).bias - 0.5).abs() < 1e-6);
        assert!(get(Region::Lit).bias.abs() < 1e-12);
        assert_eq!(get(Region::Lit).bias_ci, None, "one replica has no CI");
        assert_eq!(get(Region::Lit).mse_ci, None, "one replica has no CI");
        assert!(area_metrics(&pair, &reference[1..], &std_err, &regions).is_none());
    }

    /// The 99% CI covers a zero bias for unbiased noise and excludes it for a +5% offset
    /// (negative control). N = 64 replicas of i.i.d. uniform noise of half-width 0.2 around the
    /// reference (fixed seed), so s.e. ≈ 0.115/8 ≈ 0.014 and the CI half-width ≈ 0.038.
    #[test]
    fn bias_interval_covers_zero_only_without_offset() {
        let regions = regions();
        let reference = vec![DVec3::ONE; 8];
        let std_err = vec![DVec3::ZERO; 8];
        let mut stream = StreamKey::new(0, 0, 0x4D45, 0).stream(11);
        let mut replicas = |offset: f32| -> Vec<Image> {
            (0..64)
                .map(|_| {
                    let v = 1.0 + offset + 0.4 * (stream.next_f32() - 0.5);
                    image(vec![Vec3::splat(v); 8])
                })
                .collect()
        };
        let unbiased = area_metrics(&replicas(0.0), &reference, &std_err, &regions).unwrap();
        let offset = area_metrics(&replicas(0.05), &reference, &std_err, &regions).unwrap();
        let (u, o) = (&unbiased[0], &offset[0]);
        let (cu, co) = (u.bias_ci.unwrap(), o.bias_ci.unwrap());
        assert!(u.bias.abs() < cu, "unbiased: {} ± {cu}", u.bias);
        assert!(o.bias - co > 0.0, "offset +0.05: {} ± {co}", o.bias);
    }

    #[test]
    fn tonemapped_mse_and_efficiency_guard_edge_cases() {
        let reference = vec![DVec3::ONE; 8];
        assert_eq!(
            tonemapped_mse(&image(vec![Vec3::ONE; 8]), &reference),
            Some(0.0)
        );
        // tonemap(1) = 188, tonemap(0) = 0 → ((188 − 0)/255)².
        let black = tonemapped_mse(&image(vec![Vec3::ZERO; 8]), &reference).unwrap();
        assert!((black - (188.0f64 / 255.0).powi(2)).abs() < 1e-12);
        assert_eq!(tonemapped_mse(&image(vec![Vec3::ONE; 8]), &[]), None);
        assert_eq!(efficiency(0.0, 1.0), None);
        assert_eq!(efficiency(0.5, 0.25), Some(8.0));
    }
}
