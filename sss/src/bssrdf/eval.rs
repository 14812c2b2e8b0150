//! The BSSRDF `S`, the path contribution `f` and the target `p̂` (DESIGN §9 "BSSRDF").
//!
//! Normals: the Fresnel terms and the cosine use shading normals (x1's flipped toward the camera,
//! x2's as interpolated); `p_disk` and the probe axes use geometric normals.

use std::f32::consts::FRAC_1_PI;

use glam::Vec3;

use super::probe::{EntryPoint, ExitPoint};
use crate::color::luminance;
use crate::material::Translucent;

/// `S = (A/π) R̄_d(‖x1 − x2‖) F_t(n1·ωo) F_t(n2·ωi)` per channel [001 Eq. 2–3], truncated at
/// `r_max` of the widest channel (x1's cached profiles, equal to [`Translucent::profile_rgb`]);
/// `F_t` is the material's normalised dielectric transmittance
/// ([`FresnelTransmission`](crate::material::FresnelTransmission), cached in x1); `wi` is the
/// unit direction from x2 toward the light.
pub fn bssrdf(material: &Translucent, x1: &ExitPoint, x2: &EntryPoint, wi: Vec3) -> Vec3 {
    let r = (x2.position - x1.position).length();
    if r > x1.r_max.max_element() {
        return Vec3::ZERO;
    }
    let profile = Vec3::from_array(std::array::from_fn(|c| x1.profiles[c].pdf_disk(r)));
    bssrdf_of_profile(material.albedo * profile, x1, x2, wi)
}

/// `S = R(‖x1 − x2‖)/π · F_t(n1·ωo) F_t(n2·ωi)` for a radial profile value `profile` per channel
/// (any sign; the caller truncates), with x1's Fresnel transmittance [001 Eq. 2].
pub fn bssrdf_of_profile(profile: Vec3, x1: &ExitPoint, x2: &EntryPoint, wi: Vec3) -> Vec3 {
    let fresnel = x1.fresnel_out * x1.fresnel.eval(x2.shading_normal.dot(wi));
    profile * (FRAC_1_PI * fresnel)
}

/// `f = S · max(0, n2·ωi) · L_e` for a light sampled in solid angle at x2, unshadowed.
pub fn contribution(
    material: &Translucent,
    x1: &ExitPoint,
    x2: &EntryPoint,
    wi: Vec3,
    radiance: Vec3,
) -> Vec3 {
    lit(x2, wi, radiance, || bssrdf(material, x1, x2, wi))
}

/// `f = S · max(0, n2·ωi) · L_e` for the BSSRDF value `bssrdf()`, evaluated only when light
/// arrives from above x2's shading normal.
pub(super) fn lit(
    x2: &EntryPoint,
    wi: Vec3,
    radiance: Vec3,
    bssrdf: impl FnOnce() -> Vec3,
) -> Vec3 {
    let cos_i = x2.shading_normal.dot(wi);
    if cos_i.is_nan() || cos_i <= 0.0 {
        return Vec3::ZERO;
    }
    bssrdf() * cos_i * radiance
}

/// `p̂ = luminance(f)` (unshadowed).
pub fn target(f: Vec3) -> f32 {
    luminance(f)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::{BoundaryKind, FresnelTransmission};
    use crate::profile::ScaleFit;
    use glam::Vec2;

    /// `S` from x1's cached profiles equals `(A R̄)(r)/π · F_t · F_t` from the material (with its
    /// truncation, `F_t` of its `ior`), and `f` vanishes for light from below x2.
    #[test]
    fn bssrdf_matches_the_material_profile() {
        let material = Translucent {
            albedo: Vec3::new(0.8, 0.5, 0.3),
            mfp: Vec3::new(0.05, 0.03, 0.01),
            scale: 1.0,
            ior: 1.3,
            g: 0.0,
            fit: ScaleFit::Searchlight,
            boundary: BoundaryKind::Diffuse,
        };
        let view = Vec3::new(0.0, 0.6, 0.8);
        let x1 = ExitPoint::new(Vec3::ZERO, Vec3::Y, Vec3::Y, view, 0, &material);
        let wi = Vec3::new(0.6, 0.8, 0.0);
        for i in 0..200 {
            let r = material.r_max_all() * 1.1 * (i as f32 + 0.5) / 200.0;
            let x2 = EntryPoint {
                object: 0,
                prim: 0,
                bary: Vec2::ZERO,
                position: Vec3::new(r, 0.0, 0.0),
                geometric_normal: Vec3::Y,
                shading_normal: Vec3::Y,
            };
            let ft = material.fresnel();
            assert_eq!(ft, FresnelTransmission::new(1.3));
            let want = material.profile_rgb(r) * FRAC_1_PI * ft.eval(0.6) * ft.eval(0.8);
            let got = bssrdf(&material, &x1, &x2, wi);
            assert!(
                (got - want).abs().max_element() <= 1e-6 * want.max_element(),
                "r = {r}: {got} vs {want}"
            );
            assert_eq!(contribution(&material, &x1, &x2, wi, Vec3::ONE), got * 0.8);
            assert_eq!(
                contribution(&material, &x1, &x2, -wi, Vec3::ONE),
                Vec3::ZERO
            );
        }
    }
}
