//! Materials (DESIGN §4): translucent objects with the Burley BSSRDF, Lambert backgrounds, and
//! the measured presets of Jensen et al. 2001, and the dipole profiles of a translucent material.

pub mod color;
pub mod dipole;
pub mod fresnel;
pub mod measured;
pub mod translucent;

use glam::Vec3;

pub use dipole::DipoleProfiles;
pub use fresnel::FresnelTransmission;
pub use measured::{MEASURED_NAMES, measured};
pub use translucent::{BoundaryKind, Translucent};

/// An opaque Lambertian surface (backgrounds, floors), optionally an emitter: an emissive
/// Lambert object is geometry (camera rays see its emission, it occludes) and each of its
/// triangles is also one of the scene's lights (`sss::scene::Light::Triangle`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lambert {
    /// Diffuse reflectance per channel, in [0, 1].
    pub albedo: Vec3,
    /// Radiance `L_e` the surface emits per channel (zero: not an emitter).
    pub emission: Vec3,
    /// Whether the back face emits too (glTF `doubleSided`); the front is the side of the
    /// winding normal `(v1 − v0) × (v2 − v0)`.
    pub two_sided: bool,
}

impl Lambert {
    /// A plain (non-emissive) surface of reflectance `albedo`.
    pub fn new(albedo: Vec3) -> Lambert {
        Lambert {
            albedo,
            emission: Vec3::ZERO,
            two_sided: false,
        }
    }

    pub fn is_emitter(&self) -> bool {
        self.emission != Vec3::ZERO
    }

    /// `L_e` leaving the surface toward a viewer on its front (`front`) or back side.
    pub fn emitted(&self, front: bool) -> Vec3 {
        if front || self.two_sided {
            self.emission
        } else {
            Vec3::ZERO
        }
    }
}

/// The material of a scene object.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Material {
    Translucent(Translucent),
    Lambert(Lambert),
}
