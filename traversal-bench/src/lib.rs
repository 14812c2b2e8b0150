//! Side-by-side CPU traversal benchmark (`cargo bench -p traversal-bench`): reshift's
//! [`geometry::Geometry`] against Embree 3 on the same meshes and the same rays.
//!
//! Embree is optional and bench-only: `build.rs` links it when `libembree-dev` is installed
//! (`cfg(embree)`); otherwise the benchmark runs reshift alone and says Embree is absent.

#[cfg(embree)]
pub mod embree;
pub mod rays;
pub mod scanned;

/// How `build.rs` found Embree: `linked (…)` or `absent: <reason>`.
pub const EMBREE_STATUS: &str = env!("EMBREE_STATUS");
