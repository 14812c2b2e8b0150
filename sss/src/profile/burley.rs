//! Burley's normalized diffusion profile (Christensen & Burley 2015) for one colour channel
//! [001 Eq. 3–4], [004 Eq. 4, 20], with its exact analytic radius sampling.
//!
//! `R̄_d(r) = (e^{−r/d} + e^{−r/3d}) / (8π d r)` integrates to 1 over the plane, so it is at once
//! the shape of the profile (the material multiplies by the albedo `A`) and the disk-area density
//! of the radius sampler. The CDF of the radius is `P(r) = 1 − ¼e^{−r/d} − ¾e^{−r/3d}`; with
//! `x = e^{−r/3d}` the equation `P(r) = u` becomes the depressed cubic `x³ + 3x = 4(1 − u)`, whose
//! only real root is `x = 2 sinh(asinh(2(1 − u)) / 3)` (Cardano, written with hyperbolic functions
//! so that it is accurate as `u → 1`). As `u → 0` the root tends to 1 and `−ln x` loses digits, so
//! there the solver works on `y = 1 − x` (`y³ − 3y² + 6y = 4u`) and polishes it with Newton steps.
//!
//! Its GLSL twin (DESIGN §1) goes to `sss/glsl/burley.glsl`; it needs `expm1`/`log1p` substitutes
//! to keep the small-`r` accuracy.

use std::f32::consts::PI;
use std::sync::LazyLock;

pub use crate::contract::burley::R_MAX_QUANTILE;

/// The real root `x = e^{−r/3d}` of `x³ + 3x = 4(1 − u)` (module doc), independent of `d`.
fn cardano_root(u: f32) -> f32 {
    2.0 * ((2.0 * (1.0 - u)).asinh() / 3.0).sinh()
}

/// Burley normalized diffusion for one channel, shape parameter `d > 0` (scene units).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Burley {
    pub d: f32,
}

impl Burley {
    /// A profile with shape parameter `d`; `d` must be finite and positive (materials validate it).
    pub fn new(d: f32) -> Burley {
        debug_assert!(
            d.is_finite() && d > 0.0,
            "Burley d must be finite and > 0, got {d}"
        );
        Burley { d }
    }

    /// Disk-area density `R̄_d(r) = (e^{−r/d} + e^{−r/3d}) / (8π d r)` [001 Eq. 3].
    /// Returns 0 for `r ≤ 0` (a single point of zero measure where the density is unbounded) and
    /// for non-finite `r`.
    pub fn pdf_disk(&self, r: f32) -> f32 {
        if !(r > 0.0 && r.is_finite()) {
            return 0.0;
        }
        self.pdf_radius(r) / (2.0 * PI * r)
    }

    /// Density of the radius `r`: `2πr · R̄_d(r) = (e^{−r/d} + e^{−r/3d}) / (4d)`; 0 for `r < 0`.
    pub fn pdf_radius(&self, r: f32) -> f32 {
        if r.is_nan() || r < 0.0 || r.is_infinite() {
            return 0.0;
        }
        ((-r / self.d).exp() + (-r / (3.0 * self.d)).exp()) / (4.0 * self.d)
    }

    /// `P(r) = 1 − ¼e^{−r/d} − ¾e^{−r/3d}` [001 Eq. 4], evaluated with `expm1` so that it keeps
    /// full relative precision as `r → 0`. 0 for `r ≤ 0`, 1 for `r = +∞`.
    pub fn cdf(&self, r: f32) -> f32 {
        if r.is_nan() || r <= 0.0 {
            return 0.0;
        }
        let v = -(0.25 * (-r / self.d).exp_m1() + 0.75 * (-r / (3.0 * self.d)).exp_m1());
        v.min(1.0)
    }

