//! The Jensen dipole [002 Table 1] of a [`Translucent`] material, prepared for evaluation and
//! sampling: the profile that the image-space method of paper 002 integrates, and that the
//! path-traced reference evaluates under
//! [`ProfileKind::Dipole`](crate::profile::ProfileKind) so that the two can be compared.
//!
//! Mapping `(A, ℓ) → (σs′, σa)` per channel: `σt′ = 1/(scale · ℓ)` and `α′` solves
//! `R_d(α′) = A` ([`coefficients_from_albedo_mfp`], the inverse of the conversion of the measured
//! presets). The dipole then has the material's total diffuse reflectance `ρ = A` exactly, and
//! `scale · ℓ` is read as the reduced mean free path `1/σt′`, which is what `ℓ` means under
//! [`ScaleFit::Searchlight`](crate::profile::ScaleFit) and for the measured presets; under the other
//! fits it is the same number read the same way.
//!
//! Truncation: the dipole is cut at the material's [`Translucent::r_max_all`] (the Burley radius that
//! bounds the probe chords of BSSRDF IS), like the Burley profile (DESIGN §9). The dipole's tail is
//! heavier than Burley's, so it loses more energy there: [`DipoleProfiles::kept_fraction`] says how
//! much it keeps per channel.

use glam::Vec3;

use super::Translucent;
use super::measured::coefficients_from_albedo_mfp;
use crate::profile::Dipole;

/// The three per-channel dipoles of a translucent material and its truncation radius.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DipoleProfiles {
    pub channels: [Dipole; 3],
    /// [`Translucent::r_max_all`]: `R_d = 0` beyond.
    pub r_max_all: f32,
}

impl DipoleProfiles {
    /// The dipoles of `material` (module doc). Solves for `α′` per channel: prepare once per
    /// material or pixel, not per sample.
    pub fn new(material: &Translucent) -> DipoleProfiles {
        let channels = std::array::from_fn(|c| {
            let mfp = material.scale as f64 * material.mfp[c] as f64;
            let (sigma_s, sigma_a) =
                coefficients_from_albedo_mfp(material.albedo[c] as f64, mfp, material.ior as f64);
            Dipole::new(sigma_s as f32, sigma_a as f32, material.ior)
        });
        DipoleProfiles {
            channels,
            r_max_all: material.r_max_all(),
        }
    }

    /// `R_d,c(r)` per channel [002 Table 1], 0 beyond `r_max_all`; it takes the place of
    /// [`Translucent::profile_rgb`] (`A_c R̄_{d_c}(r)`) in the BSSRDF.
    pub fn profile_rgb(&self, r: f32) -> Vec3 {
        if r > self.r_max_all {
            return Vec3::ZERO;
        }
        Vec3::from_array(self.channels.map(|d| d.profile(r)))
    }

    /// `∫_{r ≤ r_max_all} 2πr R_d,c dr / ρ_c = CDF_c(r_max_all)` per channel [002 Eq. 6–7]: the
    /// fraction of each channel's reflectance that the truncation keeps.
    pub fn kept_fraction(&self) -> Vec3 {
        Vec3::from_array(self.channels.map(|d| d.cdf(self.r_max_all)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::{BoundaryKind, measured};
    use crate::profile::ScaleFit;

    fn jade() -> Translucent {
        Translucent {
            albedo: Vec3::new(0.9, 0.7, 0.55),
            mfp: Vec3::new(0.04, 0.02, 0.01),
            scale: 1.0,
            ior: 1.3,
            g: 0.0,
            fit: ScaleFit::Searchlight,
            boundary: BoundaryKind::Diffuse,
        }
    }

    /// Each channel's dipole reflects exactly the material's albedo, ρ_c = A_c [002 Eq. 7]; the
    /// profile is cut at r_max_all, which keeps the fraction CDF_c(r_max_all) of it.
    #[test]
    fn dipoles_keep_albedo_and_truncate_at_r_max_all() {
        let mut m = jade();
        m.scale = 2.0;
        let d = DipoleProfiles::new(&m);
        for c in 0..3 {
            let rho = d.channels[c].total_reflectance();
            assert!((rho - m.albedo[c]).abs() < 2e-6, "channel {c}: ρ = {rho}");
        }
        assert_eq!(d.r_max_all, m.r_max_all());
        assert!(d.profile_rgb(m.r_max_all()).min_element() > 0.0);
        assert_eq!(d.profile_rgb(m.r_max_all() * 1.0001), Vec3::ZERO);
        let kept = d.kept_fraction();
        for c in 0..3 {
            assert_eq!(kept[c], d.channels[c].cdf(m.r_max_all()));
            assert!(kept[c] > 0.9 && kept[c] <= 1.0, "channel {c}: {}", kept[c]);
        }
        assert!(
            kept[0] < 0.99,
            "the widest channel's dipole tail is cut: {}",
            kept[0]
        );
    }

    /// The measured presets come back as the dipoles of their own table coefficients (σs′, σa
    /// in mm⁻¹, η = 1.3): the profiles agree to 1e-4 relative at several radii.
    #[test]
    fn measured_presets_give_their_own_dipoles() {
        let skin1 = measured::measured("skin1").unwrap();
        let got = DipoleProfiles::new(&skin1);
        let table = [(0.74, 0.032), (0.88, 0.17), (1.01, 0.48)];
        for (c, (s, a)) in table.into_iter().enumerate() {
            let want = Dipole::new(s, a, 1.3);
            for r in [0.01f32, 0.3, 1.0, 3.0] {
                let (g, w) = (got.channels[c].profile(r), want.profile(r));
                assert!(
                    ((g - w) / w).abs() < 1e-4,
                    "channel {c}, r = {r}: {g} vs {w}"
                );
            }
        }
    }
}
