//! Error metrics of K replicas of a method against a reference (DESIGN §7 `compare`).
//!
//! Per area A (the whole frame, or a region of [`crate::regions`]), with replica images `I_k`
//! (linear RGB, one frame) and the reference mean `R̂` (`f64`) with per-pixel standard error `s`
//! from `n_b` independent batches, over the pixels `p ∈ A` and the three channels `c`
//! (`N = 3·|A|` values):
//!
//! * `e_k` = mean_{p,c} (I_k − R̂)², replica k's squared error;
//! * `reference_mse` `r` = mean_{p,c} s²: the reference's own variance. `I_k` and `R̂` are
//!   independent and `R̂` is unbiased, so `E[(I − R̂)²] = E[(I − R)²] + Var(R̂)` and
//!   `mse` = mean_k e_k − r estimates the error against the true image;
//! * `rel_mse` likewise with weights `w = 1 / (R̂² + ε)`, ε = [`REL_EPSILON`] (the weights are
//!   taken as fixed);
//! * the 95% intervals of `mse` and `rel_mse` ([`crate::uncertainty`]) add to the spread over
//!   replicas the variance of what the replicas share, the reference:
//!   `v_ref = N⁻² Σ_p [(Σ_c κ w s²)² + 4 (Σ_c w |Ī − R̂| s)²]`, κ = √(2 n_b / (n_b − 1)): the
//!   fluctuation of `(R̂ − R)² − s²` (variance 2σ⁴ for normal batch means, plus that of `s²`
//!   from `n_b` batches) and of the cross term `2 (Ī − R)(R − R̂)`; channels of a pixel are
//!   summed in standard deviations (a bound for any correlation), pixels are independent;
//! * `bias` = mean_k b_k, `b_k` = mean_p Y(I_k) − mean_p Y(R̂) (Y: Rec. 709 luminance), with the
//!   half-width of its 99% Student-t CI over the K replicas (the replica, not the pixel, is the
//!   unit of independence: reuse correlates pixels);
//! * `variance` = mean_{p,c} of the per-pixel sample variance over replicas.
//!
//! Paper 001's own metric is [`tonemapped_mse`]: the MSE of Reinhard-tonemapped 8-bit sRGB frames
//! (values /255), over whole frames.

use glam::DVec3;
use restir::stats::{Summary, student_t_quantile};

use crate::reference_cache::FrameReference;
use crate::regions::{Region, Regions};
use crate::uncertainty::Estimate;
use engine::image::{Image, tonemap};
use sss::color::luminance;

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
    pub const ALL: [Area; 6] = [
        Area::Image,
        Area::Region(Region::Translucent),
        Area::Region(Region::Lit),
        Area::Region(Region::Penumbra),
        Area::Region(Region::Shadowed),
        Area::Region(Region::Disoccluded),
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

    /// Every area of [`Area::ALL`] that has pixels in `regions`, with its pixels.
    pub fn non_empty(regions: &Regions) -> impl Iterator<Item = (Area, Vec<usize>)> + '_ {
        Area::ALL
            .into_iter()
            .map(|area| (area, area.pixels(regions)))
            .filter(|(_, pixels)| !pixels.is_empty())
    }
}

/// The metrics of one method in one area.
#[derive(Clone, Debug, PartialEq)]
pub struct AreaMetrics {
    pub area: Area,
    pub pixels: usize,
    pub replicas: usize,
    /// MSE with the reference's variance subtracted, over replicas.
    pub mse: Estimate,
    /// Relative MSE with the reference's relative variance subtracted, over replicas.
    pub rel_mse: Estimate,
    /// Mean luminance of the reference over the area.
    pub reference_mean: f64,
    pub bias: f64,
    /// Half-width of the [`BIAS_CONFIDENCE`] CI of `bias`; `None` with fewer than 2 replicas.
    pub bias_ci: Option<f64>,
    /// `None` with fewer than 2 replicas.
    pub variance: Option<f64>,
    /// The reference's variance `r`, subtracted from `mse`.
    pub reference_mse: f64,
}

