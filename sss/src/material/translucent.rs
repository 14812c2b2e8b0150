//! The translucent (BSSRDF) material: per-channel surface albedo `A` and length `ℓ`, mapped to
//! Burley profiles by `d = scale · ℓ / s(A)` [004 Eq. 5] (DESIGN §4, §9).

use std::path::Path;

use glam::Vec3;

use super::fresnel::FresnelTransmission;
use crate::InputError;
use crate::profile::{Burley, ScaleFit, scale_factor};

pub use crate::contract::material::BoundaryKind;

/// A translucent material with the Burley normalized-diffusion BSSRDF (DESIGN §9).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Translucent {
    /// Surface albedo `A` per channel, `∫ R(r) 2πr dr = A`, in [0, 1].
    pub albedo: Vec3,
    /// Length `ℓ` per channel in scene units; which length it is depends on `fit`.
    pub mfp: Vec3,
    /// Multiplies `ℓ` (unit conversion / artistic scale), > 0.
    pub scale: f32,
    /// Index of refraction of the boundary, > 0.
    pub ior: f32,
    /// Henyey–Greenstein anisotropy (used by the random walk ground truth), |g| < 1.
    pub g: f32,
    /// Which Christensen–Burley fit relates `ℓ` to `d`.
    pub fit: ScaleFit,
    /// The interface of path-traced volumetric transport (random walk, single scattering).
    pub boundary: BoundaryKind,
}

impl Translucent {
    /// `d_c = scale · ℓ_c / s(A_c)` per channel [004 Eq. 5].
    pub fn d(&self) -> Vec3 {
        Vec3::from_array(std::array::from_fn(|c| {
            self.scale * self.mfp[c] / scale_factor(self.fit, self.albedo[c])
        }))
    }

    /// The Burley profile of channel `c` (0, 1, 2).
    pub fn channel(&self, c: usize) -> Burley {
        Burley::new(self.d()[c])
    }

    /// Truncation radius of each channel's profile, `P_c⁻¹(R_MAX_QUANTILE)`.
    pub fn r_max(&self) -> Vec3 {
        Vec3::from_array(std::array::from_fn(|c| self.channel(c).r_max()))
    }

    /// The truncation radius of the BSSRDF: the largest channel's `r_max` (DESIGN §9).
    pub fn r_max_all(&self) -> f32 {
        self.r_max().max_element()
    }

    /// `A_c · R̄_{d_c}(r)` per channel, 0 beyond [`Translucent::r_max_all`] (DESIGN §9).
    pub fn profile_rgb(&self, r: f32) -> Vec3 {
        if r > self.r_max_all() {
            return Vec3::ZERO;
        }
        Vec3::from_array(std::array::from_fn(|c| {
            self.albedo[c] * self.channel(c).pdf_disk(r)
        }))
    }

    /// The BSSRDF's normalised Fresnel transmittance `F_t` for `ior` ([`FresnelTransmission`]).
    pub fn fresnel(&self) -> FresnelTransmission {
        FresnelTransmission::new(self.ior)
    }

