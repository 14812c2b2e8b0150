//! A negative control of the bias test: a method whose final frame is scaled per colour channel
//! ([`Tinted`]), e.g. blue × 1.03, a bias that a test of the luminance alone would miss.

use engine::{Backend, PipelineError};
use glam::Vec3;
use methods::{Estimator, LastFrame, Method};
use sss::integrator::pt::PtSettings;
use sss::scene::Scene;

/// `method` with every pixel of its final frame multiplied by `factor` (linear RGB); its
/// reference is `method`'s. Replica `i` is replica `i` of `method`, tinted.
#[derive(Clone, Debug)]
pub struct Tinted {
    pub method: Method,
    pub factor: Vec3,
}

impl Estimator for Tinted {
    /// E.g. `restir:hybrid × (1, 1, 1.03)`; not a specification [`Method::parse`] reads.
    fn name(&self) -> String {
        let f = self.factor;
        format!("{} × ({}, {}, {})", self.method.name(), f.x, f.y, f.z)
    }

    fn spp(&self) -> u32 {
        self.method.spp()
    }

    fn with_spp(&self, _: u32) -> Option<Method> {
        None
    }

    fn render(
        &self,
        backend: &Backend,
        scene: &Scene,
        frames: u32,
        seed: u64,
    ) -> Result<LastFrame, PipelineError> {
        let rendered = self.method.render_on(backend, scene, frames, seed)?;
        let mut image = rendered.image;
        image.pixels.iter_mut().for_each(|p| *p *= self.factor);
        Ok(LastFrame {
            image,
            frames_rendered: rendered.frames_rendered,
            nonfinite: rendered.nonfinite,
            passes: rendered.passes,
        })
    }

    fn reference(&self) -> PtSettings {
        self.method.reference()
    }

    fn renders_motion(&self) -> bool {
        self.method.renders_motion()
    }
}