/// Metrics of `replicas` (frames of the reference's size) in every non-empty area of `regions`.
/// `None` when the sizes disagree or there is no replica.
pub fn area_metrics(
    replicas: &[Image],
    reference: &FrameReference,
    regions: &Regions,
) -> Option<Vec<AreaMetrics>> {
    let n = regions.len();
    let sizes_agree = reference.mean.len() == n
        && reference.std_err.len() == n
        && replicas.iter().all(|i| i.pixels.len() == n);
    if !sizes_agree || replicas.is_empty() || reference.batches < 2 {
        return None;
    }
    let k = replicas.len();
    let r = &reference.mean;
    let metrics = Area::non_empty(regions)
        .map(|(area, pixels)| {
            let count = pixels.len() as f64;
            let reference_mean = pixels
                .iter()
                .map(|&p| luminance(r[p].as_vec3().as_dvec3()))
                .sum::<f64>()
                / count;
            let (mut squared, mut relative, mut biases) = (
                Vec::with_capacity(k),
                Vec::with_capacity(k),
                Vec::with_capacity(k),
            );
            for image in replicas {
                let (mut se, mut rel, mut y) = (0.0, 0.0, 0.0);
                for &p in &pixels {
                    let d = image.pixels[p].as_dvec3() - r[p];
                    se += (d * d).element_sum();
                    rel += (d * d * rel_weight(r[p])).element_sum();
                    y += luminance(image.pixels[p].as_dvec3());
                }
                squared.push(se / (3.0 * count));
                relative.push(rel / (3.0 * count));
                biases.push(y / count - reference_mean);
            }
            let mean_image = mean_over_replicas(replicas, &pixels);
            let noise = |weight: &dyn Fn(usize) -> DVec3| {
                reference_noise(reference, &pixels, &mean_image, weight)
            };
            let (reference_mse, v_abs) = noise(&|_| DVec3::ONE);
            let (reference_rel, v_rel) = noise(&|p| rel_weight(r[p]));
            let bias = Summary::from_samples(&biases);
            let t = student_t_quantile(0.5 + 0.5 * BIAS_CONFIDENCE, (k - 1) as f64);
            AreaMetrics {
                area,
                pixels: pixels.len(),
                replicas: k,
                mse: Estimate::mean(&squared).minus_constant(reference_mse, v_abs),
                rel_mse: Estimate::mean(&relative).minus_constant(reference_rel, v_rel),
                reference_mean,
                bias: bias.mean,
                bias_ci: (k >= 2).then_some(t * bias.std_err),
                variance: (k >= 2).then(|| pixel_variance(replicas, &pixels) / (3.0 * count)),
                reference_mse,
            }
        })
        .collect();
    Some(metrics)
}

/// The weight `1 / (R̂² + ε)` of the relative MSE per channel.
fn rel_weight(r: DVec3) -> DVec3 {
    DVec3::ONE / (r * r + DVec3::splat(REL_EPSILON))
}

/// `Ī` over replicas at each of `pixels`, in their order.
fn mean_over_replicas(replicas: &[Image], pixels: &[usize]) -> Vec<DVec3> {
    let k = replicas.len() as f64;
    pixels
        .iter()
        .map(|&p| {
            replicas
                .iter()
                .map(|i| i.pixels[p].as_dvec3())
                .sum::<DVec3>()
                / k
        })
        .collect()
}

