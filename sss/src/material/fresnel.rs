//! Fresnel terms of a smooth dielectric boundary: the exact unpolarised reflectance, its
//! cosine-weighted hemispherical average, and the normalised Fresnel transmittance `F_t` of the
//! BSSRDF [001 Eq. 2] (DESIGN §9).
//!
//! **The BSSRDF's `F_t`.** `S = (A/π) R̄(r) F_t(μo) F_t(μi)` with
//! `F_t(μ) = (1 − F(μ, η)) / (1 − F_dr(η))`: the dielectric transmittance of light arriving at
//! cosine `μ` from outside [Jensen et al. 2001, Eq. 5], divided by its cosine-weighted
//! hemispherical average `1 − F_dr(η) = 2∫₀¹ (1 − F(μ, η)) μ dμ` — pbrt-v3's `S_ω` normalisation
//! (§11.4.1; pbrt-v4 `NormalizedFresnelBxDF`), applied at both ends so that `S` stays
//! reciprocal. The property this buys, and which reshift relies on: `∫ F_t(μ) 2μ dμ = 1`, so under
//! uniform illumination the BSSRDF reflects exactly `A` (the material's albedo keeps its meaning
//! of total diffuse reflectance for every `η`); `η` only shapes the angular distribution, and
//! `η = 1` gives `F_t ≡ 1` (Lambertian transmission).
//!
//! `F_dr(η)` has a closed form (the hemispherical reflectance of a dielectric, Stern 1964, Appl.
//! Opt. 3(1)); it is evaluated in `f64` ([`diffuse_reflectance`]) and checked against quadrature
//! in the tests. Its GLSL twin is `sss/glsl/fresnel.glsl`; the device receives `1 − F_dr(η)` from
//! the host (`GpuMaterial::fresnel_normalization`).

/// Unpolarised Fresnel reflectance of a smooth dielectric for light arriving with
/// `cos_i = cos θ_i ≥ 0` on the incident side, `eta = η_transmitted / η_incident`.
/// Returns 1 under total internal reflection.
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let r_parallel = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_perpendicular = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    0.5 * (r_parallel * r_parallel + r_perpendicular * r_perpendicular)
}

/// `F_dr(η) = 2∫₀¹ F(μ, η) μ dμ`: the cosine-weighted hemispherical reflectance of a smooth
/// dielectric (relative index `eta > 0`) for light arriving from outside. For `η ≥ 1` the closed
/// form of Stern (1964); for `η < 1` the reciprocity `1 − F_dr(η) = η² (1 − F_dr(1/η))`
/// (hemispherical transmittance is the same both ways in étendue).
pub fn diffuse_reflectance(eta: f32) -> f32 {
    let n = eta as f64;
    if n < 1.0 {
        return (1.0 - n * n * (1.0 - diffuse_reflectance_dense((1.0 - n) / n))) as f32;
    }
    diffuse_reflectance_dense(n - 1.0) as f32
}

/// [`diffuse_reflectance`] of `n = 1 + excess ≥ 1`, in `f64`. The closed form adds terms of size
/// `1/(n − 1)` that cancel, so every factor that vanishes at `n = 1` is written through the exact
/// `excess` (`n⁴ − 1 = ε(n + 1)(n² + 1)`, `ln n = ln_1p(ε)`): the absolute error stays below
/// 1e-9 down to `ε = 2⁻²³` (tested against quadrature near 1).
fn diffuse_reflectance_dense(excess: f64) -> f64 {
    if excess <= 0.0 {
        return 0.0;
    }
    let n = 1.0 + excess;
    let (n2, n4) = (n * n, n * n * n * n);
    let n2_minus_1 = excess * (n + 1.0);
    let n4_minus_1 = n2_minus_1 * (n2 + 1.0);
    0.5 + excess * (3.0 * n + 1.0) / (6.0 * (n + 1.0) * (n + 1.0))
        + n2 * n2_minus_1 * n2_minus_1 / ((n2 + 1.0) * (n2 + 1.0) * (n2 + 1.0))
            * (excess / (n + 1.0)).ln()
        - 2.0 * n2 * n * (n2 + 2.0 * n - 1.0) / ((n2 + 1.0) * n4_minus_1)
        + 8.0 * n4 * (n4 + 1.0) / ((n2 + 1.0) * n4_minus_1 * n4_minus_1) * excess.ln_1p()
}

/// The normalised Fresnel transmittance `F_t(μ) = (1 − F(μ, η)) / (1 − F_dr(η))` of a material
/// (module doc). `normalization = 1 − F_dr(η)` is computed once ([`FresnelTransmission::new`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FresnelTransmission {
    pub eta: f32,
    /// `1 − F_dr(η)`, in (0, 1].
    pub normalization: f32,
}

impl FresnelTransmission {
    /// `eta` must be finite and > 0 (materials validate `ior`).
    pub fn new(eta: f32) -> FresnelTransmission {
        FresnelTransmission {
            eta,
            normalization: 1.0 - diffuse_reflectance(eta),
        }
    }

    /// `F_t(μ)` for the cosine `μ` between the normal and the outside direction; `μ` is clamped to
    /// [0, 1], so `F_t(μ ≤ 0) = 0` (grazing light is reflected entirely).
    pub fn eval(&self, mu: f32) -> f32 {
        (1.0 - fresnel_dielectric(mu, self.eta)) / self.normalization
    }
}

