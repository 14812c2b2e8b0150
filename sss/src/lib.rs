//! `sss`: the subsurface-scattering path space (DESIGN §4): diffusion profiles, materials,
//! scenes (on the `geometry` crate's meshes and BVH), lights and camera, BSSRDF importance
//! sampling, and the integrators (path-tracing baseline, progressive reference, volumetric
//! random walk).

pub mod bssrdf;
pub mod color;
/// What the GLSL twins (`sss/glsl/`) share with this crate: per twin its constants and kinds
/// (`twin::contract!`; rendered to `contract/sss.glsl` by `engine/build.rs`). The modules below
/// re-export them where they are used.
pub mod contract;
pub mod error;
pub mod integrator;
pub mod limits;
pub mod material;
pub mod profile;
pub mod random_walk;
pub mod sampling;
pub mod scene;

pub use error::InputError;
