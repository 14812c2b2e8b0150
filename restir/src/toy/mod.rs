//! Toy domains with known integrals for testing the GRIS core in milliseconds (DESIGN §3).
//!
//! A "pixel" integrates over Ω = [0, 1]² the target `p̂(x) = a + b·exp(−‖x − μ‖² / 2σ²)`
//! restricted to a support box, and the integrand `f(x) = p̂(x)·(½ + x₀)` (so `f ≠ p̂` and the
//! estimate `f(Y)·W` depends on which sample was selected). Both integrals are closed-form.
//! Pixel parameters come from a keyed stream of a fixed scene seed, independent of replicas.

pub mod chain;
pub mod kit;
pub mod shifts;

use crate::rng::{Stream, StreamKey};
use crate::shift::{CandidateSampler, Domain, LocalCoords};

/// A toy sample: a point of [0, 1]².
pub type Point = [f32; 2];

/// Whether all pixels share the support [0, 1]² or each has its own box.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Supports {
    Equal,
    /// Pixel-dependent boxes `[0, h₀] × [0, h₁]`, `h ∈ [0.55, 1]` (breaks `1/M`).
    Differing,
}

/// One toy domain (a pixel at a frame).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ToyPixel {
    /// Distinguishes domains (pixel + frame · pixel count); only the asymmetric broken shift uses it.
    pub id: u32,
    /// Bump centre `μ`; the translation and scaling shifts map centre to centre.
    pub centre: [f32; 2],
    /// Bump width `σ`; the scaling shift scales by the ratio of widths.
    pub sigma: f32,
    /// Constant part `a` of `p̂`.
    pub floor: f32,
    /// Bump height `b`.
    pub height: f32,
    /// Upper corner of the support box `[0, hi₀] × [0, hi₁]`.
    pub support_hi: [f32; 2],
    /// Primary-sample warp exponents: `x_d = u_d^{γ_d}` (the replay shift).
    pub warp_gamma: [f32; 2],
}

/// Fixed seed of the toy scene parameters (not a replica seed).
const SCENE_SEED: u64 = 0x5EED_70E5;

impl ToyPixel {
    /// The pixel `pixel` at `frame` of a scene with `pixel_count` pixels per frame.
    pub fn new(pixel: u32, frame: u32, pixel_count: u32, supports: Supports) -> Self {
        let mut rng = StreamKey::new(pixel, frame, 0, 0).stream(SCENE_SEED);
        let mut u = || rng.next_f32();
        let centre = [0.3 + 0.4 * u(), 0.3 + 0.4 * u()];
        let sigma = 0.08 + 0.08 * u();
        let floor = 0.1 + 0.2 * u();
        let height = 1.0 + u();
        let support_hi = match supports {
            Supports::Equal => [1.0, 1.0],
            Supports::Differing => [0.55 + 0.45 * u(), 0.55 + 0.45 * u()],
        };
        let warp_gamma = [0.7 + 0.7 * u(), 0.7 + 0.7 * u()];
        Self {
            id: pixel + frame * pixel_count,
            centre,
            sigma,
            floor,
            height,
            support_hi,
            warp_gamma,
        }
    }

    /// Whether `x` lies in Ω = [0, 1]².
    #[inline]
    pub fn in_omega(x: &Point) -> bool {
        (0.0..=1.0).contains(&x[0]) && (0.0..=1.0).contains(&x[1])
    }

    /// `f(x) = p̂(x)·(½ + x₀)`, the integrand whose estimate is `f(Y)·W`.
    #[inline]
    pub fn integrand(&self, x: &Point) -> f32 {
        self.target(x) * (0.5 + x[0])
    }

    /// `∫_Ω p̂` in closed form (f64).
    pub fn target_integral(&self) -> f64 {
        let [g0, g1] = [0, 1].map(|d| self.gauss_moments(d).0);
        let area = self.support_hi[0] as f64 * self.support_hi[1] as f64;
        self.floor as f64 * area + self.height as f64 * g0 * g1
    }

