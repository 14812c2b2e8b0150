//! What the ground-truth experiment measures per method and region, from K replicas of the
//! method and the B batches of the ground truth (all final frames of one scene):
//!
//! * **model error**: the relative difference of the region's mean luminance, method against
//!   ground truth, `(Ȳ_m − Ȳ_gt) / Ȳ_gt`, with its [`CONFIDENCE`] CI
//!   `± t · √(se_m² + se_gt²) / Ȳ_gt` (Welch–Satterthwaite degrees of freedom; replicas and
//!   batches are the units of independence). Unlike the delta method of
//!   `restir::stats::equivalence`, whose ground-truth term is scaled by `Ȳ_m`, the ground truth's
//!   own noise stays in the interval when the method's region is dark (`Ȳ_m ≈ 0`);
//! * **noise**: the method's MSE against its own converged image (its expectation), estimated
//!   without rendering that image: the mean over the region's pixels and the RGB channels of
//!   the per-pixel sample variance over the K replicas (unbiased for K ≥ 2), with a delete-one
//!   jackknife CI over the replicas (K ≥ 3);
//! * **cost**: wall-clock seconds per rendered frame, mean and standard error over the replicas;
//! * **equal-time efficiency relative to the random walk**: `(noise · seconds)_walk /
//!   (noise · seconds)_method`, the factor by which the method's noise is lower at equal time;
//!   its CI combines the four relative standard errors on the log scale (delta method).

use engine::Image;
use restir::stats::{Summary, student_t_quantile, welch};

use lab::regions::{Region, Regions};
use sss::color::luminance;

/// Confidence of every interval of the experiment.
pub const CONFIDENCE: f64 = 0.99;

/// A value and the half-width of its [`CONFIDENCE`] interval (`NaN`: no interval).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interval {
    pub value: f64,
    pub half: f64,
}

/// A relative difference and its [`CONFIDENCE`] interval `[low, high]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Relative {
    pub value: f64,
    pub low: f64,
    pub high: f64,
}

impl Relative {
    /// `(estimate − truth) / truth` (module doc); `NaN`s for a non-positive truth.
    pub fn of(estimate: &Summary, truth: &Summary) -> Relative {
        let r = truth.mean;
        if !(r > 0.0) {
            let nan = f64::NAN;
            return Relative {
                value: nan,
                low: nan,
                high: nan,
            };
        }
        let value = (estimate.mean - r) / r;
        let se = (estimate.std_err.powi(2) + truth.std_err.powi(2)).sqrt() / r;
        let t = student_t_quantile(0.5 + 0.5 * CONFIDENCE, welch(estimate, truth).dof);
        Relative {
            value,
            low: value - t * se,
            high: value + t * se,
        }
    }

    /// Whether the interval excludes 0: a model error detected at level 1 − [`CONFIDENCE`].
    pub fn is_detected(&self) -> bool {
        self.low > 0.0 || self.high < 0.0
    }
}

/// One method in one region.
#[derive(Clone, Debug, PartialEq)]
pub struct RegionMeasure {
    pub region: Region,
    pub pixels: usize,
    /// Region mean luminance of the ground truth, over its batches.
    pub truth: Summary,
    /// Region mean luminance of the method, over its replicas.
    pub estimate: Summary,
    pub model_error: Relative,
    /// Mean per-pixel RGB variance over replicas (linear HDR), jackknife CI.
    pub noise: Interval,
}

/// One method on one scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Measure {
    pub method: String,
    pub replicas: usize,
    /// Seconds per rendered frame over the replicas.
    pub seconds: Summary,
    pub regions: Vec<RegionMeasure>,
    /// Non-finite estimates over all replicas (counted by the method, left out or written as 0).
    pub nonfinite: u64,
}

