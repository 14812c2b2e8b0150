//! The homogeneous medium of the walk: RGB coefficients, a phase function and the boundary's
//! interface type.

use std::path::Path;

use glam::Vec3;

use super::phase::{HenyeyGreenstein, PhaseFunction};
use crate::InputError;
use crate::material::color::volume_coefficients;
use crate::material::{BoundaryKind, Material, Translucent};
use crate::profile::ScaleFit;
use crate::scene::Scene;

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

impl Interface {
    /// The interface a translucent material asks for: its `boundary`, a dielectric with its `ior`.
    pub fn of(material: &Translucent) -> Interface {
        match material.boundary {
            BoundaryKind::Diffuse => Interface::Diffuse,
            BoundaryKind::Dielectric => Interface::Dielectric { eta: material.ior },
            BoundaryKind::IndexMatched => Interface::IndexMatched,
        }
    }

    /// The interface without its `η`: the code a GPU medium carries.
    pub fn kind(self) -> BoundaryKind {
        match self {
            Interface::Diffuse => BoundaryKind::Diffuse,
            Interface::Dielectric { .. } => BoundaryKind::Dielectric,
            Interface::IndexMatched => BoundaryKind::IndexMatched,
        }
    }
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

    /// The medium of a translucent material by paper 000's colour mapping [000 "Parameters"]:
    /// colour `C` = the material's albedo, scatter distance `scale · mfp`, so
    /// `σt = 1/(scale · mfp)`, `σs = α(C, g) σt`, `σa = σt − σs`; the interface is the material's
    /// `boundary` ([`Interface::of`]). Only the fits whose length is the volume mean free path
    /// qualify (`searchlight`, `diffuse_transmission`); `dmfp` is an error, since a diffuse mean
    /// free path is not `1/σt`.
    pub fn from_translucent(
        material: &Translucent,
        file: &Path,
        field: &str,
    ) -> Result<Medium, InputError> {
        material.validate(file, field)?;
        if material.fit == ScaleFit::Dmfp {
            return Err(InputError::new(
                file,
                format!("{field}.fit"),
                "\"dmfp\"",
                "volumetric transport needs the volume mean free path: \
                 write fit = \"searchlight\" or fit = \"diffuse_transmission\"",
            ));
        }
        let (sigma_t, sigma_s) =
            volume_coefficients(material.albedo, material.scale * material.mfp, material.g);
        Medium::new(
            sigma_s,
            sigma_t - sigma_s,
            material.g,
            Interface::of(material),
            file,
            field,
        )
    }

    /// The media of `scene`'s materials in order: [`Medium::from_translucent`] for translucent
    /// ones, `None` for Lambert ones. Errors name the scene file and `materials[i]`.
    pub fn of_scene(scene: &Scene) -> Result<Vec<Option<Medium>>, InputError> {
        scene
            .materials
            .iter()
            .enumerate()
            .map(|(i, m)| match m {
                Material::Translucent(t) => {
                    Medium::from_translucent(t, &scene.file, &format!("materials[{i}]")).map(Some)
                }
                Material::Lambert(_) => Ok(None),
            })
            .collect()
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
            boundary: BoundaryKind::Dielectric,
        };
        let file = Path::new("scene.toml");
        let m = Medium::from_translucent(&material, file, "m").unwrap();
        assert_eq!(m.interface(), Interface::Dielectric { eta: 1.4 });
        assert_eq!(m.interface().kind(), BoundaryKind::Dielectric);
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
        for (boundary, interface) in [
            (BoundaryKind::Diffuse, Interface::Diffuse),
            (BoundaryKind::IndexMatched, Interface::IndexMatched),
        ] {
            let m = Translucent {
                boundary,
                ..material
            };
            assert_eq!(
                Medium::from_translucent(&m, file, "m").unwrap().interface(),
                interface
            );
            assert_eq!(interface.kind(), boundary);
        }
        let bad = Translucent { g: 1.5, ..material };
        let err = Medium::from_translucent(&bad, file, "m").unwrap_err();
        assert_eq!(err.field, "m.g");
    }

    /// A `dmfp` material is an error that names the scene file, the field and the value, and its
    /// hint names values the scene parser accepts: the hinted line, put in the file, loads.
    #[test]
    fn dmfp_error_names_the_file_and_a_parseable_fix() {
        const SCENE: &str = include_str!("../../../scenes/slab.toml");
        let searchlight = "fit = \"searchlight\"";
        assert_eq!(
            SCENE.matches(searchlight).count(),
            1,
            "test bug: slab.toml changed"
        );
        let dmfp = SCENE.replace(searchlight, "fit = \"dmfp\"");
        let file = Path::new("scenes/slab.toml");
        let scene = Scene::from_toml_str(&dmfp, file).unwrap();
        let err = Medium::of_scene(&scene).unwrap_err();
        assert_eq!(err.file, file);
        assert_eq!(err.field, "materials[0].fit");
        let message = err.to_string();
        assert!(message.starts_with("scenes/slab.toml: "), "{message}");
        assert!(message.contains("dmfp"), "{message}");
        let hints: Vec<&str> = message
            .split("write ")
            .nth(1)
            .expect("a hint")
            .split(" or ")
            .collect();
        assert_eq!(hints.len(), 2, "{message}");
        for hint in hints {
            let fixed = dmfp.replace("fit = \"dmfp\"", hint);
            let scene = Scene::from_toml_str(&fixed, file)
                .unwrap_or_else(|e| panic!("hint `{hint}` does not parse: {e}"));
            let media = Medium::of_scene(&scene).unwrap();
            assert!(media.iter().any(Option::is_some), "{hint}");
        }
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
