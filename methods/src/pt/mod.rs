//! `pt[:spp]`: the path-traced baseline, BSSRDF importance sampling with every probe hit
//! [001 Eq. 10] (`sss::integrator::pt`; on Vulkan [`vulkan::render`], kernel `method_pt.glsl`,
//! its twin). It has no memory across frames, so only the final frame is rendered.
//! [`path_trace`] is the path tracer on either backend with any hit policy, for this method and
//! its variants (`pt-one-hit`).

pub mod contract;
#[cfg(test)]
mod parity;
pub mod vulkan;

use engine::image::Image;
use engine::{Backend, PipelineError};
use sss::integrator::pt::{self, HitPolicy, PtSettings};
use sss::scene::{GBuffer, Scene};

use crate::estimator::{Entry, LastFrame};
use crate::per_sample::{self, PerSample};

pub const ENTRY: Entry = Entry {
    family: Pt::FAMILY,
    usage: "pt[:spp]",
    about: "path-traced baseline, BSSRDF importance sampling, all probe hits (default 1 spp)",
    build: per_sample::build::<Pt>,
};

/// The path tracer at `spp` samples per pixel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Pt {
    pub spp: u32,
}

impl PerSample for Pt {
    const FAMILY: &'static str = "pt";

    fn at(spp: u32) -> Pt {
        Pt { spp }
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
        path_trace(backend, scene, frame, seed, self.spp, HitPolicy::All)
    }
}

/// Frame `frame` of `scene` path-traced at `spp` samples per pixel with the probe hits chosen
/// by `hits`: `sss::integrator::pt::render` on the CPU; on Vulkan the G-buffer kernel, then the
/// `method_pt` kernel ([`vulkan::render`]), both on the backend's renderer.
pub fn path_trace(
    backend: &Backend,
    scene: &Scene,
    frame: u32,
    seed: u64,
    spp: u32,
    hits: HitPolicy,
) -> Result<LastFrame, PipelineError> {
    let (image, nonfinite) = match backend.renderer() {
        Some(mut renderer) => vulkan::render(&mut renderer, scene, frame, seed, spp, hits)?,
        None => {
            let gbuffer = GBuffer::render(scene, frame);
            let settings = PtSettings {
                hits,
                ..PtSettings::default()
            };
            let image = pt::render(scene, &gbuffer, &settings, seed, 0, spp);
            (to_image(&image), image.nonfinite)
        }
    };
    Ok(LastFrame {
        image,
        frames_rendered: 1,
        nonfinite,
        passes: Vec::new(),
    })
}

/// The `f32` image of an integrator's `f64` per-pixel means.
pub fn to_image(image: &pt::SampleMeans) -> Image {
    Image {
        width: image.width,
        height: image.height,
        pixels: image.pixels.iter().map(|p| p.as_vec3()).collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Method;

    /// Replica seeds are independent draws, and a replica is a function of its seed: the same
    /// seed gives the same bits, another seed a different image (the negative control).
    #[test]
    fn pt_replicas_are_deterministic_per_seed() {
        let scene = Scene::builtin("bumpy").expect("built-in");
        let scene = Scene {
            camera: scene.camera.with_resolution(12, 9),
            ..scene
        };
        let method = Method::parse("pt:2").unwrap();
        let a = method.render(&scene, 16, 3).unwrap();
        let b = method.render(&scene, 16, 3).unwrap();
        let c = method.render(&scene, 16, 4).unwrap();
        assert_eq!(a.image, b.image);
        assert_ne!(a.image, c.image);
        assert_eq!((a.image.width, a.image.height), (12, 9));
        assert!(method.render(&scene, 0, 3).is_err());
    }
}