    /// `∫_Ω f` in closed form (f64).
    pub fn integrand_integral(&self) -> f64 {
        let (_, h0) = self.gauss_moments(0);
        let (g1, _) = self.gauss_moments(1);
        let [s0, s1] = self.support_hi.map(f64::from);
        // ∫ p̂·x₀ = a·(s₀²/2)·s₁ + b·H₀·G₁
        let first_moment = self.floor as f64 * 0.5 * s0 * s0 * s1 + self.height as f64 * h0 * g1;
        0.5 * self.target_integral() + first_moment
    }

    /// `|B ∩ supp p̂|` for the box `B = [lo, hi]`.
    pub fn support_overlap(&self, lo: [f64; 2], hi: [f64; 2]) -> f64 {
        (0..2)
            .map(|d| (hi[d].min(self.support_hi[d] as f64) - lo[d].max(0.0)).max(0.0))
            .product()
    }

    /// `(G, H)` = `∫_0^s exp(−(t−μ)²/2σ²) dt` and `∫_0^s t·exp(−(t−μ)²/2σ²) dt` on axis `d`.
    fn gauss_moments(&self, d: usize) -> (f64, f64) {
        let (mu, sigma, s) = (
            self.centre[d] as f64,
            self.sigma as f64,
            self.support_hi[d] as f64,
        );
        let scale = sigma * std::f64::consts::SQRT_2;
        let g = sigma
            * (std::f64::consts::PI / 2.0).sqrt()
            * (erf((s - mu) / scale) - erf(-mu / scale));
        let gauss = |t: f64| (-(t - mu) * (t - mu) / (2.0 * sigma * sigma)).exp();
        let h = mu * g + sigma * sigma * (gauss(0.0) - gauss(s));
        (g, h)
    }
}

impl Domain for ToyPixel {
    type Sample = Point;

    #[inline]
    fn target(&self, x: &Point) -> f32 {
        let inside = (0.0..=self.support_hi[0]).contains(&x[0])
            && (0.0..=self.support_hi[1]).contains(&x[1]);
        if !inside {
            return 0.0;
        }
        let (dx, dy) = (x[0] - self.centre[0], x[1] - self.centre[1]);
        self.floor + self.height * (-(dx * dx + dy * dy) / (2.0 * self.sigma * self.sigma)).exp()
    }
}

impl LocalCoords for ToyPixel {
    fn dim(&self) -> usize {
        2
    }
    fn to_local(&self, x: &Point, out: &mut [f64]) {
        out[0] = x[0] as f64;
        out[1] = x[1] as f64;
    }
    fn sample_at_local(&self, coords: &[f64]) -> Option<Point> {
        let x = [coords[0] as f32, coords[1] as f32];
        Self::in_omega(&x).then_some(x)
    }
}

/// `erf(x)` to ≈1e-13 relative: Taylor series for |x| < 2.5, continued fraction of erfc beyond.
fn erf(x: f64) -> f64 {
    let a = x.abs();
    let value = if a < 2.5 {
        // erf(a) = 2/√π Σ (−1)ⁿ a^{2n+1} / (n! (2n+1))
        let mut term = a;
        let mut sum = a;
        let mut n = 0.0;
        while term.abs() > 1e-17 * sum.abs() {
            n += 1.0;
            term *= -a * a / n;
            sum += term / (2.0 * n + 1.0);
        }
        sum * 2.0 / std::f64::consts::PI.sqrt()
    } else {
        // erfc(a) = exp(−a²)/√π · 1/(a + (1/2)/(a + 1/(a + (3/2)/(a + …)))), evaluated bottom-up.
        let mut tail = a;
        for k in (1..=60).rev() {
            tail = a + (k as f64 / 2.0) / tail;
        }
        1.0 - (-a * a).exp() / (std::f64::consts::PI.sqrt() * tail)
    };
    value.copysign(x)
}

