//! Volumetric random walk in a homogeneous medium (DESIGN §4): the ground truth against which
//! the diffusion approximation is judged [000 slides 20–22].
//!
//! - [`phase`]: Henyey–Greenstein sampling, pdf, value and inverse.
//! - [`medium`]: RGB `σs`, `σa`, the phase function and the boundary's [`Interface`]
//!   (index-matched, smooth dielectric, Fresnel-free diffuse transmission); built from explicit
//!   coefficients or from a [`Translucent`](crate::material::Translucent) by paper 000's colour
//!   mapping.
//! - [`boundary`]: the closed surface seen from inside ([`Boundary`]): half-space (semi-infinite
//!   medium), sphere, and one closed object of the scene BVH.
//! - [`interface`]: Fresnel, refraction, cosine-distributed transmission.
//! - [`mod@walk`]: the kernel (free flights with hero-channel spectral MIS, collisions, boundary
//!   events, Russian roulette, a reported bounce cap).
//! - [`lighting`] and [`estimate`]: the pixel-level estimator [`estimate_exitant`] with
//!   next-event estimation at the exit; its entry ([`enter`]), boundary crossing ([`cross`]) and
//!   exit lighting ([`incident`]) also serve paper 000's single-scattering estimator
//!   ([`crate::integrator::single_scatter`]).
//!
//! **Analytic check.** For an index-matched semi-infinite medium with isotropic scattering and
//! albedo `α`, lit by a collimated beam at incidence cosine `μ0`, the fraction of the beam's flux
//! that is diffusely reflected is Chandrasekhar's `R(μ0) = 1 − H(μ0)·√(1 − α)`, with the
//! H-function the solution of `1/H(μ) = √(1 − α) + (α/2) ∫₀¹ μ′H(μ′)/(μ + μ′) dμ′`; the part
//! that leaves after exactly one collision is `R1(μ0) = (α/2)·(1 − μ0 ln(1 + 1/μ0))`, so
//! `R1(1) = (α/2)(1 − ln 2)`. The tests in `validation` compare walk tallies with both (per
//! channel of a chromatic medium, which also checks the hero-channel weights), and check energy
//! conservation at albedo 1 through index-matched and dielectric boundaries of a sphere and a
//! closed mesh.

pub mod boundary;
pub mod estimate;
pub mod interface;
pub mod lighting;
pub mod medium;
pub mod phase;
pub mod walk;

pub use boundary::{Boundary, BoundaryHit, HalfSpace, MeshBoundary, Sphere};
pub use estimate::{ExitantSample, enter, estimate_exitant, estimate_exitant_with, incident};
pub use lighting::{ExitLighting, LightSample};
pub use medium::{Interface, Medium};
pub use phase::{HenyeyGreenstein, PhaseFunction, PhaseSample};
pub use walk::{
    Crossing, CrossingKind, DEFAULT_MAX_BOUNCES, Exit, ExitDirection, WalkEnd, WalkEndKind,
    WalkSettings, cross, roulette, walk,
};

#[cfg(test)]
pub(crate) mod validation;
