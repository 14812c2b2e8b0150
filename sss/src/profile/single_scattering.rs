//! Paper 000's split of the diffusion profile into single scattering `R1` and the
//! multiple-scattering-only profile `Rn = R − R1` [000, "Single Scattering Diffusion Profile"].
//!
//! The `R` of paper 000 is Burley's normalized diffusion with the **searchlight** fit
//! `s(A) = 1.85 − A + 7|A − 0.8|³` ([`ScaleFit::Searchlight`], [004 Eq. 5] Θ₁), `ℓ = 1/σt` the
//! volume mean free path, written as a function of the single-scattering albedo `α` through the
//! seed's Monte Carlo fit (diffuse transmission, η = 1.4, semi-infinite slab)
//! `A(α) = (1 − √(1 − α)) / (1.554√(1 − α) + 1)`:
//! `R(r; α) = A s (e^{−rs/ℓ} + e^{−rs/3ℓ}) / (8πℓr)` with `A = A(α)`, `s = s(A(α))`, i.e.
//! `A(α) · R̄_{ℓ/s}(r)` in terms of [`Burley`].
//!
//! n-fold scattering is the `αⁿ` term of the Taylor series of `R` in `α` at 0, so
//! `R1(r; α) = α ∂R/∂α|_{α=0}`. Because `A(0) = 0`, only `A′(0)` survives: with `q = √(1 − α)`,
//! `A′(0) = (dA/dq)(dq/dα) = (−2.554/2.554²)(−½) = 1/5.108`, and `s(A(0)) = 1.85 + 7·0.8³ = 5.434`:
//! `R1(r; α) = (α/5.108) · R̄_{ℓ/5.434}(r)` — itself a Burley profile (albedo `α/5.108`,
//! `d = ℓ/5.434`), so it is sampled with [`Burley::sample_radius`]. The seed's printed
//! `0.0423281 (e^{−5.434/ℓ} + e^{−1.8113/ℓ}) / (ℓr)` is this coefficient `5.434/(5.108·8π)` per unit
//! `α`, with `r` lost from the exponents.
//!
//! `Rn = R − R1` keeps `R1 + Rn = R` exactly but is **negative near r = 0 once α ≳ 0.29**: both
//! behave as `1/r` there and `A(α)s(α) < α·5.434/5.108` (tested). Callers that need a
//! non-negative target must clamp and account for it.

use crate::profile::{Burley, ScaleFit, scale_factor};

/// `A′(0) = 1 / (2(1 + 1.554))` (module doc).
const SINGLE_ALBEDO_SLOPE: f32 = 1.0 / 5.108;

/// Paper 000's fit of the surface albedo as a function of the single-scattering albedo `α ∈ [0, 1]`.
pub fn surface_albedo(alpha: f32) -> f32 {
    let q = (1.0 - alpha.clamp(0.0, 1.0)).sqrt();
    (1.0 - q) / (1.554 * q + 1.0)
}

/// The profiles `R`, `R1`, `Rn` of one channel: single-scattering albedo `alpha ∈ [0, 1]` and
/// volume mean free path `mfp = 1/σt > 0` (scene units).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScatteringOrders {
    pub alpha: f32,
    pub mfp: f32,
}

impl ScatteringOrders {
    /// The full profile's albedo `A(α)` and its Burley profile `R̄_{ℓ/s(A)}`.
    pub fn full(&self) -> (f32, Burley) {
        let a = surface_albedo(self.alpha);
        (
            a,
            Burley::new(self.mfp / scale_factor(ScaleFit::Searchlight, a)),
        )
    }

    /// The single-scattering albedo `α/5.108` and profile `R̄_{ℓ/5.434}` (module doc).
    pub fn single(&self) -> (f32, Burley) {
        let d = self.mfp / scale_factor(ScaleFit::Searchlight, 0.0);
        (self.alpha * SINGLE_ALBEDO_SLOPE, Burley::new(d))
    }

    /// `R(r; α)` (disk-area density times albedo).
    pub fn full_profile(&self, r: f32) -> f32 {
        let (a, burley) = self.full();
        a * burley.pdf_disk(r)
    }

    /// `R1(r; α)`.
    pub fn single_profile(&self, r: f32) -> f32 {
        let (a, burley) = self.single();
        a * burley.pdf_disk(r)
    }

