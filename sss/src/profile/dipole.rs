//! Jensen et al. 2001 classical dipole [002 Table 1]: the radial profile `R_d(r)`, its total
//! diffuse reflectance [002 Eq. 7], and the exact (Newton) radius sampling of [002 §4].
//!
//! Sampling follows [002 §4]: pick the real or the virtual pole with probability proportional to
//! its integrated reflectance `e^{−σ_tr z}`, then invert that pole's radius CDF
//! `F_z(r) = 1 − (z/s) e^{−σ_tr (s − z)}`, `s = √(r² + z²)` [002 Eq. 6]. With `u = s/z = e^{t}` the
//! equation `F_z(r) = ξ` reads `σ_tr z (e^{t} − 1) + t + ln(1 − ξ) = 0`; its left side is increasing
//! and convex in `t`, and dropping either positive term bounds the root from above, so Newton from
//! the smaller bound converges monotonically. Then `r = z √(e^{2t} − 1)`. The mixture's radius
//! density is `2πr R_d(r) / ρ` ([`Dipole::pdf_radius`]) and its CDF [`Dipole::cdf`].

use std::f32::consts::PI;

use crate::contract::dipole::NEWTON_ITERATIONS;
pub use crate::contract::dipole::Pole;

/// Diffuse Fresnel reflectance `F_dr(η) = −1.440/η² + 0.710/η + 0.668 + 0.0636η` (Jensen et al.
/// 2001's fit; η = relative index of refraction of the medium).
pub fn fresnel_diffuse_reflectance(eta: f64) -> f64 {
    -1.440 / (eta * eta) + 0.710 / eta + 0.668 + 0.0636 * eta
}

/// The boundary term `A = (1 + F_dr) / (1 − F_dr)` [002 Table 1].
pub fn boundary_a(eta: f64) -> f64 {
    let f_dr = fresnel_diffuse_reflectance(eta);
    (1.0 + f_dr) / (1.0 - f_dr)
}

/// Total diffuse reflectance of the dipole for the reduced albedo `α′ = σs′/σt′` [002 Eq. 7]:
/// `ρ = (α′/2)(1 + e^{−(4/3)A√(3(1−α′))}) e^{−√(3(1−α′))}` (`σ_tr z_r = √(3(1−α′))`,
/// `z_v = z_r(1 + 4A/3)`). Increasing in `α′`, 0 at 0 and 1 at 1.
pub fn total_diffuse_reflectance(reduced_albedo: f64, eta: f64) -> f64 {
    let s = (3.0 * (1.0 - reduced_albedo).max(0.0)).sqrt();
    0.5 * reduced_albedo * (1.0 + (-(4.0 / 3.0) * boundary_a(eta) * s).exp()) * (-s).exp()
}

/// The reduced albedo `α′` whose [`total_diffuse_reflectance`] is `reflectance` (clamped to
/// [0, 1]), by bisection to f64 resolution on the increasing map.
pub fn reduced_albedo_from_reflectance(reflectance: f64, eta: f64) -> f64 {
    let target = reflectance.clamp(0.0, 1.0);
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    loop {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            return mid;
        }
        if total_diffuse_reflectance(mid, eta) < target {
            lo = mid
        } else {
            hi = mid
        }
    }
}

/// The largest `f32` below 1 (keeps remapped uniforms inside [0, 1)).
const ONE_MINUS_EPSILON: f32 = 1.0 - 1.0 / 16_777_216.0;

/// The dipole of one channel, from reduced scattering `σs′`, absorption `σa` (inverse length)
/// and relative IOR `η` [002 Table 1].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dipole {
    reduced_albedo: f32,
    sigma_tr: f32,
    z_r: f32,
    z_v: f32,
}

