//! Measured scattering coefficients of Jensen, Marschner, Levoy & Hanrahan 2001 (Table "measured
//! parameters"; σs′ and σa in mm⁻¹ per RGB, η = 1.3) as [`Translucent`] presets.
//!
//! Conversion `(σs′, σa) → (A, ℓ)` per channel: `σt′ = σs′ + σa`, `ℓ = 1/σt′` (the reduced volume
//! mean free path, so the presets use [`ScaleFit::Searchlight`] and `g = 0`: the reduced
//! coefficients already fold the anisotropy in), `α′ = σs′/σt′`, and `A = R_d(α′)` the dipole's
//! total diffuse reflectance ([`total_diffuse_reflectance`]). The inverse `(A, ℓ) → (σs′, σa)`
//! solves `R_d(α′) = A` for `α′` (defined for every `A ∈ [0, 1]`, `R_d` being increasing from 0 to 1).
//! Lengths are in mm with `scale = 1`; a scene in other units sets `scale`.

use glam::Vec3;

use super::{BoundaryKind, Translucent};
use crate::profile::ScaleFit;
use crate::profile::dipole::{reduced_albedo_from_reflectance, total_diffuse_reflectance};

/// Relative index of refraction of all presets (Jensen et al. 2001).
pub const MEASURED_IOR: f32 = 1.3;

/// `(name, σs′ [mm⁻¹], σa [mm⁻¹])` per RGB; "chicken" is Jensen's "Chicken1".
const TABLE: &[(&str, [f64; 3], [f64; 3])] = &[
    ("marble", [2.19, 2.62, 3.00], [0.0021, 0.0041, 0.0071]),
    ("skin1", [0.74, 0.88, 1.01], [0.032, 0.17, 0.48]),
    ("skin2", [1.09, 1.59, 1.79], [0.013, 0.070, 0.145]),
    ("ketchup", [0.18, 0.07, 0.03], [0.061, 0.97, 1.45]),
    ("apple", [2.29, 2.39, 1.97], [0.0030, 0.0034, 0.046]),
    ("potato", [0.68, 0.70, 0.55], [0.0024, 0.0090, 0.12]),
    ("chicken", [0.15, 0.21, 0.38], [0.015, 0.077, 0.19]),
    ("cream", [7.38, 5.47, 3.15], [0.0002, 0.0028, 0.0163]),
    ("wholemilk", [2.55, 3.21, 3.77], [0.0011, 0.0024, 0.014]),
    ("skimmilk", [0.70, 1.22, 1.90], [0.0014, 0.0025, 0.0142]),
];

/// The preset names accepted by [`measured`].
pub const MEASURED_NAMES: &[&str] = &[
    "marble",
    "skin1",
    "skin2",
    "ketchup",
    "apple",
    "potato",
    "chicken",
    "cream",
    "wholemilk",
    "skimmilk",
];

/// `(σs′, σa) → (A, ℓ)` for one channel (module doc), in f64.
pub fn albedo_mfp_from_coefficients(sigma_s_reduced: f64, sigma_a: f64, eta: f64) -> (f64, f64) {
    let sigma_t_reduced = sigma_s_reduced + sigma_a;
    let reduced_albedo = sigma_s_reduced / sigma_t_reduced;
    (
        total_diffuse_reflectance(reduced_albedo, eta),
        1.0 / sigma_t_reduced,
    )
}

/// `(A, ℓ) → (σs′, σa)` for one channel, the inverse of [`albedo_mfp_from_coefficients`].
pub fn coefficients_from_albedo_mfp(albedo: f64, mfp: f64, eta: f64) -> (f64, f64) {
    let reduced_albedo = reduced_albedo_from_reflectance(albedo, eta);
    let sigma_t_reduced = 1.0 / mfp;
    (
        reduced_albedo * sigma_t_reduced,
        (1.0 - reduced_albedo) * sigma_t_reduced,
    )
}

/// The Jensen et al. 2001 preset `name` (case-insensitive), or `None` for an unknown name.
pub fn measured(name: &str) -> Option<Translucent> {
    let (_, sigma_s, sigma_a) = TABLE
        .iter()
        .find(|(n, _, _)| n.eq_ignore_ascii_case(name))?;
    let mut albedo = [0.0f32; 3];
    let mut mfp = [0.0f32; 3];
    for c in 0..3 {
        let (a, l) = albedo_mfp_from_coefficients(sigma_s[c], sigma_a[c], MEASURED_IOR as f64);
        albedo[c] = a as f32;
        mfp[c] = l as f32;
    }
    Some(Translucent {
        albedo: Vec3::from_array(albedo),
        mfp: Vec3::from_array(mfp),
        scale: 1.0,
        ior: MEASURED_IOR,
        g: 0.0,
        fit: ScaleFit::Searchlight,
        boundary: BoundaryKind::Diffuse,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    #[test]
    fn names_match_table_and_presets_validate() {
        let table_names: Vec<&str> = TABLE.iter().map(|(n, _, _)| *n).collect();
        assert_eq!(table_names, MEASURED_NAMES);
        for name in MEASURED_NAMES {
            let m = measured(name).expect(name);
            assert_eq!(m.validate(Path::new("presets"), name), Ok(()));
            assert_eq!(measured(&name.to_uppercase()), Some(m));
        }
        assert_eq!(measured("granite"), None);
    }

    /// (σs′, σa) → (A, ℓ) → (σs′, σa) in f64 reproduces the table to 1e-9 relative, and ℓ = 1/σt′.
    #[test]
    fn conversion_round_trip() {
        for (name, sigma_s, sigma_a) in TABLE {
            for c in 0..3 {
                let (a, l) = albedo_mfp_from_coefficients(sigma_s[c], sigma_a[c], 1.3);
                assert!(a > 0.0 && a < 1.0, "{name}[{c}]: A = {a}");
                assert!((l * (sigma_s[c] + sigma_a[c]) - 1.0).abs() < 1e-12);
                let (s_back, a_back) = coefficients_from_albedo_mfp(a, l, 1.3);
                let rel = |x: f64, y: f64| ((x - y) / y).abs();
                assert!(
                    rel(s_back, sigma_s[c]) < 1e-9,
                    "{name}[{c}]: σs′ {s_back} vs {}",
                    sigma_s[c]
                );
                assert!(
                    rel(a_back, sigma_a[c]) < 1e-9,
                    "{name}[{c}]: σa {a_back} vs {}",
                    sigma_a[c]
                );
            }
        }
    }
}