    /// The exact inverse of [`Burley::cdf`] for `u ∈ [0, 1)` (Cardano on the cubic in
    /// `x = e^{−r/3d}`, see the module doc). `u ≤ 0` gives 0; `u ≥ 1` gives `+∞`.
    pub fn sample_radius(&self, u: f32) -> f32 {
        if u.is_nan() || u <= 0.0 {
            return 0.0;
        }
        if u >= 1.0 {
            return f32::INFINITY;
        }
        let x_cardano = cardano_root(u);
        if u > 0.5 {
            return -3.0 * self.d * x_cardano.ln();
        }
        // y = 1 − x solves y³ − 3y² + 6y = 4u; f'(y) = 3((y − 1)² + 1) ≥ 3, so Newton is safe.
        let mut y = (1.0 - x_cardano).max(0.0);
        for _ in 0..3 {
            let f = y * (y * (y - 3.0) + 6.0) - 4.0 * u;
            let df = 3.0 * ((y - 1.0) * (y - 1.0) + 1.0);
            y -= f / df;
        }
        -3.0 * self.d * (-y).ln_1p()
    }

    /// Truncation radius `P⁻¹(R_MAX_QUANTILE)` (DESIGN §4, §9): [`Burley::sample_radius`] at
    /// the quantile, `−3d · ln x(R_MAX_QUANTILE)`, with the root's logarithm taken once per
    /// process (the same operations in the same order, so the same bits as the sampler's).
    pub fn r_max(&self) -> f32 {
        static LN_ROOT: LazyLock<f32> = LazyLock::new(|| cardano_root(R_MAX_QUANTILE).ln());
        const {
            assert!(
                R_MAX_QUANTILE > 0.5,
                "r_max takes the sampler's u > 0.5 branch"
            )
        };
        -3.0 * self.d * *LN_ROOT
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::profile::test_support::{bin_probabilities, draw, histogram};
    use restir::stats::chi_square_gof;

    /// f64 reference of the radius CDF, for round trips that do not trust the f32 kernels.
    fn cdf_f64(d: f64, r: f64) -> f64 {
        -(0.25 * (-r / d).exp_m1() + 0.75 * (-r / (3.0 * d)).exp_m1())
    }

    /// f64 reference inverse by bisection on the monotone CDF (independent of Cardano).
    fn inverse_cdf_f64(d: f64, u: f64) -> f64 {
        let (mut lo, mut hi) = (0.0f64, d);
        while cdf_f64(d, hi) < u {
            hi *= 2.0;
        }
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if cdf_f64(d, mid) < u {
                lo = mid
            } else {
                hi = mid
            }
        }
        0.5 * (lo + hi)
    }

