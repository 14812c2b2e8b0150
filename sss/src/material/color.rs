//! Paper 000's artist mapping from a colour `C` and a scatter distance `mfp` to volume coefficients
//! [000, "Parameters"; after Kulla & Conty 2017]:
//! `S = 4.09712 + 4.20863C − √(9.59217 + 41.6808C + 17.7126C²)`, single-scattering albedo
//! `α = (1 − S²)/(1 − gS²)`, `σt = 1/mfp`, `σs = α/mfp` (per channel, `C ∈ [0, 1]`).
//!
//! `S(C)` decreases on [0, 1] from `S(0) ≈ 0.999997` to `S(1) ≈ −5·10⁻⁶`; because of the rounded
//! constants `α(C=0) ≈ 6·10⁻⁶` (smaller `α` have no colour) and `S` crosses 0 at
//! `C* ≈ 1 − 1.2·10⁻⁵`, where `α = 1`. So `α` increases on `[0, C*]` and the inverse maps
//! `[α(0, g), 1]` onto `[0, C*]` (colours in `(C*, 1]` alias to `C* − (C − C*)`). The inverse solves `S² = (1 − α)/(1 − gα)` and then the quadratic
//! `(S − 4.09712 − 4.20863C)² = 9.59217 + 41.6808C + 17.7126C²` for `C` (its leading coefficient
//! `4.20863² − 17.7126 ≈ −3·10⁻⁵` makes it nearly linear, so the small root is taken in the
//! cancellation-free form `2c₀ / (−c₁ ∓ √(c₁² − 4c₂c₀))`). Host-side parameter setup, in f64.

use glam::Vec3;

const K0: f64 = 4.09712;
const K1: f64 = 4.20863;
const Q0: f64 = 9.59217;
const Q1: f64 = 41.6808;
const Q2: f64 = 17.7126;

/// The intermediate `S(C)` of the mapping.
fn s_of_color(color: f64) -> f64 {
    K0 + K1 * color - (Q0 + Q1 * color + Q2 * color * color).sqrt()
}

/// Single-scattering albedo `α(C, g)`; `color` clamped to [0, 1], `|g| < 1`.
pub fn single_scattering_albedo(color: f64, g: f64) -> f64 {
    let s2 = s_of_color(color.clamp(0.0, 1.0)).powi(2);
    (1.0 - s2) / (1.0 - g * s2)
}

/// The colour `C ∈ [0, C*]` with `single_scattering_albedo(C, g) = alpha`, or `None` when `alpha`
/// lies outside `[α(0, g), 1]` or `|g| ≥ 1` (module doc).
pub fn color_from_single_scattering_albedo(alpha: f64, g: f64) -> Option<f64> {
    if !(0.0..=1.0).contains(&alpha) || g.is_nan() || g.abs() >= 1.0 {
        return None;
    }
    let s = ((1.0 - alpha) / (1.0 - g * alpha)).sqrt();
    let b = K0 - s;
    let (c2, c1, c0) = (K1 * K1 - Q2, 2.0 * K1 * b - Q1, b * b - Q0);
    let disc = c1 * c1 - 4.0 * c2 * c0;
    if disc < 0.0 {
        return None;
    }
    let q = -0.5 * (c1 + c1.signum() * disc.sqrt());
    let color = c0 / q;
    // At α = α(0, g) the root is 0 up to the round-off of c₀ (|c₀| ~ 1e-15), admitted here.
    (-1e-12..=1.0).contains(&color).then_some(color.max(0.0))
}

/// `(σt, σs)` per channel from colour `C`, scatter distance `mfp` (scene units) and `g`
/// [000, "Parameters"]: `σt = 1/mfp`, `σs = α(C, g)/mfp`.
pub fn volume_coefficients(color: Vec3, mfp: Vec3, g: f32) -> (Vec3, Vec3) {
    let sigma_t = Vec3::ONE / mfp;
    let alpha = Vec3::from_array(std::array::from_fn(|c| {
        single_scattering_albedo(color[c] as f64, g as f64) as f32
    }));
    (sigma_t, alpha * sigma_t)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// C → α → C to 1e-9 on a grid over [0, 0.999] for several g; α is increasing there.
    #[test]
    fn round_trip_and_monotone() {
        for g in [-0.5, 0.0, 0.3, 0.8] {
            let mut previous = -1.0;
            for i in 0..1000 {
                let color = i as f64 / 1000.0;
                let alpha = single_scattering_albedo(color, g);
                assert!(alpha > previous, "g = {g}: α not increasing at C = {color}");
                previous = alpha;
                let back = color_from_single_scattering_albedo(alpha, g)
                    .unwrap_or_else(|| panic!("g = {g}, C = {color}: α = {alpha} has no inverse"));
                assert!(
                    (back - color).abs() < 1e-9,
                    "g = {g}, C = {color}: back {back}"
                );
            }
        }
    }

    /// Ends of the map and the documented domain of the inverse.
    #[test]
    fn range_and_domain() {
        let (lo, hi) = (
            single_scattering_albedo(0.0, 0.0),
            single_scattering_albedo(1.0, 0.0),
        );
        assert!(lo > 0.0 && lo < 1e-5, "α(0) = {lo}");
        assert!(hi > 1.0 - 1e-9 && hi < 1.0, "α(1) = {hi}");
        assert_eq!(color_from_single_scattering_albedo(lo * 0.5, 0.0), None);
        assert_eq!(color_from_single_scattering_albedo(lo, 0.0), Some(0.0));
        let c_star = color_from_single_scattering_albedo(1.0, 0.0).expect("α = 1 has a colour");
        assert!(
            s_of_color(c_star).abs() < 1e-12 && c_star > 0.9999 && c_star < 1.0,
            "C* = {c_star}"
        );
        assert_eq!(color_from_single_scattering_albedo(1.5, 0.0), None);
        assert_eq!(color_from_single_scattering_albedo(0.5, 1.0), None);
        let (sigma_t, sigma_s) =
            volume_coefficients(Vec3::new(0.0, 0.5, 1.0), Vec3::splat(2.0), 0.0);
        assert_eq!(sigma_t, Vec3::splat(0.5));
        assert!((sigma_s.y as f64 - 0.5 * single_scattering_albedo(0.5, 0.0)).abs() < 1e-7);
    }
}