impl Dipole {
    /// Requires `σs′ ≥ 0`, `σa ≥ 0`, `σs′ + σa > 0`, `η > 0`, all finite.
    pub fn new(sigma_s_reduced: f32, sigma_a: f32, eta: f32) -> Dipole {
        let sigma_t_reduced = sigma_s_reduced + sigma_a;
        debug_assert!(sigma_s_reduced >= 0.0 && sigma_a >= 0.0 && sigma_t_reduced > 0.0);
        let z_r = 1.0 / sigma_t_reduced;
        Dipole {
            reduced_albedo: sigma_s_reduced / sigma_t_reduced,
            sigma_tr: (3.0 * sigma_a * sigma_t_reduced).sqrt(),
            z_r,
            z_v: z_r * (1.0 + 4.0 / 3.0 * boundary_a(eta as f64) as f32),
        }
    }

    /// The depth of `pole`: `z_r` below the surface or `z_v` above it.
    pub fn depth(&self, pole: Pole) -> f32 {
        match pole {
            Pole::Real => self.z_r,
            Pole::Virtual => self.z_v,
        }
    }

    /// The reduced albedo `α′ = σs′/σt′`.
    pub fn reduced_albedo(&self) -> f32 {
        self.reduced_albedo
    }

    /// The effective transport coefficient `σ_tr = √(3 σa σt′)`.
    pub fn sigma_tr(&self) -> f32 {
        self.sigma_tr
    }

    /// `R_d(r) = α′/(4π) Σ_z z(1 + σ_tr s)e^{−σ_tr s}/s³` over both poles [002 Table 1].
    pub fn profile(&self, r: f32) -> f32 {
        let term = |z: f32| {
            let s = r.hypot(z);
            z * (1.0 + self.sigma_tr * s) * (-self.sigma_tr * s).exp() / (s * s * s)
        };
        self.reduced_albedo / (4.0 * PI) * (term(self.z_r) + term(self.z_v))
    }

    /// `ρ = ∫ 2πr R_d(r) dr = (α′/2)(e^{−σ_tr z_r} + e^{−σ_tr z_v})` [002 Eq. 7].
    pub fn total_reflectance(&self) -> f32 {
        0.5 * self.reduced_albedo * self.pole_mass(Pole::Real)
            + 0.5 * self.reduced_albedo * self.pole_mass(Pole::Virtual)
    }

    /// `e^{−σ_tr z}`: the integral of one pole's term, up to the common factor `α′/2`.
    fn pole_mass(&self, pole: Pole) -> f32 {
        (-self.sigma_tr * self.depth(pole)).exp()
    }

    /// Probability of choosing `pole` in [`Dipole::sample_radius`] [002 §4].
    pub fn pole_probability(&self, pole: Pole) -> f32 {
        self.pole_mass(pole) / (self.pole_mass(Pole::Real) + self.pole_mass(Pole::Virtual))
    }

    /// Disk-area density of the sampler, `R_d(r) / ρ`; 0 for `r < 0` or `ρ = 0`.
    pub fn pdf_disk(&self, r: f32) -> f32 {
        let rho = self.total_reflectance();
        if !(r >= 0.0 && rho > 0.0) {
            return 0.0;
        }
        self.profile(r) / rho
    }

    /// Radius density `2πr R_d(r) / ρ`.
    pub fn pdf_radius(&self, r: f32) -> f32 {
        2.0 * PI * r.max(0.0) * self.pdf_disk(r)
    }

    /// One pole's radius CDF `F_z(r) = 1 − (z/s)e^{−σ_tr(s − z)}` [002 Eq. 6–7], written as
    /// `1 − exp(−σ_tr r²/(s + z) − ½ ln(1 + r²/z²))` so that it keeps its digits as `r → 0`.
    pub fn pole_cdf(&self, pole: Pole, r: f32) -> f32 {
        if r.is_nan() || r <= 0.0 {
            return 0.0;
        }
        let z = self.depth(pole);
        let s = r.hypot(z);
        let ratio = r / z;
        -(-(self.sigma_tr * r * r / (s + z) + 0.5 * (ratio * ratio).ln_1p())).exp_m1()
    }

    /// The mixture CDF of [`Dipole::sample_radius`], `Σ_pole P(pole) F_{z_pole}(r)`.
    pub fn cdf(&self, r: f32) -> f32 {
        let p_real = self.pole_probability(Pole::Real);
        p_real * self.pole_cdf(Pole::Real, r) + (1.0 - p_real) * self.pole_cdf(Pole::Virtual, r)
    }