    /// Checks the parameters; `field` is the material's dotted path in `file`, the error names
    /// `field.<member>` and the offending value.
    pub fn validate(&self, file: &Path, field: &str) -> Result<(), InputError> {
        let err = |member: &str, value: String, reason: &str| {
            Err(InputError::new(
                file,
                format!("{field}.{member}"),
                value,
                reason,
            ))
        };
        let a = self.albedo.to_array();
        if !a.iter().all(|x| (0.0..=1.0).contains(x)) {
            return err(
                "albedo",
                format!("{a:?}"),
                "each channel must lie in [0, 1]",
            );
        }
        let l = self.mfp.to_array();
        if !l.iter().all(|x| x.is_finite() && *x > 0.0) {
            return err(
                "mfp",
                format!("{l:?}"),
                "each channel must be finite and > 0",
            );
        }
        if !(self.scale.is_finite() && self.scale > 0.0) {
            return err("scale", self.scale.to_string(), "must be finite and > 0");
        }
        if !(self.ior.is_finite() && self.ior > 0.0) {
            return err("ior", self.ior.to_string(), "must be finite and > 0");
        }
        if self.g.is_nan() || self.g.abs() >= 1.0 {
            return err("g", self.g.to_string(), "must satisfy |g| < 1");
        }
        let d = self.d().to_array();
        if !d.iter().all(|x| x.is_finite() && *x > 0.0) {
            return err(
                "mfp",
                format!("{l:?}"),
                "scale · mfp / s(A) is not a positive finite d",
            );
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    fn skin_like() -> Translucent {
        Translucent {
            albedo: Vec3::new(0.8, 0.5, 0.2),
            mfp: Vec3::new(1.0, 0.5, 0.25),
            scale: 2.0,
            ior: 1.4,
            g: 0.0,
            fit: ScaleFit::Dmfp,
            boundary: BoundaryKind::Diffuse,
        }
    }

    #[test]
    fn d_follows_scale_fit() {
        let m = skin_like();
        let d = m.d();
        for c in 0..3 {
            let want = m.scale * m.mfp[c] / scale_factor(m.fit, m.albedo[c]);
            assert_eq!(d[c], want);
            assert_eq!(m.channel(c).d, want);
            assert_eq!(m.r_max()[c], Burley::new(want).r_max());
        }
        let r = m.r_max();
        assert_eq!(m.r_max_all(), r[0].max(r[1]).max(r[2]));
    }

    /// ∫ profile_rgb 2πr dr = A · P(r_max_all) per channel (Simpson in ln r, f64).
    #[test]
    fn profile_integrates_to_albedo() {
        let m = skin_like();
        let r_max = m.r_max_all() as f64;
        let (t0, t1, n) = ((r_max * 1e-10).ln(), r_max.ln(), 20_000usize);
        let h = (t1 - t0) / n as f64;
        let f = |t: f64| {
            let r = t.exp();
            let p = m.profile_rgb(r as f32).as_dvec3();
            p * (2.0 * std::f64::consts::PI * r * r)
        };
        let mut sum = f(t0) + f(t1);
        for i in 1..n {
            sum += f(t0 + i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
        }
        let total = sum * h / 3.0;
        for c in 0..3 {
            let want = m.albedo[c] as f64 * m.channel(c).cdf(r_max as f32) as f64;
            assert!(
                (total[c] - want).abs() < 1e-4,
                "channel {c}: {} vs {want}",
                total[c]
            );
        }
        assert_eq!(m.profile_rgb(m.r_max_all() * 1.001), Vec3::ZERO);
    }

    #[test]
    fn validation_names_file_field_value() {
        let file = PathBuf::from("scenes/test.toml");
        assert_eq!(skin_like().validate(&file, "objects[0].material"), Ok(()));
        type Case = (fn(&mut Translucent), &'static str, &'static str);
        let cases: [Case; 7] = [
            (|m| m.mfp.y = f32::NAN, "mfp", "NaN"),
            (|m| m.mfp.z = -1.0, "mfp", "-1.0"),
            (|m| m.albedo.x = 1.5, "albedo", "1.5"),
            (|m| m.ior = 0.0, "ior", "0"),
            (|m| m.g = 1.0, "g", "1"),
            (|m| m.scale = -2.0, "scale", "-2"),
            (|m| m.scale = f32::INFINITY, "scale", "inf"),
        ];
        for (break_it, member, value) in cases {
            let mut m = skin_like();
            break_it(&mut m);
            let e = m.validate(&file, "objects[0].material").expect_err(member);
            assert_eq!(e.file, file);
            assert_eq!(e.field, format!("objects[0].material.{member}"));
            assert!(
                e.value.contains(value),
                "{member}: value `{}` lacks `{value}`",
                e.value
            );
        }
    }
}
