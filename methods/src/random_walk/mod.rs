//! `random-walk[:spp]`: the volumetric random walk of `sss::random_walk` on the pixels whose
//! primary hit is translucent and the path tracer on the others ([`render`]; on Vulkan
//! [`vulkan::render`], kernel `method_random_walk.glsl`) — another transport model than the
//! BSSRDF, the ground truth of the diffusion approximation [000]. Memoryless like `pt`: only the
//! final frame is rendered.
//!
//! Model choices (a different transport model than the BSSRDF methods, so `compare` measures
//! its difference to the BSSRDF reference, not only its noise):
//! * the medium is the material's by paper 000's colour mapping ([`Medium::from_translucent`]),
//!   so `fit = "dmfp"` materials are an input error;
//! * the boundary is the material's `boundary` ([`Interface::of`]); the default, Fresnel-free
//!   Lambertian transmission, has the exit lobe `1/π` of the diffusion profiles and lets exits
//!   use next-event estimation (a smooth dielectric exit reaches area lights only by chance);
//! * the boundary is the hit object's own mesh; x1's outward normal comes from its winding as
//!   seen by the camera (the camera sees closed objects from outside).
//!
//! [`Interface::of`]: sss::random_walk::Interface::of
//!
//!
//! The exits are lit by the engine's [`SceneLighting`] (shared with single-scatter).

pub mod vulkan;

use std::cell::RefCell;

use engine::image::Image;
use engine::scene_lighting::SceneLighting;
use engine::{Backend, PipelineError};
use glam::{DVec3, Vec3};
use restir::rng::{Stream, StreamKey};
use sss::integrator::pt::{self, PtSettings};
use sss::random_walk::{Medium, MeshBoundary, estimate_exitant};
use sss::scene::{GBuffer, GPixel, Scene};

use super::estimator::{Entry, LastFrame};
use super::per_sample::{self, PerSample};

/// `purpose` of the walks' streams and of the light-selection numbers of [`SceneLighting`].
pub use engine::purpose::{WALK as PURPOSE_WALK, WALK_LIGHT as PURPOSE_WALK_LIGHT};

pub const ENTRY: Entry = Entry {
    family: RandomWalk::FAMILY,
    usage: "random-walk[:spp]",
    about: "volumetric random walk on translucent pixels (another transport model than the BSSRDF)",
    build: per_sample::build::<RandomWalk>,
};

/// `spp` walks per translucent pixel, `spp` path-traced samples elsewhere.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RandomWalk {
    pub spp: u32,
}

impl PerSample for RandomWalk {
    const FAMILY: &'static str = "random-walk";

    fn at(spp: u32) -> RandomWalk {
        RandomWalk { spp }
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
        let (image, nonfinite) = match backend.renderer() {
            Some(mut renderer) => vulkan::render(&mut renderer, scene, frame, seed, self.spp)?,
            None => {
                let gbuffer = GBuffer::render(scene, frame);
                render(scene, &gbuffer, seed, self.spp)?
            }
        };
        Ok(LastFrame {
            image,
            frames_rendered: 1,
            nonfinite,
            passes: Vec::new(),
        })
    }
}

/// What the walks of one translucent pixel need: the object's mesh as the boundary, the outward
/// normal at x1, the scene's lights with the pixel's light-selection stream, and the pixel's
/// walk stream (both keyed by pixel, frame and seed).
pub struct PixelWalk<'a> {
    pub boundary: MeshBoundary<'a>,
    pub n1: Vec3,
    pub lighting: SceneLighting<'a>,
    pub stream: Stream,
}

impl<'a> PixelWalk<'a> {
    pub fn new(scene: &'a Scene, g: &GPixel, pixel: u32, frame: u32, seed: u64) -> PixelWalk<'a> {
        let n = scene.geometry.geometric_normal(g.prim);
        let inward_winding = n.dot(g.view) < 0.0;
        let key = |purpose| StreamKey {
            pixel,
            frame,
            pass: 0,
            purpose,
        };
        PixelWalk {
            boundary: MeshBoundary {
                geometry: &scene.geometry,
                object: g.object,
                inward_winding,
            },
            n1: if inward_winding { -n } else { n },
            lighting: SceneLighting {
                scene,
                selection: RefCell::new(key(PURPOSE_WALK_LIGHT).stream(seed)),
            },
            stream: key(PURPOSE_WALK).stream(seed),
        }
    }
}

/// Renders frame `gbuffer.frame`: translucent pixels by `spp` random walks each, the others by
/// the path tracer at `spp`. Returns the image and the number of non-finite estimates (left out).
pub fn render(
    scene: &Scene,
    gbuffer: &GBuffer,
    seed: u64,
    spp: u32,
) -> Result<(Image, u64), PipelineError> {
    let media =
        Medium::of_scene(scene).map_err(|e| PipelineError::Config(format!("random-walk: {e}")))?;
    let base = pt::render(scene, gbuffer, &PtSettings::default(), seed, 0, spp);
    let mut nonfinite = base.nonfinite;
    let mut pixels: Vec<DVec3> = base.pixels;
    for (index, (out, g)) in pixels.iter_mut().zip(&gbuffer.pixels).enumerate() {
        let Some(g) = g else { continue };
        let material = scene.objects[g.object as usize].material as usize;
        let Some(medium) = &media[material] else {
            continue;
        };
        let PixelWalk {
            boundary,
            n1,
            lighting,
            mut stream,
        } = PixelWalk::new(scene, g, index as u32, gbuffer.frame, seed);
        let (mut sum, mut finite) = (DVec3::ZERO, 0u32);
        for _ in 0..spp {
            let l = estimate_exitant(
                &boundary,
                medium,
                g.position,
                n1,
                g.view,
                &lighting,
                &mut stream,
            );
            if l.is_finite() {
                sum += l.as_dvec3();
                finite += 1;
            } else {
                nonfinite += 1;
            }
        }
        *out = if finite > 0 {
            sum / finite as f64
        } else {
            DVec3::ZERO
        };
    }
    Ok((
        Image {
            width: gbuffer.width,
            height: gbuffer.height,
            pixels: pixels.iter().map(|p| p.as_vec3()).collect(),
        },
        nonfinite,
    ))
}
