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

/// An opaque Lambertian surface (backgrounds, floors).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lambert {
    /// Diffuse reflectance per channel, in [0, 1].
    pub albedo: Vec3,
}

/// The material of a scene object.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Material {
    Translucent(Translucent),
    Lambert(Lambert),
}