    /// ∫₀^∞ 2πr R̄_d(r) dr = 1 by composite Simpson in the variable t = ln r (f64), which resolves
    /// both the 1/r singularity and the exponential tail.
    #[test]
    fn profile_integrates_to_one() {
        for &d in &[0.01f32, 0.3, 1.0, 7.5] {
            let p = Burley::new(d);
            let (t0, t1, n) = ((d as f64 * 1e-9).ln(), (d as f64 * 200.0).ln(), 20_000usize);
            let h = (t1 - t0) / n as f64;
            let integrand = |t: f64| {
                let r = t.exp();
                2.0 * std::f64::consts::PI * r * p.pdf_disk(r as f32) as f64 * r
            };
            let mut sum = integrand(t0) + integrand(t1);
            for i in 1..n {
                sum += integrand(t0 + i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
            }
            let total = sum * h / 3.0;
            assert!(
                (total - 1.0).abs() < 1e-4,
                "d = {d}: ∫ 2πr R̄_d dr = {total}, want 1 ± 1e-4"
            );
        }
    }

    /// The CDF is the integral of the radius density: compare P(b) − P(a) with Simpson on [a, b].
    #[test]
    fn cdf_is_integral_of_pdf_radius() {
        let p = Burley::new(0.7);
        for &(a, b) in &[(0.0f64, 0.1f64), (0.1, 1.0), (1.0, 5.0), (5.0, 20.0)] {
            let n = 2000;
            let h = (b - a) / n as f64;
            let f = |r: f64| p.pdf_radius(r as f32) as f64;
            let mut sum = f(a) + f(b);
            for i in 1..n {
                sum += f(a + i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
            }
            let quad = sum * h / 3.0;
            let diff = p.cdf(b as f32) as f64 - p.cdf(a as f32) as f64;
            assert!(
                (quad - diff).abs() < 1e-6,
                "[{a}, {b}]: quadrature {quad} vs CDF difference {diff}"
            );
        }
    }

    /// sample_radius(u) equals the f64 bisection inverse to 1e-6 relative, over u from 1e-7 to
    /// 1 − 2⁻²⁴ (the largest `next_f32`), and sample_radius(cdf(r)) ≈ r in f32.
    #[test]
    fn inverse_cdf_round_trip() {
        for &d in &[0.05f32, 1.0, 3.0] {
            let p = Burley::new(d);
            let mut us: Vec<f32> = (1..1000).map(|i| i as f32 / 1000.0).collect();
            us.extend([1e-7, 1e-6, 1e-5, 1e-4, 1e-3, 0.999_99, 1.0 - 2f32.powi(-24)]);
            for &u in &us {
                let r = p.sample_radius(u) as f64;
                let want = inverse_cdf_f64(d as f64, u as f64);
                assert!(
                    ((r - want) / want).abs() < 1e-6,
                    "d = {d}, u = {u}: sample_radius = {r}, f64 inverse = {want}"
                );
            }
            // r from 1e-6·d up to where 1 − P(r) ≈ 2⁻²⁰ (beyond, P(r) rounds to 1 in f32).
            for i in 1..1750 {
                let r = d * 1e-6 * 1.01f32.powi(i);
                let back = p.sample_radius(p.cdf(r));
                // The f32 CDF itself is only accurate to a few ulps of P, amplified by P/(r·P'(r)).
                let cond = (p.cdf(r) / (r * p.pdf_radius(r))).max(1.0);
                let tol = 4.0 * f32::EPSILON * cond;
                assert!(
                    ((back - r) / r).abs() < tol.max(1e-6),
                    "d = {d}, r = {r}: round trip {back}"
                );
            }
        }
    }

    #[test]
    fn edge_values_are_finite() {
        let p = Burley::new(0.5);
        assert_eq!(p.sample_radius(0.0), 0.0);
        assert_eq!(p.pdf_disk(0.0), 0.0);
        assert_eq!(p.cdf(0.0), 0.0);
        let r = p.sample_radius(1.0 - 2f32.powi(-24));
        assert!(r.is_finite() && r > 0.0);
        assert!(p.pdf_disk(1e-30).is_finite());
        assert!(p.pdf_disk(1e30) == 0.0);
        let rm = p.r_max() as f64;
        assert!(
            (cdf_f64(0.5, rm) - R_MAX_QUANTILE as f64).abs() < 1e-6,
            "r_max = {rm}"
        );
    }

    /// `r_max`, with its root's logarithm taken once, is the sampler's quantile bit for bit
    /// (the pinned outputs depend on it), over `d` across nine decades.
    #[test]
    fn r_max_is_the_samplers_quantile_bit_for_bit() {
        for i in 0..2000 {
            let d = 1e-4f32 * 1.0105f32.powi(i);
            let p = Burley::new(d);
            assert_eq!(
                p.r_max().to_bits(),
                p.sample_radius(R_MAX_QUANTILE).to_bits(),
                "d = {d}"
            );
        }
    }

    /// χ² of N = 2·10⁵ radii (`next_f32`, seed 2001) in 100 equal-probability bins plus the tail
    /// against ∫ pdf_radius per bin, α = 1e-3 (cells pooled to ≥ 5 expected). Negative control:
    /// radii drawn with d′ = 1.05 d are rejected by the same test.
    #[test]
    fn sampled_radii_follow_pdf() {
        const N: usize = 200_000;
        const ALPHA: f64 = 1e-3;
        let p = Burley::new(0.6);
        let edges: Vec<f64> = (0..100)
            .map(|k| p.sample_radius(k as f32 / 100.0) as f64)
            .collect();
        let expected = bin_probabilities(|r| p.pdf_radius(r), &edges);
        let good = chi_square_gof(
            &histogram(&draw(N, 1, |u| p.sample_radius(u)), &edges),
            &expected,
            5.0,
        );
        assert!(
            good.p_value > ALPHA,
            "Burley sampling rejected (N = {N}, α = {ALPHA}): {good:?}"
        );
        let wrong = Burley::new(1.05 * p.d);
        let bad = chi_square_gof(
            &histogram(&draw(N, 2, |u| wrong.sample_radius(u)), &edges),
            &expected,
            5.0,
        );
        assert!(
            bad.p_value < ALPHA,
            "negative control (d′ = 1.05 d) not rejected (N = {N}, α = {ALPHA}): {bad:?}"
        );
    }
}
