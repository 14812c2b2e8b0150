//! Methods that are a sample count and nothing else, `family[:spp]`, and keep no memory across
//! frames (`pt`, `pt-one-hit`, `random-walk`, `image-space`): the [`Estimator`] and the entry's
//! `build` they share, so that such a method writes only how it renders one frame.

use std::fmt;

use engine::{Backend, PipelineError};
use sss::integrator::pt::PtSettings;
use sss::scene::Scene;

use crate::estimator::{Estimator, LastFrame, Method, parse_spp};

/// A memoryless method at a number of samples per pixel; its name is `FAMILY:spp`.
pub trait PerSample: Copy + fmt::Debug + Send + Sync + 'static {
    /// The family its entry registers (`pt`).
    const FAMILY: &'static str;

    /// The method at `spp` samples per pixel.
    fn at(spp: u32) -> Self;

    /// Its samples per pixel.
    fn samples(&self) -> u32;

    /// Frame `frame` of replica `seed` of `scene`'s trajectory on `backend`.
    fn render_frame(
        &self,
        backend: &Backend,
        scene: &Scene,
        frame: u32,
        seed: u64,
    ) -> Result<LastFrame, PipelineError>;

    /// [`Estimator::reference`]: the default path tracer unless the method renders another
    /// transport model.
    fn reference_settings(&self) -> PtSettings {
        PtSettings::default()
    }
}

/// An entry's `build` for `T`: the optional spp after `family:` ([`parse_spp`]).
pub fn build<T: PerSample>(arg: Option<&str>) -> Result<Method, String> {
    Ok(Method::new(T::at(parse_spp(arg)?)))
}

impl<T: PerSample> Estimator for T {
    fn name(&self) -> String {
        format!("{}:{}", T::FAMILY, self.samples())
    }

    fn spp(&self) -> u32 {
        self.samples()
    }

    fn with_spp(&self, spp: u32) -> Option<Method> {
        Some(Method::new(T::at(spp)))
    }

    /// Memoryless: only the last frame is rendered, in the scene posed there.
    fn render(
        &self,
        backend: &Backend,
        scene: &Scene,
        frames: u32,
        seed: u64,
    ) -> Result<LastFrame, PipelineError> {
        let frame = frames - 1;
        self.render_frame(backend, &scene.at_frame(frame), frame, seed)
    }

    fn renders_motion(&self) -> bool {
        true
    }

    fn reference(&self) -> PtSettings {
        self.reference_settings()
    }
}
