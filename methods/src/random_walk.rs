//! `random-walk[:spp]`: the volumetric random walk on translucent pixels and the path tracer
//! on the others (`engine::random_walk_method`; on Vulkan `method_random_walk.glsl`) — another
//! transport model than the BSSRDF, the ground truth of the diffusion approximation [000].
//! Memoryless like `pt`: only the final frame is rendered.

use engine::random_walk_method;
use engine::{Backend, PipelineError};
use sss::scene::{GBuffer, Scene};

use super::estimator::{Entry, Estimator, LastFrame, Method, parse_spp};

pub const ENTRY: Entry = Entry {
    family: "random-walk",
    usage: "random-walk[:spp]",
    about: "volumetric random walk on translucent pixels (another transport model than the BSSRDF)",
    build: |arg| {
        Ok(Method::new(RandomWalk {
            spp: parse_spp(arg)?,
        }))
    },
};

/// `spp` walks per translucent pixel, `spp` path-traced samples elsewhere.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RandomWalk {
    pub spp: u32,
}

impl Estimator for RandomWalk {
    fn name(&self) -> String {
        format!("random-walk:{}", self.spp)
    }

    fn spp(&self) -> u32 {
        self.spp
    }

    fn with_spp(&self, spp: u32) -> Option<Method> {
        Some(Method::new(RandomWalk { spp }))
    }

    fn render(
        &self,
        backend: &Backend,
        scene: &Scene,
        frames: u32,
        seed: u64,
    ) -> Result<LastFrame, PipelineError> {
        let last = frames - 1;
        let (image, nonfinite) = match backend.renderer() {
            Some(mut renderer) => renderer.random_walk(scene, last, seed, self.spp)?,
            None => {
                let gbuffer = GBuffer::render(scene, last);
                random_walk_method::render(scene, &gbuffer, seed, self.spp)?
            }
        };
        Ok(LastFrame {
            image,
            frames_rendered: 1,
            nonfinite,
        })
    }
}