/// `(r, v_ref)` of the module documentation over `pixels` with per-channel weights `weight(p)`:
/// the reference's weighted variance, subtracted from the MSE, and the variance of that
/// correction, added to the MSE interval's. `mean_image` is `Ī` at `pixels`.
fn reference_noise(
    reference: &FrameReference,
    pixels: &[usize],
    mean_image: &[DVec3],
    weight: &dyn Fn(usize) -> DVec3,
) -> (f64, f64) {
    let nb = reference.batches as f64;
    let kappa = (2.0 * nb / (nb - 1.0)).sqrt();
    let n = 3.0 * pixels.len() as f64;
    let (mut r, mut v) = (0.0, 0.0);
    for (&p, &mean) in pixels.iter().zip(mean_image) {
        let (s, w) = (reference.std_err[p], weight(p));
        let s2 = w * s * s;
        r += s2.element_sum();
        let cross = (w * (mean - reference.mean[p]).abs() * s).element_sum();
        v += (kappa * s2.element_sum()).powi(2) + 4.0 * cross * cross;
    }
    (r / n, v / (n * n))
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

/// Paper 001's metric: MSE between the Reinhard-tonemapped 8-bit sRGB frames of `image` and
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
                let abs = luminance((x.as_dvec3() - r).abs().as_vec3().as_dvec3());
                (abs, abs / (luminance(r.as_vec3().as_dvec3()) + floor))
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

    /// A reference of `mean` with standard error `std_err` per channel from `batches` batches.
    fn reference(mean: Vec<DVec3>, std_err: f64, batches: u32) -> FrameReference {
        FrameReference {
            frame: 0,
            std_err: vec![DVec3::splat(std_err); mean.len()],
            mean,
            batches,
            spp: batches as u64,
        }
    }

    /// Hand-computed values: a constant reference of 1 (standard error 0.1) and two replicas
    /// at 1 ± 0.5 give a squared error of 0.25 and so MSE 0.25 − 0.01, relMSE (0.25 − 0.01)/1.01,
    /// zero bias and a per-pixel variance of 0.5 (sample variance of {0.5, 1.5}); a replica
    /// shifted by +0.5 in the shadowed row only is biased there by exactly 0.5 (the negative
    /// control) and not in the lit row.
    #[test]
    fn metrics_match_hand_computed_values() {
        let regions = regions();
        let reference = reference(vec![DVec3::ONE; 8], 0.1, 4);
        let pair = [
            image(vec![Vec3::splat(0.5); 8]),
            image(vec![Vec3::splat(1.5); 8]),
        ];
        let m = area_metrics(&pair, &reference, &regions).unwrap();
        assert_eq!(
            m.len(),
            4,
            "image, translucent, lit, shadowed (no penumbra)"
        );
        for a in &m {
            assert!((a.mse.value - 0.24).abs() < 1e-12, "{a:?}");
            assert!((a.rel_mse.value - 0.24 / 1.01).abs() < 1e-12, "{a:?}");
            assert!(a.bias.abs() < 1e-12, "{a:?}");
            assert!((a.variance.unwrap() - 0.5).abs() < 1e-12, "{a:?}");
            assert!((a.reference_mse - 0.01).abs() < 1e-12, "{a:?}");
        }
        let shifted: Vec<Vec3> = (0..8)
            .map(|p| Vec3::splat(if p < 4 { 1.0 } else { 1.5 }))
            .collect();
        let m = area_metrics(&[image(shifted)], &reference, &regions).unwrap();
        let get = |r| m.iter().find(|a| a.area == Area::Region(r)).unwrap();
        assert!((get(Region::Shadowed).bias - 0.5).abs() < 1e-6);
        assert!(get(Region::Lit).bias.abs() < 1e-12);
        assert_eq!(get(Region::Lit).bias_ci, None, "one replica has no CI");
        let short = FrameReference {
            mean: vec![DVec3::ONE; 7],
            ..reference
        };
        assert!(area_metrics(&pair, &short, &regions).is_none());
    }

    /// The 99% CI covers a zero bias for unbiased noise and excludes it for a +5% offset
    /// (negative control). N = 64 replicas of i.i.d. uniform noise of half-width 0.2 around the
    /// reference (fixed seed), so s.e. ≈ 0.115/8 ≈ 0.014 and the CI half-width ≈ 0.038.
    #[test]
    fn bias_interval_covers_zero_only_without_offset() {
        let regions = regions();
        let reference = reference(vec![DVec3::ONE; 8], 0.0, 4);
        let mut stream = StreamKey::new(0, 0, 0x4D45, 0).stream(11);
        let mut replicas = |offset: f32| -> Vec<Image> {
            (0..64)
                .map(|_| {
                    let v = 1.0 + offset + 0.4 * (stream.next_f32() - 0.5);
                    image(vec![Vec3::splat(v); 8])
                })
                .collect()
        };
        let unbiased = area_metrics(&replicas(0.0), &reference, &regions).unwrap();
        let offset = area_metrics(&replicas(0.05), &reference, &regions).unwrap();
        let (u, o) = (&unbiased[0], &offset[0]);
        let (cu, co) = (u.bias_ci.unwrap(), o.bias_ci.unwrap());
        assert!(u.bias.abs() < cu, "unbiased: {} ± {cu}", u.bias);
        assert!(o.bias - co > 0.0, "offset +0.05: {} ± {co}", o.bias);
    }

    fn normal(s: &mut restir::rng::Stream) -> f64 {
        let radius = (-2.0 * (1.0 - s.next_f64()).ln()).sqrt();
        radius * (std::f64::consts::TAU * s.next_f64()).cos()
    }

    /// One synthetic comparison on a 20 × 20 frame whose true image is 1 everywhere (one
    /// region, every pixel lit): a reference from `NB` = 4 batch means of noise σ_b = 0.5 per
    /// channel (its standard error from their spread, as `sss::integrator::Reference` computes
    /// it), and K = 8 replicas of noise σ = 0.2, so the true MSE is σ² = 0.04 while the raw
    /// squared error averages 0.04 + σ_b²/NB = 0.1025. Returns the image-area metrics.
    fn noisy_reference_trial(s: &mut restir::rng::Stream) -> AreaMetrics {
        const NB: usize = 4;
        const SIDE: u32 = 20;
        let n = (SIDE * SIDE) as usize;
        let visible = vec![Some(VISIBILITY_SAMPLES); n];
        let regions = Regions::from_visible_samples(SIDE, SIDE, visible).unwrap();
        let (mut mean, mut std_err) = (Vec::new(), Vec::new());
        for _ in 0..n {
            let batches: Vec<DVec3> = (0..NB)
                .map(|_| DVec3::ONE + 0.5 * DVec3::new(normal(s), normal(s), normal(s)))
                .collect();
            let m = batches.iter().sum::<DVec3>() / NB as f64;
            let ss: DVec3 = batches.iter().map(|b| (*b - m) * (*b - m)).sum();
            mean.push(m);
            std_err.push((ss / ((NB - 1) * NB) as f64).map(f64::sqrt));
        }
        let reference = FrameReference {
            frame: 0,
            mean,
            std_err,
            batches: NB as u32,
            spp: NB as u64,
        };
        let replicas: Vec<Image> = (0..8)
            .map(|_| Image {
                width: SIDE,
                height: SIDE,
                pixels: (0..n)
                    .map(|_| {
                        let d = DVec3::new(normal(s), normal(s), normal(s));
                        (DVec3::ONE + 0.2 * d).as_vec3()
                    })
                    .collect(),
            })
            .collect();
        area_metrics(&replicas, &reference, &regions)
            .unwrap()
            .remove(0)
    }

    /// The reference's noise is subtracted and its uncertainty is in the interval. Claim: the
    /// 95% interval of the MSE covers the true MSE (0.04) with coverage ≥ 0.95 − δ, δ = 0.02,
    /// although the reference is noisier than the replicas' spread (α = 0.05). Decision: the
    /// covering count of N trials reaches the lower end of the 99.8% acceptance region of
    /// Binomial(N, 0.93). N = 600 from N ≥ ((z·√(0.93·0.07) + z·√(0.85·0.15)) / 0.08)² ≈ 560
    /// (z = 3.09): a procedure with coverage 0.85 passes with probability ≤ 0.001. Negative
    /// controls: the raw squared error (no subtraction) and the interval without the
    /// reference's variance (`v_ref`) must both fail the same decision.
    #[test]
    fn the_reference_noise_is_subtracted_and_bounds_the_interval() {
        const N: usize = 600;
        let (lo, _) = restir::stats::binomial_interval(N, 0.93, 0.998);
        let mut s = StreamKey::new(0, 0, 0x5245_464E, 0).stream(9);
        let (mut covered, mut raw, mut no_v_ref) = (0, 0, 0);
        for _ in 0..N {
            let m = noisy_reference_trial(&mut s);
            let i = m.mse.interval(0.95).unwrap();
            covered += (i.lo <= 0.04 && 0.04 <= i.hi) as usize;
            let shifted = (i.lo + m.reference_mse, i.hi + m.reference_mse);
            raw += (shifted.0 <= 0.04 && 0.04 <= shifted.1) as usize;
            let spread = Estimate::mean(m.mse.influences()).interval(0.95).unwrap();
            let centred = (spread.lo - m.reference_mse, spread.hi - m.reference_mse);
            no_v_ref += (centred.0 <= 0.04 && 0.04 <= centred.1) as usize;
        }
        assert!(covered >= lo, "coverage {covered}/{N} < {lo}");
        assert!(raw < lo, "raw squared error covered {raw}/{N}");
        assert!(
            no_v_ref < lo,
            "interval without v_ref covered {no_v_ref}/{N}"
        );
    }

    #[test]
    fn tonemapped_mse_guards_edge_cases() {
        let reference = vec![DVec3::ONE; 8];
        assert_eq!(
            tonemapped_mse(&image(vec![Vec3::ONE; 8]), &reference),
            Some(0.0)
        );
        // tonemap(1) = 188, tonemap(0) = 0 → ((188 − 0)/255)².
        let black = tonemapped_mse(&image(vec![Vec3::ZERO; 8]), &reference).unwrap();
        assert!((black - (188.0f64 / 255.0).powi(2)).abs() < 1e-12);
        assert_eq!(tonemapped_mse(&image(vec![Vec3::ONE; 8]), &[]), None);
    }
}