impl Measure {
    /// The measures of `replicas` (with their `seconds` per frame) against the ground truth's
    /// `batches`, in every non-empty region; `None` when an image is not of `regions`' size.
    pub fn new(
        method: &str,
        replicas: &[Image],
        seconds: &[f64],
        batches: &[Image],
        regions: &Regions,
    ) -> Option<Measure> {
        let sized = |i: &Image| i.pixels.len() == regions.len();
        if !(replicas.iter().all(sized) && batches.iter().all(sized)) {
            return None;
        }
        let luminance_of = |images: &[Image]| -> Vec<Vec<f64>> {
            images
                .iter()
                .map(|i| i.pixels.iter().map(|&p| luminance(p.as_dvec3())).collect())
                .collect()
        };
        let (estimates, truths) = (luminance_of(replicas), luminance_of(batches));
        let measures = Region::ALL
            .into_iter()
            .filter_map(|region| {
                let pixels = regions.pixels(region);
                if pixels.is_empty() {
                    return None;
                }
                let region_means = |images: &[Vec<f64>]| {
                    let means: Vec<f64> = images
                        .iter()
                        .map(|y| pixels.iter().map(|&p| y[p]).sum::<f64>() / pixels.len() as f64)
                        .collect();
                    Summary::from_samples(&means)
                };
                let (estimate, truth) = (region_means(&estimates), region_means(&truths));
                Some(RegionMeasure {
                    region,
                    pixels: pixels.len(),
                    model_error: Relative::of(&estimate, &truth),
                    estimate,
                    truth,
                    noise: noise(replicas, &pixels),
                })
            })
            .collect();
        Some(Measure {
            method: method.to_string(),
            replicas: replicas.len(),
            seconds: Summary::from_samples(seconds),
            regions: measures,
            nonfinite: 0,
        })
    }

    pub fn region(&self, region: Region) -> Option<&RegionMeasure> {
        self.regions.iter().find(|r| r.region == region)
    }

    /// `(noise · seconds)_walk / (noise · seconds)_self` in `region` with its CI `[low, high]`
    /// (module doc); `None` where either has no noise or time.
    pub fn efficiency_relative_to(&self, walk: &Measure, region: Region) -> Option<[f64; 3]> {
        let (own, theirs) = (self.region(region)?, walk.region(region)?);
        let cost = |m: &Measure, r: &RegionMeasure| {
            let product = r.noise.value * m.seconds.mean;
            (product.is_finite() && product > 0.0).then_some(product)
        };
        let ratio = cost(walk, theirs)? / cost(self, own)?;
        // Relative standard errors: the noise's from its half-width, the time's from its s.e.
        let relative = |m: &Measure, r: &RegionMeasure| {
            let t = student_t_quantile(0.5 + 0.5 * CONFIDENCE, (m.replicas - 1) as f64);
            [
                r.noise.half / t / r.noise.value,
                m.seconds.std_err / m.seconds.mean,
            ]
        };
        let variance: f64 = relative(self, own)
            .into_iter()
            .chain(relative(walk, theirs))
            .map(|x| x * x)
            .sum();
        let dof = (self.replicas.min(walk.replicas) - 1) as f64;
        let half = student_t_quantile(0.5 + 0.5 * CONFIDENCE, dof) * variance.sqrt();
        Some([ratio, ratio * (-half).exp(), ratio * half.exp()])
    }
}