#[cfg(test)]
/// Test reference: the textbook form of the unpolarised Fresnel reflectance, through the angles:
/// `½ (sin²(θi − θt)/sin²(θi + θt) + tan²(θi − θt)/tan²(θi + θt))` (f64), independent of
/// [`fresnel_dielectric`]'s cosine form; 1 beyond the critical angle.
pub(crate) fn fresnel_by_angles(cos_i: f64, eta: f64) -> f64 {
    let theta_i = cos_i.clamp(0.0, 1.0).acos();
    let sin_t = theta_i.sin() / eta;
    if sin_t >= 1.0 {
        return 1.0;
    }
    if theta_i == 0.0 {
        return ((eta - 1.0) / (eta + 1.0)).powi(2);
    }
    let theta_t = sin_t.asin();
    let (d, s) = (theta_i - theta_t, theta_i + theta_t);
    0.5 * ((d.sin() / s.sin()).powi(2) + (d.tan() / s.tan()).powi(2))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `2∫₀¹ F(μ, η) μ dμ` by the midpoint rule on 200 000 panels, split at the critical cosine
    /// for `η < 1` (where `F` has a kink), in f64.
    fn diffuse_reflectance_by_quadrature(eta: f64) -> f64 {
        let integrate = |a: f64, b: f64| {
            let n = 200_000;
            let h = (b - a) / n as f64;
            (0..n)
                .map(|i| {
                    let mu = a + (i as f64 + 0.5) * h;
                    fresnel_by_angles(mu, eta) * mu
                })
                .sum::<f64>()
                * h
        };
        let critical = if eta < 1.0 {
            (1.0 - eta * eta).sqrt()
        } else {
            0.0
        };
        2.0 * (integrate(0.0, critical) + integrate(critical, 1.0))
    }

    #[test]
    fn reflectance_matches_the_angle_form() {
        for eta in [1.0f32 / 1.4, 1.0, 1.2, 1.4, 2.4] {
            for cos_i in [1.0f32, 0.9, 0.7, 0.5, 0.3, 0.1, 0.02] {
                let want = fresnel_by_angles(cos_i as f64, eta as f64);
                let got = fresnel_dielectric(cos_i, eta) as f64;
                assert!(
                    (got - want).abs() < 2e-6,
                    "η = {eta}, cos = {cos_i}: {got} vs {want}"
                );
            }
        }
        assert_eq!(fresnel_dielectric(0.0, 1.4), 1.0);
        // Beyond the critical angle (sin θc = 1/1.5) from inside: total internal reflection.
        assert_eq!(fresnel_dielectric(0.7, 1.0 / 1.5), 1.0);
    }

    /// The closed form (and the reciprocity branch below 1) against quadrature of the angle form,
    /// absolute 2e-8 (the quadrature's own error), from far from 1 down to one f32 step off 1.
    #[test]
    fn diffuse_reflectance_matches_quadrature() {
        let step = f32::EPSILON;
        for eta in [
            0.5f32,
            0.75,
            0.9,
            0.9995,
            1.0 - step,
            1.0,
            1.0 + step,
            1.0005,
            1.1,
            1.4,
            2.5,
        ] {
            let want = diffuse_reflectance_by_quadrature(eta as f64);
            let got = diffuse_reflectance(eta) as f64;
            assert!(
                (got - want).abs() < 2e-8,
                "η = {eta}: closed form {got}, quadrature {want}"
            );
        }
    }

    /// `F_t` is the exact dielectric transmittance divided by a constant: at several angles
    /// `F_t(μ) (1 − F_dr) = 1 − F(μ)` (F from the angle form), and its cosine-weighted
    /// hemispherical integral `∫ F_t(μ) 2μ dμ` is 1 (midpoint rule, 100 000 panels) for every η;
    /// `η = 1` gives `F_t ≡ 1`. Negative control: the previous η-free `1 − ½(1 − μ)⁵` is not
    /// normalised (its integral is 41/42, measured below 0.98).
    #[test]
    fn transmission_is_normalised_fresnel() {
        let hemispherical = |f: &dyn Fn(f32) -> f32| {
            let n = 100_000;
            (0..n)
                .map(|i| {
                    let mu = (i as f64 + 0.5) / n as f64;
                    2.0 * mu * f(mu as f32) as f64
                })
                .sum::<f64>()
                / n as f64
        };
        for eta in [0.8f32, 1.0, 1.3, 1.4, 1.6] {
            let ft = FresnelTransmission::new(eta);
            for mu in [1.0f32, 0.8, 0.5, 0.2, 0.05] {
                let want = 1.0 - fresnel_by_angles(mu as f64, eta as f64);
                let got = (ft.eval(mu) * ft.normalization) as f64;
                assert!(
                    (got - want).abs() < 2e-6,
                    "η = {eta}, μ = {mu}: {got} vs {want}"
                );
            }
            let total = hemispherical(&|mu| ft.eval(mu));
            assert!(
                (total - 1.0).abs() < 1e-5,
                "η = {eta}: ∫ F_t 2μ dμ = {total}"
            );
            assert_eq!(ft.eval(-0.3), 0.0);
        }
        let index_matched = FresnelTransmission::new(1.0);
        assert_eq!(index_matched.normalization, 1.0);
        assert!((index_matched.eval(0.37) - 1.0).abs() < 1e-6);
        let schlick_like = hemispherical(&|mu| 1.0 - 0.5 * (1.0 - mu).powi(5));
        assert!(
            (schlick_like - 41.0 / 42.0).abs() < 1e-6 && schlick_like < 0.98,
            "control: {schlick_like}"
        );
    }
}