/// Candidate sampler with the per-axis linear density `p(t) = ½ + t` on [0, 1] — known, covers
/// every support, and not proportional to any target.
#[derive(Clone, Copy, Debug, Default)]
pub struct LinearSampler;

impl LinearSampler {
    /// Inverse CDF of `p(t) = ½ + t`: `F(t) = (t + t²)/2 = u`.
    #[inline]
    pub fn warp(u: f32) -> f32 {
        (((1.0 + 8.0 * u).sqrt() - 1.0) * 0.5).min(1.0)
    }
    /// `F(t)`, the inverse of [`LinearSampler::warp`].
    #[inline]
    pub fn invert(t: f32) -> f32 {
        0.5 * (t + t * t)
    }
    /// The density of a point: `(½ + x₀)(½ + x₁)` on Ω, 0 outside.
    #[inline]
    pub fn density(x: &Point) -> f32 {
        if ToyPixel::in_omega(x) {
            (0.5 + x[0]) * (0.5 + x[1])
        } else {
            0.0
        }
    }
}

impl CandidateSampler<ToyPixel> for LinearSampler {
    fn sample(&self, _domain: &ToyPixel, rng: &mut Stream) -> Option<(Point, f32)> {
        let x = [Self::warp(rng.next_f32()), Self::warp(rng.next_f32())];
        Some((x, Self::density(&x)))
    }
    fn pdf(&self, _domain: &ToyPixel, x: &Point) -> f32 {
        Self::density(x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn erf_matches_known_values() {
        // Values from Abramowitz & Stegun Table 7.1.
        for (x, want) in [
            (0.5, 0.520_499_877_8),
            (1.0, 0.842_700_792_9),
            (2.0, 0.995_322_265_0),
        ] {
            assert!((erf(x) - want).abs() < 1e-9, "erf({x})");
            assert!((erf(-x) + want).abs() < 1e-9);
        }
        assert!((erf(3.0) - 0.999_977_909_5).abs() < 1e-9);
    }

    /// Closed-form integrals against a 600² midpoint rule of the f32 functions over the support
    /// box (relative 1e-4).
    #[test]
    fn closed_form_integrals_match_quadrature() {
        for supports in [Supports::Equal, Supports::Differing] {
            for pixel in 0..4 {
                let d = ToyPixel::new(pixel, 1, 16, supports);
                let n = 600;
                let [h0, h1] = d.support_hi.map(|s| s as f64 / n as f64);
                let (mut ip, mut i_f) = (0.0f64, 0.0f64);
                for a in 0..n {
                    for b in 0..n {
                        let x = [
                            ((a as f64 + 0.5) * h0) as f32,
                            ((b as f64 + 0.5) * h1) as f32,
                        ];
                        ip += d.target(&x) as f64 * h0 * h1;
                        i_f += d.integrand(&x) as f64 * h0 * h1;
                    }
                }
                let rel = |a: f64, b: f64| ((a - b) / b).abs();
                assert!(
                    rel(ip, d.target_integral()) < 1e-4,
                    "{supports:?} {pixel}: {ip}"
                );
                assert!(
                    rel(i_f, d.integrand_integral()) < 1e-4,
                    "{supports:?} {pixel}: {i_f}"
                );
            }
        }
    }

    #[test]
    fn linear_sampler_warp_inverts_and_density_integrates_to_one() {
        for k in 0..100 {
            let u = k as f32 / 100.0;
            assert!((LinearSampler::invert(LinearSampler::warp(u)) - u).abs() < 1e-6);
        }
        let n = 400;
        let h = 1.0 / n as f64;
        let total: f64 = (0..n * n)
            .map(|k| {
                let x = [((k % n) as f64 + 0.5) * h, ((k / n) as f64 + 0.5) * h];
                LinearSampler::density(&[x[0] as f32, x[1] as f32]) as f64 * h * h
            })
            .sum();
        assert!((total - 1.0).abs() < 1e-5);
    }
}
