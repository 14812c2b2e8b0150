//! The homogeneous medium of the walk: RGB coefficients, a phase function and the boundary's
//! interface type.

use std::path::Path;

use glam::Vec3;

use super::phase::{HenyeyGreenstein, PhaseFunction};
use crate::InputError;
use crate::material::Translucent;
use crate::material::color::volume_coefficients;
use crate::profile::ScaleFit;

/// What happens where the walk meets the object's surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Interface {
    /// No interface: every crossing leaves (or enters) along the same direction.
    IndexMatched,
    /// A smooth dielectric with relative index `eta = η_inside / η_outside`: Fresnel reflection
    /// or refraction, chosen with the Fresnel probability; total internal reflection.
    Dielectric { eta: f32 },
    /// Lambertian transmission, Fresnel-free: every crossing transmits, with `f = 1/π` on both
    /// sides (entry and exit directions cosine-distributed about the normal). No internal
    /// reflection, no `η`: the convention of diffusion-profile renderers [000 slide 57].
    Diffuse,
}

/// A homogeneous medium: scattering and absorption coefficients per RGB channel (1/length), a
/// phase function (achromatic) and the interface of the enclosing surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Medium<P = HenyeyGreenstein> {
    sigma_s: Vec3,
    sigma_a: Vec3,
    phase: P,
    interface: Interface,
}

impl Medium {
    /// Validates explicit coefficients: `σs, σa ≥ 0` and finite, `σt = σs + σa > 0` per channel,
    /// `−1 < g < 1`, and for a dielectric a finite `η > 0`. `file` and `field` (a dotted prefix,
    /// e.g. `objects[2].material`) name the origin of the values in the error.
    pub fn new(
        sigma_s: Vec3,
        sigma_a: Vec3,
        g: f32,
        interface: Interface,
        file: &Path,
        field: &str,
    ) -> Result<Medium, InputError> {
        let error = |name: &str, value: String, reason: &str| {
            InputError::new(file, format!("{field}.{name}"), value, reason)
        };
        for (name, v) in [("sigma_s", sigma_s), ("sigma_a", sigma_a)] {
            if !(v.is_finite() && v.min_element() >= 0.0) {
                return Err(error(
                    name,
                    format!("{v}"),
                    "must be finite and ≥ 0 in every channel",
                ));
            }
        }
        let sigma_t = sigma_s + sigma_a;
        if !(sigma_t.min_element() > 0.0 && sigma_t.is_finite()) {
            return Err(error(
                "sigma_t",
                format!("{sigma_t}"),
                "σs + σa must be finite and > 0 in every channel (a vacuum has no walk)",
            ));
        }
        let phase = HenyeyGreenstein::new(g).ok_or_else(|| {
            error(
                "g",
                format!("{g}"),
                "Henyey–Greenstein g must lie in (−1, 1)",
            )
        })?;
        if let Interface::Dielectric { eta } = interface
            && !(eta.is_finite() && eta > 0.0)
        {
            return Err(error(
                "eta",
                format!("{eta}"),
                "the index of refraction must be finite and > 0",
            ));
        }
        Ok(Medium {
            sigma_s,
            sigma_a,
            phase,
            interface,
        })
    }

    /// The medium of a translucent material by seed 000's colour mapping [000 "Parameters"]:
    /// colour `C` = the material's albedo, scatter distance `scale · mfp`, so
    /// `σt = 1/(scale · mfp)`, `σs = α(C, g) σt`, `σa = σt − σs`. Only the fits whose length is the
    /// volume mean free path qualify (`searchlight`, `diffuse-transmission`); `dmfp` is an error,
    /// since a diffuse mean free path is not `1/σt`. `interface` is the caller's choice (e.g.
    /// `Interface::Dielectric { eta: material.ior }` for a smooth surface).
    pub fn from_translucent(
        material: &Translucent,
        interface: Interface,
        file: &Path,
        field: &str,
    ) -> Result<Medium, InputError> {
        material.validate(file, field)?;
        if material.fit == ScaleFit::Dmfp {
            return Err(InputError::new(
                file,
                format!("{field}.fit"),
                "dmfp",
                "the random walk needs the volume mean free path: use fit searchlight or diffuse-transmission",
            ));
        }
        let (sigma_t, sigma_s) =
            volume_coefficients(material.albedo, material.scale * material.mfp, material.g);
        Medium::new(
            sigma_s,
            sigma_t - sigma_s,
            material.g,
            interface,
            file,
            field,
        )
    }
}

