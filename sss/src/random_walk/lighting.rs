//! The light outside the medium, as seen from a boundary point where the walk leaves.

use glam::Vec3;

/// A light direction drawn by [`ExitLighting::sample`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSample {
    /// Unit direction from the boundary point toward the light (outside the medium).
    pub wi: Vec3,
    /// Radiance arriving along `wi` divided by `pdf` (for a delta light: its irradiance at
    /// normal incidence, the usual delta convention).
    pub radiance_over_pdf: Vec3,
    /// Solid-angle density of `wi` (unused for delta lights).
    pub pdf: f32,
    pub is_delta: bool,
}

/// Incident light at boundary points, supplied by the caller (scene lights, an environment, a
/// test furnace). Visibility is the implementor's concern: return occluded radiance as zero.
pub trait ExitLighting {
    /// Draws a direction toward the light from `point` (outward unit `normal`), from two uniform
    /// numbers in [0, 1). `None` when nothing can be sampled.
    fn sample(&self, point: Vec3, normal: Vec3, u: [f32; 2]) -> Option<LightSample>;
    /// The solid-angle density with which `sample` returns `wi` (0 for delta lights).
    fn pdf(&self, point: Vec3, normal: Vec3, wi: Vec3) -> f32;
    /// Radiance arriving at `point` from direction `wi` (travelling along `−wi`); delta lights
    /// contribute 0 here, since no direction chosen independently of them can hit them.
    fn radiance(&self, point: Vec3, wi: Vec3) -> Vec3;
}