/// Mean over `pixels` and RGB of the per-pixel sample variance over `replicas`, with the
/// half-width of its delete-one jackknife interval (Student-t, K − 1 degrees of freedom);
/// `NaN` without enough replicas (value: K < 2, interval: K < 3).
pub fn noise(replicas: &[Image], pixels: &[usize]) -> Interval {
    let k = replicas.len();
    if k < 2 || pixels.is_empty() {
        return Interval {
            value: f64::NAN,
            half: f64::NAN,
        };
    }
    let kf = k as f64;
    let count = (3 * pixels.len()) as f64;
    // Per replica i, Σ_{p,c} of the squared deviation d_i² from the pixel mean, and Σ SS.
    let mut deviations = vec![0.0f64; k];
    let mut total = 0.0f64;
    for &p in pixels {
        for c in 0..3 {
            let values = replicas.iter().map(|r| r.pixels[p][c] as f64);
            let mean = values.clone().sum::<f64>() / kf;
            for (i, v) in values.enumerate() {
                let d2 = (v - mean) * (v - mean);
                deviations[i] += d2;
                total += d2;
            }
        }
    }
    let value = total / (kf - 1.0) / count;
    if k < 3 {
        return Interval {
            value,
            half: f64::NAN,
        };
    }
    // Without replica i: SS_(i) = SS − K/(K − 1) d_i², variance SS_(i) / (K − 2).
    let leave_one_out: Vec<f64> = deviations
        .iter()
        .map(|d| (total - kf / (kf - 1.0) * d) / (kf - 2.0) / count)
        .collect();
    let mean = leave_one_out.iter().sum::<f64>() / kf;
    let spread: f64 = leave_one_out.iter().map(|v| (v - mean) * (v - mean)).sum();
    let std_err = ((kf - 1.0) / kf * spread).sqrt();
    Interval {
        value,
        half: student_t_quantile(0.5 + 0.5 * CONFIDENCE, kf - 1.0) * std_err,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;
    use restir::rng::StreamKey;

    fn normal(s: &mut restir::rng::Stream) -> f64 {
        let radius = (-2.0 * (1.0 - s.next_f64()).ln()).sqrt();
        radius * (std::f64::consts::TAU * s.next_f64()).cos()
    }

    /// Images of `pixels` pixels, each channel `mean + sigma · N(0, 1)`, from `seed`.
    fn images(n: usize, pixels: usize, mean: f64, sigma: f64, seed: u64) -> Vec<Image> {
        let mut s = StreamKey::new(0, 0, 0x6774, 0).stream(seed);
        (0..n)
            .map(|_| Image {
                width: pixels as u32,
                height: 1,
                pixels: (0..pixels)
                    .map(|_| {
                        Vec3::from_array(std::array::from_fn(|_| {
                            (mean + sigma * normal(&mut s)) as f32
                        }))
                    })
                    .collect(),
            })
            .collect()
    }

    /// The delete-one formula equals recomputing the variance without each replica.
    #[test]
    fn jackknife_matches_recomputation() {
        let replicas = images(5, 7, 1.0, 0.3, 1);
        let pixels: Vec<usize> = (0..7).collect();
        let full = noise(&replicas, &pixels);
        let direct: Vec<f64> = (0..5)
            .map(|i| {
                let rest: Vec<Image> = replicas
                    .iter()
                    .enumerate()
                    .filter(|(j, _)| *j != i)
                    .map(|(_, r)| r.clone())
                    .collect();
                noise(&rest, &pixels).value
            })
            .collect();
        let mean = direct.iter().sum::<f64>() / 5.0;
        let se = (0.8 * direct.iter().map(|v| (v - mean).powi(2)).sum::<f64>()).sqrt();
        let t = student_t_quantile(0.995, 4.0);
        assert!(
            (full.half - t * se).abs() < 1e-9 * full.half,
            "{full:?} vs {}",
            t * se
        );
        assert!(noise(&replicas[..2], &pixels).half.is_nan());
        assert!(noise(&replicas[..1], &pixels).value.is_nan());
    }

    /// Calibration of the noise interval: σ² = 0.09 known; over 200 independent experiments of
    /// K = 8 replicas × 40 pixels × 3 channels, the 99% interval must cover σ² in ≥ 95% of them
    /// (a jackknife interval is approximate; the binomial s.d. of the count at 99% is 1.4, so 95%
    /// leaves 6 s.d. for its approximation), and it must not be wide to get there: its mean
    /// half-width is within ±40% of `t₇ · σ² √(2 / (7 · 120))`, the exact standard error of the
    /// pooled variance. Negative control: a fifth of the width covers in fewer than 70%.
    #[test]
    fn noise_interval_covers_the_variance() {
        let pixels: Vec<usize> = (0..40).collect();
        let (mut covered, mut narrow, mut half) = (0, 0, 0.0);
        for seed in 0..200 {
            let n = noise(&images(8, 40, 2.0, 0.3, seed), &pixels);
            covered += ((n.value - 0.09).abs() <= n.half) as u32;
            narrow += ((n.value - 0.09).abs() <= 0.2 * n.half) as u32;
            half += n.half / 200.0;
        }
        let exact = student_t_quantile(0.995, 7.0) * 0.09 * (2.0f64 / (7.0 * 120.0)).sqrt();
        eprintln!("covered {covered}/200, control {narrow}/200, half {half:.4} vs {exact:.4}");
        assert!(covered >= 190, "covered {covered}/200");
        assert!(
            (half / exact - 1.0).abs() < 0.4,
            "half-width {half} vs {exact}"
        );
        assert!(
            narrow < 140,
            "control: a fifth of the width covered {narrow}/200"
        );
    }

    /// Coverage of the model-error interval: 300 experiments of K = 8 replica means ~ N(1.1,
    /// 0.05²) against B = 16 batch means ~ N(1, 0.2²) (standard errors 1.8% and 5%); the 99%
    /// interval must contain +10% in ≥ 96% of them (binomial s.d. at 99%: 0.6%; the ratio's
    /// noisy denominator costs about 1%). Negative control: without the ground truth's term the
    /// interval (Student-t with the replicas' 7 dof) covers in < 85% (≈ 71% expected). A dark
    /// method (every replica 0) keeps the ground truth's noise in its interval.
    #[test]
    fn model_error_interval_covers() {
        let mut s = StreamKey::new(0, 0, 0x6775, 0).stream(5);
        let (mut covered, mut without) = (0, 0);
        for _ in 0..300 {
            let mut draw = |n: usize, mean: f64, sd: f64| {
                let xs: Vec<f64> = (0..n).map(|_| mean + sd * normal(&mut s)).collect();
                Summary::from_samples(&xs)
            };
            let (estimate, truth) = (draw(8, 1.1, 0.05), draw(16, 1.0, 0.2));
            let e = Relative::of(&estimate, &truth);
            covered += (e.low <= 0.1 && 0.1 <= e.high) as u32;
            let exact = Summary {
                std_err: 0.0,
                ..truth
            };
            let narrow = Relative::of(&estimate, &exact);
            without += (narrow.low <= 0.1 && 0.1 <= narrow.high) as u32;
        }
        eprintln!("covered {covered}/300, control {without}/300");
        assert!(covered >= 288, "covered {covered}/300");
        assert!(without < 255, "control covered {without}/300");
        let dark = Relative::of(
            &Summary::from_samples(&[0.0; 8]),
            &Summary::from_samples(&[0.9, 1.1, 1.0, 1.0]),
        );
        assert_eq!(dark.value, -1.0);
        assert!(dark.low < -1.05 && dark.high > -0.95, "{dark:?}");
        assert!(
            Relative::of(&dark_summary(), &Summary::exact(0.0))
                .value
                .is_nan()
        );
    }

    fn dark_summary() -> Summary {
        Summary::from_samples(&[0.0; 3])
    }

    /// A method with the walk's noise at half its time is twice as efficient; one with the
    /// same numbers has ratio 1 inside its interval. Model errors: +10% is measured as such.
    #[test]
    fn efficiency_and_model_error() {
        let regions =
            Regions::from_visible_samples(40, 1, vec![Some(lab::regions::VISIBILITY_SAMPLES); 40])
                .unwrap();
        let truth = images(16, 40, 1.0, 0.3, 100);
        let walk = Measure::new(
            "walk",
            &images(8, 40, 1.0, 0.3, 1),
            &[2.0; 8],
            &truth,
            &regions,
        )
        .unwrap();
        let fast = Measure::new(
            "fast",
            &images(8, 40, 1.1, 0.3, 2),
            &[1.0; 8],
            &truth,
            &regions,
        )
        .unwrap();
        let e = fast.efficiency_relative_to(&walk, Region::Lit).unwrap();
        assert!(
            e[1] < e[0] && e[0] < e[2] && e[1] < 2.0 && 2.0 < e[2],
            "{e:?}"
        );
        let same = walk.efficiency_relative_to(&walk, Region::Lit).unwrap();
        assert_eq!(same[0], 1.0);
        let m = &fast.region(Region::Lit).unwrap().model_error;
        assert!(m.low < 0.1 && 0.1 < m.high && m.low > 0.0, "{m:?}");
        assert!(fast.region(Region::Shadowed).is_none());
        assert!(
            Measure::new(
                "bad",
                &images(2, 39, 1.0, 0.3, 3),
                &[1.0; 2],
                &truth,
                &regions
            )
            .is_none()
        );
    }
}