impl<P: PhaseFunction> Medium<P> {
    /// The same medium with another phase function (custom phases; the tests' negative controls).
    pub fn with_phase<Q: PhaseFunction>(self, phase: Q) -> Medium<Q> {
        Medium {
            sigma_s: self.sigma_s,
            sigma_a: self.sigma_a,
            phase,
            interface: self.interface,
        }
    }

    pub fn sigma_s(&self) -> Vec3 {
        self.sigma_s
    }

    pub fn sigma_a(&self) -> Vec3 {
        self.sigma_a
    }

    /// Extinction `σt = σs + σa`.
    pub fn sigma_t(&self) -> Vec3 {
        self.sigma_s + self.sigma_a
    }

    /// Single-scattering albedo `α = σs / σt`.
    pub fn albedo(&self) -> Vec3 {
        self.sigma_s / self.sigma_t()
    }

    pub fn phase(&self) -> &P {
        &self.phase
    }

    pub fn interface(&self) -> Interface {
        self.interface
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::color::single_scattering_albedo;

    fn build(
        sigma_s: Vec3,
        sigma_a: Vec3,
        g: f32,
        interface: Interface,
    ) -> Result<Medium, InputError> {
        Medium::new(
            sigma_s,
            sigma_a,
            g,
            interface,
            Path::new("scene.toml"),
            "objects[1].material",
        )
    }

    #[test]
    fn valid_medium_reports_its_coefficients() {
        let m = build(
            Vec3::new(1.0, 2.0, 3.0),
            Vec3::new(1.0, 0.0, 1.0),
            0.3,
            Interface::Diffuse,
        )
        .unwrap();
        assert_eq!(m.sigma_t(), Vec3::new(2.0, 2.0, 4.0));
        assert_eq!(m.sigma_a(), Vec3::new(1.0, 0.0, 1.0));
        assert_eq!(m.albedo(), Vec3::new(0.5, 1.0, 0.75));
        assert_eq!(m.phase().g(), 0.3);
    }

    #[test]
    fn translucent_material_maps_through_seed_000_colours() {
        let material = Translucent {
            albedo: Vec3::new(0.2, 0.5, 0.9),
            mfp: Vec3::new(0.5, 1.0, 2.0),
            scale: 2.0,
            ior: 1.4,
            g: 0.3,
            fit: ScaleFit::Searchlight,
        };
        let file = Path::new("scene.toml");
        let m = Medium::from_translucent(&material, Interface::Dielectric { eta: 1.4 }, file, "m")
            .unwrap();
        assert!(
            (m.sigma_t() - Vec3::new(1.0, 0.5, 0.25))
                .abs()
                .max_element()
                < 1e-6
        );
        for c in 0..3 {
            let alpha = single_scattering_albedo(material.albedo[c] as f64, 0.3);
            assert!((m.albedo()[c] as f64 - alpha).abs() < 1e-5, "channel {c}");
        }
        // A brighter colour needs a higher single-scattering albedo.
        assert!(m.albedo().x < m.albedo().y && m.albedo().y < m.albedo().z);
        let dmfp = Translucent {
            fit: ScaleFit::Dmfp,
            ..material
        };
        let err = Medium::from_translucent(&dmfp, Interface::Diffuse, file, "m").unwrap_err();
        assert_eq!(err.field, "m.fit");
        let bad = Translucent { g: 1.5, ..material };
        let err = Medium::from_translucent(&bad, Interface::Diffuse, file, "m").unwrap_err();
        assert_eq!(err.field, "m.g");
    }

    #[test]
    fn bad_parameters_are_input_errors_naming_the_field() {
        let one = Vec3::ONE;
        let cases = [
            (
                build(Vec3::new(1.0, -1.0, 1.0), one, 0.0, Interface::IndexMatched),
                "objects[1].material.sigma_s",
            ),
            (
                build(one, Vec3::splat(f32::NAN), 0.0, Interface::IndexMatched),
                "objects[1].material.sigma_a",
            ),
            (
                build(
                    Vec3::ZERO,
                    Vec3::new(1.0, 0.0, 1.0),
                    0.0,
                    Interface::IndexMatched,
                ),
                "objects[1].material.sigma_t",
            ),
            (
                build(one, one, 1.0, Interface::IndexMatched),
                "objects[1].material.g",
            ),
            (
                build(one, one, 0.0, Interface::Dielectric { eta: 0.0 }),
                "objects[1].material.eta",
            ),
            (
                build(one, one, 0.0, Interface::Dielectric { eta: f32::INFINITY }),
                "objects[1].material.eta",
            ),
        ];
        for (result, field) in cases {
            let err = result.expect_err(field);
            assert_eq!(err.field, field);
            assert_eq!(err.file, Path::new("scene.toml"));
        }
    }
}
