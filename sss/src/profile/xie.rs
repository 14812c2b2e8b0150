//! Xie et al.'s approximate inverse of the Burley radius CDF [004 Eq. 21],
//! `g(ξ) = d((2 − c)ξ − 2) ln(1 − ξ)` with `c = 2.5715`, as a sampling option in its own right.
//!
//! `g` is only close to `P⁻¹` (a few per cent), so samples `r = g(ξ)` are *not* distributed as
//! Burley's `R̄_d`. To stay unbiased they must be weighted with the density of `g(U)` itself,
//! [`Xie::pdf_radius`]` = 1 / g′(g⁻¹(r))`, which needs `g⁻¹`: with `t = −ln(1 − ξ)`,
//! `g = d(2 + k(1 − e^{−t}))t` (`k = c − 2`) is increasing in `t` and bracketed by
//! `2dt ≤ g ≤ (2 + k)dt`, so `g⁻¹` is a safeguarded Newton solve on that bracket.

use std::f32::consts::PI;

use crate::contract::xie::INVERSE_ITERATIONS;

/// The damping constant `c` of [004 Eq. 21] (their least-squares optimum).
pub const XIE_C: f32 = 2.5715;

/// Xie's approximate Burley radius sampler for one channel with shape parameter `d > 0`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Xie {
    pub d: f32,
}

impl Xie {
    /// The sampler for shape parameter `d` (finite, > 0).
    pub fn new(d: f32) -> Xie {
        debug_assert!(
            d.is_finite() && d > 0.0,
            "Xie d must be finite and > 0, got {d}"
        );
        Xie { d }
    }

    /// `g(ξ) = d((2 − c)ξ − 2) ln(1 − ξ)` [004 Eq. 21]; 0 for `ξ ≤ 0`, `+∞` for `ξ ≥ 1`.
    pub fn sample_radius(&self, xi: f32) -> f32 {
        if xi.is_nan() || xi <= 0.0 {
            return 0.0;
        }
        if xi >= 1.0 {
            return f32::INFINITY;
        }
        approximate_inverse(self.d, XIE_C, xi)
    }

    /// The CDF of `g(U)`, i.e. `g⁻¹(r)` (module doc). 0 for `r ≤ 0`, 1 for `r = +∞`.
    pub fn cdf(&self, r: f32) -> f32 {
        -(-self.inverse_t(r)).exp_m1()
    }

    /// Density of the radius `r = g(U)`: `1 / g′(ξ)` at `ξ = g⁻¹(r)`, where
    /// `g′(ξ) = d(k t + (2 + kξ)e^{t})`, `t = −ln(1 − ξ)`, `k = c − 2`. 0 for `r < 0`.
    pub fn pdf_radius(&self, r: f32) -> f32 {
        if r.is_nan() || r < 0.0 || r.is_infinite() {
            return 0.0;
        }
        let k = XIE_C - 2.0;
        let t = self.inverse_t(r);
        let xi = -(-t).exp_m1();
        let decay = (-t).exp();
        // 1/g′ = e^{−t} / (d (k t e^{−t} + 2 + kξ)), finite as t → ∞.
        decay / (self.d * (k * t * decay + 2.0 + k * xi))
    }

    /// Disk-area density `pdf_radius(r) / (2πr)`; 0 for `r ≤ 0`.
    pub fn pdf_disk(&self, r: f32) -> f32 {
        if !(r > 0.0 && r.is_finite()) {
            return 0.0;
        }
        self.pdf_radius(r) / (2.0 * PI * r)
    }

    /// `t = −ln(1 − g⁻¹(r))`: root of `(2 + k(1 − e^{−t}))t = r/d` in `[ρ/(2 + k), ρ/2]`.
    fn inverse_t(&self, r: f32) -> f32 {
        if r.is_nan() || r <= 0.0 {
            return 0.0;
        }
        if r.is_infinite() {
            return f32::INFINITY;
        }
        let k = XIE_C - 2.0;
        let rho = r / self.d;
        let (mut lo, mut hi) = (rho / (2.0 + k), rho / 2.0);
        let mut t = 0.5 * (lo + hi);
        for _ in 0..INVERSE_ITERATIONS {
            let one_minus_decay = -(-t).exp_m1();
            let h = (2.0 + k * one_minus_decay) * t - rho;
            if h == 0.0 {
                break;
            }
            if h > 0.0 {
                hi = t
            } else {
                lo = t
            }
            let dh = 2.0 + k * one_minus_decay + k * t * (-t).exp();
            let newton = t - h / dh;
            let next = if newton >= lo && newton <= hi {
                newton
            } else {
                0.5 * (lo + hi)
            };
            if next == t {
                break;
            }
            t = next;
        }
        t
    }
}

