//! `geometry` (DESIGN §4): triangle meshes, procedural shapes, OBJ/PLY/glTF loading within their
//! [`limits`], and the BVH with closest-hit, any-hit and all-hits-on-object queries; and the
//! [`InputError`] every loader of the workspace returns.
//!
//! Ray conventions: hits satisfy `t_min < t < t_max` (open at both ends, so `t_min = hit.t`
//! continues past a hit); `t` is in units of `dir` (not normalised); ties in `t` go to the lower
//! global triangle id. For the GPU twin, [`Geometry::bvh`] exposes the obvhs CWBVH as built
//! (80-byte `CwBvhNode`s and the leaf-slot → triangle-id map `primitive_indices`); the CPU
//! traverses its own uncompressed layout of the same tree ([`wide`]).

pub mod bvh;
/// What the BVH's GLSL twin (`glsl/bvh.glsl`) shares with this crate (`twin::contract!`;
/// rendered to `contract/geometry.glsl` by `engine/build.rs`).
pub mod contract;
pub mod error;
pub mod frame;
mod kernel;
pub mod limits;
pub mod load;
pub mod mesh;
mod query;
pub mod ray;
pub mod shapes;
#[cfg(test)]
mod testing;
mod traverse;
mod watertight;
mod wide;

pub use bvh::Geometry;
pub use error::InputError;
pub use frame::Frame;
pub use load::load_mesh;
pub use mesh::TriangleMesh;
/// The build parameters [`Geometry::with_build_params`] takes (obvhs's).
pub use obvhs::BvhBuildParams;
pub use ray::{Hit, Ray};
