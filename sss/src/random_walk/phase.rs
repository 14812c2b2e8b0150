//! Phase functions for the random walk: the [`PhaseFunction`] interface and Henyey–Greenstein.
//!
//! Directions are *propagation* directions: `cos θ = dir_in · dir_out`, so `g > 0` scatters
//! forward. `sample` returns the sampling density separately from the phase value, and the walk
//! multiplies its throughput by `value / pdf` (pbrt-v4 style), so a phase function whose sampler
//! is not exact stays unbiased as long as `pdf` is the density `sample` really draws from.

use std::f32::consts::{FRAC_1_PI, TAU};

use glam::Vec3;

/// `1/(4π)`: the isotropic phase function.
pub const ISOTROPIC: f32 = 0.25 * FRAC_1_PI;

use crate::contract::random_walk::SMALL_G;

/// A scattered direction with its phase value and the density it was drawn with (both per sr).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhaseSample {
    pub dir: Vec3,
    pub value: f32,
    pub pdf: f32,
}

/// A phase function `p(dir_in → dir_out)` over the sphere of propagation directions.
pub trait PhaseFunction {
    /// The phase function value (1/sr); integrates to 1 over `dir_out`.
    fn eval(&self, dir_in: Vec3, dir_out: Vec3) -> f32;
    /// Draws `dir_out` from two uniform numbers in [0, 1).
    fn sample(&self, dir_in: Vec3, u: [f32; 2]) -> PhaseSample;
    /// The solid-angle density with which [`PhaseFunction::sample`] draws `dir_out`.
    fn pdf(&self, dir_in: Vec3, dir_out: Vec3) -> f32;
}

/// The Henyey–Greenstein phase function with mean cosine `g ∈ (−1, 1)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HenyeyGreenstein {
    g: f32,
}

impl HenyeyGreenstein {
    /// `None` unless `−1 < g < 1` (the medium constructor turns that into an input error).
    pub fn new(g: f32) -> Option<HenyeyGreenstein> {
        (g > -1.0 && g < 1.0).then_some(HenyeyGreenstein { g })
    }

    pub fn g(&self) -> f32 {
        self.g
    }

    /// `p(cos θ) = (1 − g²) / (4π (1 + g² − 2g cos θ)^{3/2})`.
    pub fn eval_cos(&self, cos_theta: f32) -> f32 {
        let g = self.g;
        let denom = 1.0 + g * g - 2.0 * g * cos_theta;
        ISOTROPIC * (1.0 - g * g) / (denom * denom.sqrt())
    }

    /// The density of the sampled `cos θ` per steradian (isotropic in the small-`g` branch).
    pub fn pdf_cos(&self, cos_theta: f32) -> f32 {
        if self.g.abs() < SMALL_G {
            ISOTROPIC
        } else {
            self.eval_cos(cos_theta)
        }
    }

    /// Inverse CDF of `cos θ`: `cos θ = (1 + g² − ((1 − g²)/(1 − g + 2gu))²) / (2g)`.
    pub fn sample_cos(&self, u: f32) -> f32 {
        let g = self.g;
        let cos_theta = if g.abs() < SMALL_G {
            1.0 - 2.0 * u
        } else {
            let s = (1.0 - g * g) / (1.0 - g + 2.0 * g * u);
            (1.0 + g * g - s * s) / (2.0 * g)
        };
        cos_theta.clamp(-1.0, 1.0)
    }

    /// The CDF of the sampled `cos θ`, the inverse of [`HenyeyGreenstein::sample_cos`]:
    /// `u = (1 − g²)/(2g) · (1/√(1 + g² − 2g cos θ) − 1/(1 + g))`.
    pub fn invert_cos(&self, cos_theta: f32) -> f32 {
        let g = self.g;
        if g.abs() < SMALL_G {
            return 0.5 * (1.0 - cos_theta);
        }
        let root = (1.0 + g * g - 2.0 * g * cos_theta).sqrt();
        ((1.0 - g * g) / (2.0 * g) * (1.0 / root - 1.0 / (1.0 + g))).clamp(0.0, 1.0)
    }

    /// The random numbers `u` with `sample(dir_in, u).dir == dir_out` (up to rounding).
    pub fn invert(&self, dir_in: Vec3, dir_out: Vec3) -> [f32; 2] {
        let (t, b) = dir_in.any_orthonormal_pair();
        let phi = dir_out.dot(b).atan2(dir_out.dot(t));
        let u_phi = phi / TAU;
        [
            self.invert_cos(dir_in.dot(dir_out)),
            if u_phi < 0.0 { u_phi + 1.0 } else { u_phi },
        ]
    }
}

impl PhaseFunction for HenyeyGreenstein {
    fn eval(&self, dir_in: Vec3, dir_out: Vec3) -> f32 {
        self.eval_cos(dir_in.dot(dir_out))
    }

    fn sample(&self, dir_in: Vec3, u: [f32; 2]) -> PhaseSample {
        let cos_theta = self.sample_cos(u[0]);
        let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
        let (sin_phi, cos_phi) = (TAU * u[1]).sin_cos();
        let (t, b) = dir_in.any_orthonormal_pair();
        let dir =
            (sin_theta * cos_phi * t + sin_theta * sin_phi * b + cos_theta * dir_in).normalize();
        PhaseSample {
            dir,
            value: self.eval_cos(cos_theta),
            pdf: self.pdf_cos(cos_theta),
        }
    }

