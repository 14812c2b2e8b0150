//! `pt-one-hit[:spp]`: the path tracer that keeps one probe hit per BSSRDF sample, picked
//! uniformly and weighted by the hit count [001 Eq. 9], where `pt` keeps every hit
//! [001 Eq. 10]. Both are unbiased (`sss/tests/hit_policies.rs`); this one traces one shadow ray
//! per sample instead of one per hit. The worked example of docs/adding-a-method.md.

use engine::{Backend, PipelineError};
use sss::integrator::pt::HitPolicy;
use sss::scene::Scene;

use super::estimator::{Entry, LastFrame};
use super::per_sample::{self, PerSample};
use super::pt::path_trace;

pub const ENTRY: Entry = Entry {
    family: PtOneHit::FAMILY,
    usage: "pt-one-hit[:spp]",
    about: "path tracer keeping one probe hit per sample, weighted by the hit count [001 Eq. 9]",
    build: per_sample::build::<PtOneHit>,
};

/// The one-hit path tracer at `spp` samples per pixel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PtOneHit {
    pub spp: u32,
}

impl PerSample for PtOneHit {
    const FAMILY: &'static str = "pt-one-hit";

    fn at(spp: u32) -> PtOneHit {
        PtOneHit { spp }
    }

    fn samples(&self) -> u32 {
        self.spp
    }

    fn render_frame(
        &self,
        backend: &Backend,
        scene: &Scene,
        frame: u32,
        seed: u64,
    ) -> Result<LastFrame, PipelineError> {
        path_trace(backend, scene, frame, seed, self.spp, HitPolicy::UniformOne)
    }
}