    /// `Rn(r; α) = R − R1`, the multiple-scattering-only profile (may be negative, module doc).
    pub fn multiple_profile(&self, r: f32) -> f32 {
        self.full_profile(r) - self.single_profile(r)
    }

    /// `∫ 2πr Rn dr = A(α) − α/5.108`.
    pub fn multiple_albedo(&self) -> f32 {
        self.full().0 - self.single().0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// Paper 000's R(r; α) written out from the slide in f64, independently of the module.
    fn slide_r(r: f64, alpha: f64, mfp: f64) -> f64 {
        let q = (1.0 - alpha).sqrt();
        let a = (1.0 - q) / (1.554 * q + 1.0);
        let s = 1.85 - a + 7.0 * (a - 0.8).abs().powi(3);
        a * s * ((-r * s / mfp).exp() + (-s * r / (3.0 * mfp)).exp()) / (8.0 * PI * mfp * r)
    }

    /// R1/α equals ∂R/∂α at α = 0 by a second-order one-sided difference (h = 1e-5, f64) at
    /// several r and ℓ, to 1e-5 relative; R itself matches the slide formula.
    #[test]
    fn single_is_first_taylor_term() {
        let h = 1e-5;
        for mfp in [0.2f32, 1.0, 3.0] {
            for r in [0.01f32, 0.1, 0.5, 1.0, 2.0] {
                let (r64, l64) = (r as f64, mfp as f64);
                let derivative = (-3.0 * slide_r(r64, 0.0, l64) + 4.0 * slide_r(r64, h, l64)
                    - slide_r(r64, 2.0 * h, l64))
                    / (2.0 * h);
                for alpha in [0.05f32, 0.5, 0.9] {
                    let orders = ScatteringOrders { alpha, mfp };
                    let r1 = orders.single_profile(r) as f64 / alpha as f64;
                    assert!(
                        ((r1 - derivative) / derivative).abs() < 1e-5,
                        "ℓ = {mfp}, r = {r}, α = {alpha}: R1/α = {r1}, ∂R/∂α = {derivative}"
                    );
                    let full = slide_r(r64, alpha as f64, l64);
                    let ours = orders.full_profile(r) as f64;
                    assert!(
                        ((ours - full) / full).abs() < 1e-5,
                        "R: {ours} vs slide {full}"
                    );
                }
            }
        }
    }

    /// R1 + Rn = R everywhere; Rn integrates to A(α) − α/5.108 (Simpson in ln r, f64).
    #[test]
    fn multiple_completes_full() {
        let orders = ScatteringOrders {
            alpha: 0.7,
            mfp: 1.0,
        };
        let (t0, t1, n) = ((1e-9f64).ln(), (200.0f64).ln(), 20_000usize);
        let step = (t1 - t0) / n as f64;
        let f = |t: f64| {
            let r = t.exp();
            2.0 * PI * r * r * orders.multiple_profile(r as f32) as f64
        };
        let mut sum = f(t0) + f(t1);
        for i in 1..n {
            sum += f(t0 + i as f64 * step) * if i % 2 == 1 { 4.0 } else { 2.0 };
        }
        let total = sum * step / 3.0;
        let want = orders.multiple_albedo() as f64;
        assert!((total - want).abs() < 1e-4, "∫ Rn = {total}, want {want}");
        for r in [1e-3f32, 0.1, 1.0, 10.0] {
            let sum = orders.single_profile(r) + orders.multiple_profile(r);
            assert!((sum - orders.full_profile(r)).abs() <= 1e-6 * orders.full_profile(r));
        }
    }

    /// The documented sign of Rn near r = 0: non-negative for α = 0.2, negative for α = 0.5, 0.9.
    #[test]
    fn multiple_sign_near_origin() {
        let r = 1e-4;
        assert!(
            ScatteringOrders {
                alpha: 0.2,
                mfp: 1.0
            }
            .multiple_profile(r)
                > 0.0
        );
        assert!(
            ScatteringOrders {
                alpha: 0.5,
                mfp: 1.0
            }
            .multiple_profile(r)
                < 0.0
        );
        assert!(
            ScatteringOrders {
                alpha: 0.9,
                mfp: 1.0
            }
            .multiple_profile(r)
                < 0.0
        );
    }
}
