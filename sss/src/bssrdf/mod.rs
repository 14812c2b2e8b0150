//! BSSRDF importance sampling (DESIGN §4, §9; [001 §2.1, §3.1, Alg. 3–4]).
//!
//! A technique is a projection axis (normal / tangent / bitangent of x1's geometric normal frame)
//! times a profile channel. It samples a disk point at radius `r ~ p_{d_c}` and angle `2π u`,
//! traces the chord of the `r_max,c` sphere through it along the axis, and every hit on x1's
//! object is a candidate x2 with the one-sample MIS density [`p_disk`] over all nine techniques.
//! Each sampling routine has its density ([`p_disk`], [`technique_terms`]) and its inverse
//! ([`invert`], [`TechniqueSelection::u_interval`]).

mod dipole;
mod eval;
mod invert;
mod pdf;
mod probe;
mod sample;
mod technique;

pub use dipole::{bssrdf_dipole, contribution_dipole};
pub use eval::{bssrdf, bssrdf_of_profile, contribution, target};
pub use invert::{InvertFail, find_index, invert, invert_random_numbers, invert_technique};
pub use pdf::{p_disk, p_disk_with, technique_terms, technique_terms_with};
pub use probe::{EntryPoint, ExitPoint, chord, probe_ray, probe_ray_with, trace_probe};
pub use sample::{BssrdfSample, Probe, pick_hit};
pub use technique::{Axis, RadiusSampling, Technique, TechniqueSelection};

#[cfg(test)]
mod tests;