    /// The exact inverse of [`Dipole::pole_cdf`] by monotone Newton on `t = ln(s/z)` (module doc).
    /// `ξ ≤ 0` gives 0, `ξ ≥ 1` gives `+∞`.
    pub fn sample_pole(&self, pole: Pole, xi: f32) -> f32 {
        if xi.is_nan() || xi <= 0.0 {
            return 0.0;
        }
        if xi >= 1.0 {
            return f32::INFINITY;
        }
        let z = self.depth(pole);
        let a = self.sigma_tr * z;
        let log_survival = -(-xi).ln_1p();
        let mut t = if a > 0.0 {
            log_survival.min((log_survival / a).ln_1p())
        } else {
            log_survival
        };
        for _ in 0..NEWTON_ITERATIONS {
            let e = t.exp_m1();
            let h = a * e + t - log_survival;
            let step = h / (a * (e + 1.0) + 1.0);
            t -= step;
            if step.is_nan() || step.abs() <= f32::EPSILON * t {
                break;
            }
        }
        z * (2.0 * t).exp_m1().max(0.0).sqrt()
    }

    /// [002 §4]: choose a pole by `u` against [`Dipole::pole_probability`], rescale `u` and invert
    /// that pole's CDF. The density of the result is [`Dipole::pdf_radius`].
    pub fn sample_radius(&self, u: f32) -> f32 {
        let p_real = self.pole_probability(Pole::Real);
        if u < p_real {
            self.sample_pole(Pole::Real, (u / p_real).min(ONE_MINUS_EPSILON))
        } else {
            self.sample_pole(
                Pole::Virtual,
                ((u - p_real) / (1.0 - p_real)).min(ONE_MINUS_EPSILON),
            )
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::profile::test_support::draw;
    use restir::stats::ks_one_sample;

    /// (σs′, σa, η) covering low and high absorption (mm⁻¹; skin1 red, ketchup green, cream red).
    const CASES: [(f32, f32, f32); 4] = [
        (0.74, 0.032, 1.3),
        (0.07, 0.97, 1.3),
        (7.38, 0.0002, 1.3),
        (1.0, 0.1, 1.5),
    ];

    /// Simpson in t = ln r of `f(r)·r` over [r0, r1] (f64).
    fn integrate_log(f: impl Fn(f64) -> f64, r0: f64, r1: f64, n: usize) -> f64 {
        let (t0, t1) = (r0.ln(), r1.ln());
        let h = (t1 - t0) / n as f64;
        let g = |t: f64| f(t.exp()) * t.exp();
        let mut sum = g(t0) + g(t1);
        for i in 1..n {
            sum += g(t0 + i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
        }
        sum * h / 3.0
    }

    /// ∫ 2πr R_d(r) dr equals the closed form ρ [002 Eq. 7] to 1e-4 relative, and ρ equals
    /// [`total_diffuse_reflectance`] of α′.
    #[test]
    fn profile_integrates_to_total_reflectance() {
        for (s, a, eta) in CASES {
            let dip = Dipole::new(s, a, eta);
            let z_r = 1.0 / (s + a) as f64;
            let sigma_tr = (3.0 * a as f64 * (s + a) as f64).sqrt();
            // The tail beyond r1 is below z_v/r1 (1/r² decay) and e^{−σ_tr r1}.
            let r1 = (z_r * 1e7).min(60.0 / sigma_tr);
            let quad = integrate_log(
                |r| 2.0 * std::f64::consts::PI * r * dip.profile(r as f32) as f64,
                z_r * 1e-8,
                r1,
                40_000,
            );
            let rho = dip.total_reflectance() as f64;
            assert!(
                ((quad - rho) / rho).abs() < 1e-4,
                "{s}, {a}, {eta}: quadrature {quad}, ρ = {rho}"
            );
            let (s64, a64) = (s as f64, a as f64);
            let closed = total_diffuse_reflectance(s64 / (s64 + a64), eta as f64);
            assert!(
                ((closed - rho) / rho).abs() < 1e-5,
                "ρ = {rho} vs closed form {closed}"
            );
        }
    }

    /// The mixture CDF is the integral of pdf_radius: CDF(b) − CDF(a) vs Simpson.
    #[test]
    fn cdf_is_integral_of_pdf() {
        for (s, a, eta) in CASES {
            let dip = Dipole::new(s, a, eta);
            let z = 1.0 / (s + a) as f64;
            for (r0, r1) in [(z * 1e-3, z * 0.5), (z * 0.5, z * 3.0), (z * 3.0, z * 20.0)] {
                let quad = integrate_log(|r| dip.pdf_radius(r as f32) as f64, r0, r1, 4000);
                let diff = dip.cdf(r1 as f32) as f64 - dip.cdf(r0 as f32) as f64;
                assert!(
                    (quad - diff).abs() < 2e-6,
                    "{s}, {a}: [{r0}, {r1}] {quad} vs {diff}"
                );
            }
        }
    }

    /// pole_cdf(sample_pole(ξ)) = ξ to 1e-6 relative for ξ from 1e-7 to 1 − 2⁻²⁴, both poles.
    #[test]
    fn newton_inverse_round_trip() {
        for (s, a, eta) in CASES {
            let dip = Dipole::new(s, a, eta);
            let mut xis: Vec<f32> = (1..1000).map(|i| i as f32 / 1000.0).collect();
            xis.extend([1e-7, 1e-5, 1e-3, 0.999_99, ONE_MINUS_EPSILON]);
            for pole in [Pole::Real, Pole::Virtual] {
                for &xi in &xis {
                    let r = dip.sample_pole(pole, xi);
                    assert!(r.is_finite() && r > 0.0, "{pole:?}, ξ = {xi}: r = {r}");
                    let back = dip.pole_cdf(pole, r);
                    assert!(
                        ((back - xi) / xi).abs() < 1e-6,
                        "{s}, {a}, {pole:?}, ξ = {xi}: F(r) = {back}"
                    );
                }
            }
        }
    }

    /// The conversion used by the measured presets inverts: α′ → ρ → α′ to 1e-12.
    #[test]
    fn reduced_albedo_inverse() {
        for eta in [1.0, 1.3, 1.5] {
            for i in 0..=100 {
                let alpha = i as f64 / 100.0;
                let back =
                    reduced_albedo_from_reflectance(total_diffuse_reflectance(alpha, eta), eta);
                assert!(
                    (back - alpha).abs() < 1e-12,
                    "η = {eta}, α′ = {alpha}: {back}"
                );
            }
        }
    }

    /// KS of N = 10⁵ Newton-sampled radii (`next_f32`, seed 2001) against the mixture CDF, i.e.
    /// the radius density 2πr R_d / ρ, α = 1e-3, for each case. Negative control: radii from a
    /// dipole with σs′ and σa scaled by 1.05 (all lengths shrunk by 1/1.05) are rejected by the
    /// same test.
    #[test]
    fn newton_samples_follow_profile() {
        const N: usize = 100_000;
        const ALPHA: f64 = 1e-3;
        for (i, (s, a, eta)) in CASES.into_iter().enumerate() {
            let dip = Dipole::new(s, a, eta);
            let purpose = 10 + 2 * i as u32;
            let good = ks_one_sample(&draw(N, purpose, |u| dip.sample_radius(u)), |r| {
                dip.cdf(r as f32) as f64
            });
            assert!(
                good.p_value > ALPHA,
                "({s}, {a}, {eta}) rejected (N = {N}, α = {ALPHA}): {good:?}"
            );
            let wrong = Dipole::new(1.05 * s, 1.05 * a, eta);
            let bad = ks_one_sample(&draw(N, purpose + 1, |u| wrong.sample_radius(u)), |r| {
                dip.cdf(r as f32) as f64
            });
            assert!(
                bad.p_value < ALPHA,
                "({s}, {a}, {eta}) control 1.05 (σs′, σa) not rejected (N = {N}, α = {ALPHA}): {bad:?}"
            );
        }
    }
}