    fn pdf(&self, dir_in: Vec3, dir_out: Vec3) -> f32 {
        self.pdf_cos(dir_in.dot(dir_out))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use restir::rng::StreamKey;
    use restir::stats::chi_square_gof;

    /// Probability of `cos θ ∈ [a, b]` under the density `pdf_cos` (per sr), by composite Simpson
    /// over `2π ∫ pdf dμ`; independent of the inverse-CDF formula.
    fn bin_probability(pdf_cos: impl Fn(f32) -> f32, a: f64, b: f64) -> f64 {
        let n = 200;
        let h = (b - a) / n as f64;
        let f = |x: f64| std::f64::consts::TAU * pdf_cos(x as f32) as f64;
        let inner: f64 = (1..n)
            .map(|i| f(a + i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 })
            .sum();
        (f(a) + f(b) + inner) * h / 3.0
    }

    /// Chi-square p-value of `n` sampled `cos θ` of `sampler` in 40 equal-width bins against
    /// the probabilities of `reference` (a per-sr density).
    fn chi_square_p(
        sampler: &HenyeyGreenstein,
        reference: &HenyeyGreenstein,
        n: usize,
        seed: u64,
    ) -> f64 {
        const BINS: usize = 40;
        let mut counts = [0u64; BINS];
        let mut stream = StreamKey::new(0, 0, 0, 0x4847).stream(seed);
        let dir_in = Vec3::new(0.48, -0.6, 0.64);
        for _ in 0..n {
            let s = sampler.sample(dir_in, [stream.next_f32(), stream.next_f32()]);
            let mu = dir_in.dot(s.dir).clamp(-1.0, 1.0);
            counts[(((mu + 1.0) * 0.5 * BINS as f32) as usize).min(BINS - 1)] += 1;
        }
        let observed: Vec<f64> = counts.iter().map(|&c| c as f64).collect();
        let expected: Vec<f64> = (0..BINS)
            .map(|k| {
                let a = -1.0 + 2.0 * k as f64 / BINS as f64;
                bin_probability(|c| reference.pdf_cos(c), a, a + 2.0 / BINS as f64)
            })
            .collect();
        // Pooling to ≥ 5 expected counts per cell (only g = 0.9's backward bins are pooled).
        chi_square_gof(&observed, &expected, 5.0).p_value
    }

    /// Sampled `cos θ` against the pdf: chi-square, 40 bins, N = 200 000 per g, α = 1e-3 per g
    /// (5 values of g). Negative control: samples with g = 0.5 tested against the pdf of g = 0.53.
    #[test]
    fn hg_sampling_matches_pdf_chi_square() {
        const N: usize = 200_000;
        const ALPHA: f64 = 1e-3;
        for (i, g) in [-0.7f32, 0.0, 0.0004, 0.3, 0.9].into_iter().enumerate() {
            let hg = HenyeyGreenstein::new(g).unwrap();
            let p = chi_square_p(&hg, &hg, N, 11 + i as u64);
            eprintln!("HG g = {g}: chi-square p = {p:.3}");
            assert!(
                p > ALPHA,
                "HG g={g}: chi-square p = {p:.2e} ≤ α = {ALPHA} (N = {N}, 40 bins)"
            );
        }
        let sampled = HenyeyGreenstein::new(0.5).unwrap();
        let wrong = HenyeyGreenstein::new(0.53).unwrap();
        let p = chi_square_p(&sampled, &wrong, N, 99);
        eprintln!("HG negative control: chi-square p = {p:.2e}");
        assert!(
            p < ALPHA,
            "negative control (g 0.5 vs pdf of 0.53) not detected: p = {p:.2e}, α = {ALPHA}"
        );
    }

    #[test]
    fn hg_pdf_integrates_to_one_and_is_isotropic_at_zero() {
        for g in [-0.9f32, -0.2, 0.0, 0.5, 0.95] {
            let hg = HenyeyGreenstein::new(g).unwrap();
            let total: f64 = (0..40)
                .map(|k| {
                    bin_probability(
                        |c| hg.eval_cos(c),
                        -1.0 + k as f64 / 20.0,
                        -0.95 + k as f64 / 20.0,
                    )
                })
                .sum();
            assert!((total - 1.0).abs() < 1e-4, "∫ p = {total} for g = {g}");
        }
        let iso = HenyeyGreenstein::new(0.0).unwrap();
        assert_eq!(iso.eval_cos(0.3), ISOTROPIC);
        assert_eq!(iso.pdf_cos(-0.8), ISOTROPIC);
        assert!(HenyeyGreenstein::new(1.0).is_none() && HenyeyGreenstein::new(f32::NAN).is_none());
    }

    #[test]
    fn hg_invert_round_trips_sample() {
        let mut stream = StreamKey::new(1, 0, 0, 0x4847).stream(3);
        for g in [-0.6f32, 0.0, 0.8] {
            let hg = HenyeyGreenstein::new(g).unwrap();
            let dir_in = Vec3::new(0.0, 0.6, -0.8);
            for _ in 0..1000 {
                let u = [0.02 + 0.96 * stream.next_f32(), stream.next_f32()];
                let s = hg.sample(dir_in, u);
                let back = hg.invert(dir_in, s.dir);
                assert!(
                    (back[0] - u[0]).abs() < 2e-3,
                    "g={g}: u0 {} → {}",
                    u[0],
                    back[0]
                );
                let dphi = (back[1] - u[1]).abs();
                assert!(
                    dphi.min(1.0 - dphi) < 2e-3,
                    "g={g}: u1 {} → {}",
                    u[1],
                    back[1]
                );
                let pdf = hg.pdf(dir_in, s.dir);
                assert!(
                    (s.pdf - pdf).abs() <= 1e-3 * s.pdf,
                    "g={g}: sample pdf {} vs pdf() {pdf}",
                    s.pdf
                );
            }
        }
    }
}
