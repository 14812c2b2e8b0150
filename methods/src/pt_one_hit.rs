//! `pt-one-hit[:spp]`: the path tracer that keeps one probe hit per BSSRDF sample, picked
//! uniformly and weighted by the hit count [001 Eq. 9], where `pt` keeps every hit
//! [001 Eq. 10]. Both are unbiased (`sss/tests/hit_policies.rs`); this one traces one shadow ray
//! per sample instead of one per hit. The worked example of docs/adding-a-method.md.

use engine::{Backend, PipelineError};
use sss::integrator::pt::HitPolicy;
use sss::scene::Scene;

use super::estimator::{Entry, Estimator, LastFrame, Method, parse_spp};
use super::pt::path_trace;

pub const ENTRY: Entry = Entry {
    family: "pt-one-hit",
    usage: "pt-one-hit[:spp]",
    about: "path tracer keeping one probe hit per sample, weighted by the hit count [001 Eq. 9]",
    build: |arg| {
        Ok(Method::new(PtOneHit {
            spp: parse_spp(arg)?,
        }))
    },
};

/// The one-hit path tracer at `spp` samples per pixel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PtOneHit {
    pub spp: u32,
}

impl Estimator for PtOneHit {
    fn name(&self) -> String {
        format!("pt-one-hit:{}", self.spp)
    }

    fn spp(&self) -> u32 {
        self.spp
    }

    fn with_spp(&self, spp: u32) -> Option<Method> {
        Some(Method::new(PtOneHit { spp }))
    }

    /// Memoryless: only the last frame is rendered.
    fn render(
        &self,
        backend: &Backend,
        scene: &Scene,
        frames: u32,
        seed: u64,
    ) -> Result<LastFrame, PipelineError> {
        path_trace(
            backend,
            scene,
            frames - 1,
            seed,
            self.spp,
            HitPolicy::UniformOne,
        )
    }
}
