//! The BSSRDF and path contribution with the dipole profile in place of Burley's
//! ([`ProfileKind::Dipole`](crate::profile::ProfileKind)): `S = R_d(‖x1 − x2‖)/π · F_t(n1·ωo) ·
//! F_t(n2·ωi)` [002 Eq. 2], with the dipole's `R_d` already carrying the albedo (`ρ = A`) and the
//! material's normalised Fresnel transmittance `F_t` of [`super::eval`] (x1's cached
//! [`FresnelTransmission`](crate::material::FresnelTransmission)).

use glam::Vec3;

use super::eval::{bssrdf_of_profile, lit};
use super::probe::{EntryPoint, ExitPoint};
use crate::material::DipoleProfiles;

/// `S` with the dipole profile, truncated at `r_max_all` ([`DipoleProfiles::profile_rgb`]).
pub fn bssrdf_dipole(dipoles: &DipoleProfiles, x1: &ExitPoint, x2: &EntryPoint, wi: Vec3) -> Vec3 {
    let r = (x2.position - x1.position).length();
    bssrdf_of_profile(dipoles.profile_rgb(r), x1, x2, wi)
}

/// `f = S · max(0, n2·ωi) · L_e` with the dipole profile, unshadowed.
pub fn contribution_dipole(
    dipoles: &DipoleProfiles,
    x1: &ExitPoint,
    x2: &EntryPoint,
    wi: Vec3,
    radiance: Vec3,
) -> Vec3 {
    lit(x2, wi, radiance, || bssrdf_dipole(dipoles, x1, x2, wi))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bssrdf::contribution;
    use crate::material::{BoundaryKind, Translucent};
    use crate::profile::ScaleFit;
    use glam::Vec2;
    use restir::rng::StreamKey;

    /// For random geometry, `f_dipole / R_d = f / (A R̄_d)` per channel: both BSSRDFs share the
    /// Fresnel factors, cosine and truncation of [`super::super::eval`] (if one changes, so must
    /// the other, and the image-space method with them).
    #[test]
    fn dipole_contribution_follows_the_burley_convention() {
        let material = Translucent {
            albedo: Vec3::new(0.8, 0.5, 0.3),
            mfp: Vec3::new(0.05, 0.03, 0.01),
            scale: 1.0,
            ior: 1.3,
            g: 0.0,
            fit: ScaleFit::Searchlight,
            boundary: BoundaryKind::Diffuse,
        };
        let dipoles = DipoleProfiles::new(&material);
        let mut rng = StreamKey::new(0, 0, 0, 0xD1B0_0001).stream(3);
        let mut unit = || {
            let v = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - 1.0;
            v.normalize()
        };
        for i in 0..500 {
            let (n1, view, n2, wi) = (unit(), unit(), unit(), unit());
            let x1 = ExitPoint::new(Vec3::ZERO, n1, n1, view, 0, &material);
            let r = material.r_max_all() * 1.05 * (i as f32 + 0.5) / 500.0;
            let x2 = EntryPoint {
                object: 0,
                prim: 0,
                bary: Vec2::ZERO,
                position: r * unit(),
                geometric_normal: n2,
                shading_normal: n2,
            };
            let r = x2.position.length();
            let radiance = Vec3::new(1.0, 2.0, 3.0);
            if r > material.r_max_all() {
                assert_eq!(
                    contribution_dipole(&dipoles, &x1, &x2, wi, radiance),
                    Vec3::ZERO
                );
                continue;
            }
            let burley = contribution(&material, &x1, &x2, wi, radiance) / material.profile_rgb(r);
            let dipole =
                contribution_dipole(&dipoles, &x1, &x2, wi, radiance) / dipoles.profile_rgb(r);
            for c in 0..3 {
                assert!(
                    (burley[c] - dipole[c]).abs() <= 1e-5 * burley[c].abs().max(1e-30),
                    "sample {i}, channel {c}: {} vs {}",
                    burley[c],
                    dipole[c]
                );
            }
        }
    }
}
