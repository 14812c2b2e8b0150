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

/// Test lightings shared by the walk's and the single-scattering estimator's tests.
#[cfg(test)]
pub(crate) mod test_support {
    use glam::Vec3;

    use super::{ExitLighting, LightSample};
    use crate::random_walk::phase::ISOTROPIC;
    use crate::sampling::{cosine_hemisphere_pdf, sample_cosine_hemisphere};

    /// Uniform environment of radiance `radiance`, sampled uniformly over the sphere, with
    /// `pdf_scale ≠ 1` misreporting the density (negative control). With `delta`, each sample is
    /// instead a directional light from a cosine-distributed direction about the normal, with
    /// irradiance `π·radiance / cos θ`: the NEE term alone is then exactly `radiance`.
    pub struct Furnace {
        pub radiance: Vec3,
        pub delta: bool,
        pub pdf_scale: f32,
    }

    impl ExitLighting for Furnace {
        fn sample(&self, _: Vec3, normal: Vec3, u: [f32; 2]) -> Option<LightSample> {
            if self.delta {
                let wi = sample_cosine_hemisphere(normal, u);
                let radiance_over_pdf = self.radiance / cosine_hemisphere_pdf(normal, wi);
                return Some(LightSample {
                    wi,
                    radiance_over_pdf,
                    pdf: 0.0,
                    is_delta: true,
                });
            }
            let z = 1.0 - 2.0 * u[0];
            let r = (1.0 - z * z).max(0.0).sqrt();
            let (s, c) = (std::f32::consts::TAU * u[1]).sin_cos();
            let pdf = self.pdf_scale * ISOTROPIC;
            let wi = Vec3::new(r * c, r * s, z);
            Some(LightSample {
                wi,
                radiance_over_pdf: self.radiance / pdf,
                pdf,
                is_delta: false,
            })
        }
        fn pdf(&self, _: Vec3, _: Vec3, _: Vec3) -> f32 {
            if self.delta {
                0.0
            } else {
                self.pdf_scale * ISOTROPIC
            }
        }
        fn radiance(&self, _: Vec3, _: Vec3) -> Vec3 {
            if self.delta {
                Vec3::ZERO
            } else {
                self.radiance
            }
        }
    }
}