/// `g(ξ | c)` of [004 Eq. 21] for `ξ ∈ (0, 1)`.
fn approximate_inverse(d: f32, c: f32, xi: f32) -> f32 {
    d * ((2.0 - c) * xi - 2.0) * (-xi).ln_1p()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::profile::Burley;
    use crate::profile::test_support::{bin_probabilities, draw, histogram};
    use restir::stats::chi_square_gof;

    /// cdf(g(ξ)) = ξ to 1e-6 relative over ξ from 1e-7 to 1 − 2⁻²⁴.
    #[test]
    fn inverse_round_trip() {
        for &d in &[0.05f32, 1.0, 4.0] {
            let x = Xie::new(d);
            let mut xis: Vec<f32> = (1..1000).map(|i| i as f32 / 1000.0).collect();
            xis.extend([1e-7, 1e-5, 1e-3, 0.999_99, 1.0 - 2f32.powi(-24)]);
            for &xi in &xis {
                let r = x.sample_radius(xi);
                let back = x.cdf(r);
                assert!(
                    ((back - xi) / xi).abs() < 1e-6,
                    "d = {d}, ξ = {xi}: cdf(g(ξ)) = {back}"
                );
            }
        }
    }

    /// pdf_radius is the derivative of cdf (central differences in f64 around several r), and
    /// integrates to 1 (Simpson in ln r).
    #[test]
    fn pdf_is_derivative_of_cdf_and_normalized() {
        let x = Xie::new(0.8);
        for &r in &[0.01f32, 0.3, 1.0, 3.0, 10.0] {
            let h = r * 1e-2;
            let fd = (x.cdf(r + h) as f64 - x.cdf(r - h) as f64) / (2.0 * h as f64);
            let pdf = x.pdf_radius(r) as f64;
            assert!(
                ((fd - pdf) / pdf).abs() < 1e-3,
                "r = {r}: finite difference {fd} vs pdf {pdf}"
            );
        }
        let (t0, t1, n) = ((1e-8f64).ln(), (400.0f64).ln(), 20_000usize);
        let h = (t1 - t0) / n as f64;
        let f = |t: f64| t.exp() * x.pdf_radius(t.exp() as f32) as f64;
        let mut sum = f(t0) + f(t1);
        for i in 1..n {
            sum += f(t0 + i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
        }
        let total = sum * h / 3.0;
        assert!((total - 1.0).abs() < 1e-4, "∫ pdf_radius = {total}");
    }

    /// [004 §4]: c = 2.5715 minimizes the mean squared error of P(g(ξ | c)) − ξ (Burley's CDF P,
    /// ξ on a 10⁴-point grid, f64 accumulation): it beats c ± 0.02. And g is not Burley's inverse:
    /// the largest CDF gap is far above f32 noise, so Xie samples need [`Xie::pdf_radius`].
    #[test]
    fn c_minimizes_cdf_error_but_differs_from_burley() {
        let b = Burley::new(1.0);
        let mse = |c: f32| {
            let n = 10_000;
            let sum: f64 = (1..n)
                .map(|i| {
                    let xi = i as f32 / n as f32;
                    (b.cdf(approximate_inverse(1.0, c, xi)) as f64 - xi as f64).powi(2)
                })
                .sum();
            sum / (n - 1) as f64
        };
        let best = mse(XIE_C);
        for c in [XIE_C - 0.02, XIE_C + 0.02] {
            assert!(
                best < mse(c),
                "MSE(c = {XIE_C}) = {best} ≥ MSE(c = {c}) = {}",
                mse(c)
            );
        }
        let x = Xie::new(1.0);
        let max_cdf_gap = (1..1000)
            .map(|i| {
                let xi = i as f32 / 1000.0;
                (b.cdf(x.sample_radius(xi)) - xi).abs()
            })
            .fold(0.0f32, f32::max);
        assert!(max_cdf_gap > 1e-3, "max |P(g(ξ)) − ξ| = {max_cdf_gap}");
    }

    /// χ² of N = 2·10⁵ radii g(ξ) (`next_f32`, seed 2001) in 100 equal-probability bins plus the
    /// tail against ∫ Xie::pdf_radius per bin, α = 1e-3. Negative controls, same test: radii from
    /// d′ = 1.05 d, and the same Xie radii against Burley's pdf (the bias of using g with R̄_d).
    #[test]
    fn sampled_radii_follow_own_pdf() {
        const N: usize = 200_000;
        const ALPHA: f64 = 1e-3;
        let x = Xie::new(0.6);
        let edges: Vec<f64> = (0..100)
            .map(|k| x.sample_radius(k as f32 / 100.0) as f64)
            .collect();
        let expected = bin_probabilities(|r| x.pdf_radius(r), &edges);
        let samples = draw(N, 3, |u| x.sample_radius(u));
        let good = chi_square_gof(&histogram(&samples, &edges), &expected, 5.0);
        assert!(
            good.p_value > ALPHA,
            "Xie sampling rejected (N = {N}, α = {ALPHA}): {good:?}"
        );
        let wrong = Xie::new(1.05 * x.d);
        let bad_d = chi_square_gof(
            &histogram(&draw(N, 4, |u| wrong.sample_radius(u)), &edges),
            &expected,
            5.0,
        );
        assert!(
            bad_d.p_value < ALPHA,
            "control d′ = 1.05 d not rejected (N = {N}, α = {ALPHA}): {bad_d:?}"
        );
        let burley = bin_probabilities(|r| Burley::new(x.d).pdf_radius(r), &edges);
        let bad_pdf = chi_square_gof(&histogram(&samples, &edges), &burley, 5.0);
        assert!(
            bad_pdf.p_value < ALPHA,
            "control Burley pdf not rejected (N = {N}, α = {ALPHA}): {bad_pdf:?}"
        );
    }
}
