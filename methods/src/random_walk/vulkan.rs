//! The random-walk method on the device (`method_random_walk.glsl`, twin of
//! [`super::render`]): volumetric walks on translucent pixels, the path tracer elsewhere, over one
//! frame's G-buffer; driven through the engine's [`Renderer`] ([`render`]).
//!
//! The walk needs per-material values that `GpuMaterial` lacks (`σs`, `σt`, the interface):
//! they live in this method's own buffer, binding 11 ([`GpuMedium`]), computed on the host by
//! [`Medium::from_translucent`] exactly as the CPU computes them (its colour mapping uses
//! transcendentals the GPU must not redo). Binding 12 returns how each pixel's walks ended
//! ([`WalkStats`]); binding 13 carries each pixel's streams and sums between dispatches.
//!
//! **One dispatch per sample.** Lavapipe shares one budget of 65 535 loop iterations among all
//! loops of an invocation group and silently cuts every loop short once it is spent (gallivm's
//! `LP_MAX_TGSI_LOOP_ITERATIONS`); a few long walks in one invocation exceed it. So dispatch
//! `s` runs sample `s` of every pixel, and the kernel counts in [`WalkStats::cut`] the
//! dispatches whose loops were cut anyway; [`RandomWalkImage::cut`] sums them, and a caller must
//! treat a non-zero count as a failed render.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use sss::random_walk::{Interface, Medium};
use sss::scene::Scene;

use engine::PipelineError;
use engine::image::Image;
use engine::vulkan::{
    Buffer, Context, DeviceImage, FrameInput, Kernel, LoopsCut, MethodParams, Renderer, Shader,
    VulkanError, groups_for,
};

/// `method_random_walk.glsl`: scene bindings 0–8, 9 G-buffer (`GpuPixel`), 10 `vec4` out (mean,
/// `w` = non-finite samples left out), 11 [`GpuMedium`] per material, 12 [`WalkStats`] per
/// pixel, 13 the per-pixel state carried between dispatches (bindings 11–13 are this method's
/// own, after the contract's 0–10). Push constants: [`MethodParams`], `pad[0]` = the sample.
pub const RANDOM_WALK: Shader = Shader::compiled(
    "method_random_walk",
    crate::spirv!("method_random_walk"),
    14,
    size_of::<MethodParams>() as u32,
);

/// The `random-walk:spp` method at `frame`: the image and the samples left out; a dispatch whose
/// loops the device cut short is an error.
pub fn render(
    renderer: &mut Renderer,
    scene: &Scene,
    frame: u32,
    seed: u64,
    spp: u32,
) -> Result<(Image, u64), PipelineError> {
    let media = scene_media(scene)?;
    let (out, _) =
        renderer.method_frame(scene, frame, seed, RANDOM_WALK, |context, kernel, input| {
            render_random_walk(context, kernel, input, &media, spp)
        })?;
    Ok((out.image.image, out.image.left_out))
}

/// `random_walk.glsl`'s `RandomWalkMedium` (std430, 48 bytes): one material's medium. The kernel
/// reads it only for translucent materials (it decides by `GpuMaterial`'s kind, as the CPU
/// method does); Lambert materials get a zeroed placeholder.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuMedium {
    /// [`Medium::sigma_s`].
    pub sigma_s: [f32; 3],
    /// [`Medium::sigma_t`], computed on the host.
    pub sigma_t: [f32; 3],
    /// Henyey–Greenstein mean cosine.
    pub g: f32,
    /// The [`BoundaryKind`](sss::material::BoundaryKind) code of [`Medium::interface`].
    pub interface: u32,
    /// `η` of a dielectric interface (0 otherwise).
    pub eta: f32,
    pub pad: [u32; 3],
}

impl GpuMedium {
    /// The device layout of `medium` (Henyey–Greenstein phase).
    pub fn new(medium: &Medium) -> GpuMedium {
        let interface = medium.interface();
        let eta = match interface {
            Interface::Dielectric { eta } => eta,
            Interface::IndexMatched | Interface::Diffuse => 0.0,
        };
        GpuMedium {
            sigma_s: medium.sigma_s().to_array(),
            sigma_t: medium.sigma_t().to_array(),
            g: medium.phase().g(),
            interface: interface.kind().code(),
            eta,
            pad: [0; 3],
        }
    }
}

/// The media of `scene`'s materials as the CPU method builds them ([`Medium::of_scene`]),
/// Lambert ones a zeroed placeholder. The CPU's error for a material the walk cannot take
/// (`fit = "dmfp"`).
pub fn scene_media(scene: &Scene) -> Result<Vec<GpuMedium>, PipelineError> {
    let media =
        Medium::of_scene(scene).map_err(|e| PipelineError::Config(format!("random-walk: {e}")))?;
    Ok(media
        .iter()
        .map(|m| m.as_ref().map_or_else(GpuMedium::default, GpuMedium::new))
        .collect())
}

/// `method_random_walk.glsl`'s `RandomWalkStats` (std430, 36 bytes): how one pixel's walks
/// ended. All zero on pixels without walks except `nonfinite` and `cut`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct WalkStats {
    /// Sum over exited walks of their exit weight (`walk::Exit::weight`).
    pub weight_sum: [f32; 3],
    /// The largest `|weight_c − 1|` of an exited walk.
    pub max_weight_deviation: f32,
    pub exited: u32,
    /// Killed by Russian roulette, zero weight, or `ωo` below the surface (no walk).
    pub terminated: u32,
    /// Cut off at the bounce cap or the mesh boundary's entry-skip cap (`random_walk.glsl`).
    pub truncated: u32,
    /// Samples (walks or path-traced) left out of the mean as NaN or infinite.
    pub nonfinite: u32,
    /// Dispatches in which the device cut this pixel's loops short (see the module doc).
    pub cut: u32,
}

/// `method_random_walk.glsl`'s `RandomWalkPixelState` (std430, 64 bytes): the walk and
/// light-selection streams (PCG32 state and increment), the f64 sum of finite samples and their
/// count. Only its size matters to the host.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
struct WalkPixelState {
    streams: [u64; 4],
    sum: [f64; 3],
    finite: u32,
    pad: u32,
}

/// One frame of the random-walk method read back: the image (`left_out` = non-finite walk and
/// path-traced samples), every pixel's [`WalkStats`], and the sum of their `cut` counts (non-zero:
/// the device cut loops short and the image is not to be trusted).
#[derive(Clone, Debug, PartialEq)]
pub struct RandomWalkImage {
    pub image: DeviceImage,
    pub stats: Vec<WalkStats>,
    pub cut: u64,
}

impl LoopsCut for RandomWalkImage {
    fn loops_cut(&self) -> u64 {
        self.cut
    }
}

/// The `random-walk:spp` method on one frame (the kernel of [`RANDOM_WALK`]): `spp` walks per
/// translucent pixel in the media `media` (one per material of the scene, e.g. [`scene_media`]),
/// `spp` path-traced samples per other pixel, in `max(spp, 1)` dispatches.
pub fn render_random_walk(
    context: &mut Context,
    kernel: &Kernel,
    frame: &FrameInput,
    media: &[GpuMedium],
    spp: u32,
) -> Result<RandomWalkImage, VulkanError> {
    let count = frame.width * frame.height;
    // Vulkan buffers cannot be empty; a scene without materials has no pixel that reads one.
    let media = if media.is_empty() {
        Buffer::from_slice(context, &[GpuMedium::default()])?
    } else {
        Buffer::from_slice(context, media)?
    };
    let output = Buffer::zeroed(context, count as usize * 16)?;
    let stats = Buffer::zeroed(context, count as usize * size_of::<WalkStats>())?;
    let states = Buffer::zeroed(context, count as usize * size_of::<WalkPixelState>())?;
    let mut buffers: Vec<&Buffer> = frame.scene.buffers().to_vec();
    buffers.extend_from_slice(&[
        frame.params,
        frame.gbuffer,
        &output,
        &media,
        &stats,
        &states,
    ]);
    for sample in 0..spp.max(1) {
        let params = MethodParams {
            spp,
            pad: [sample, 0, 0, 0, 0, 0, 0],
        };
        context.dispatch(
            kernel,
            &buffers,
            bytemuck::bytes_of(&params),
            [groups_for(count, RANDOM_WALK.local_size), 1, 1],
        )?;
    }
    let texels = output.read::<[f32; 4]>()?;
    let stats = stats.read::<WalkStats>()?;
    Ok(RandomWalkImage {
        image: DeviceImage {
            image: Image {
                width: frame.width,
                height: frame.height,
                pixels: texels.iter().map(|t| Vec3::new(t[0], t[1], t[2])).collect(),
            },
            left_out: texels.iter().map(|t| t[3] as u64).sum(),
        },
        cut: stats.iter().map(|s| u64::from(s.cut)).sum(),
        stats,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use sss::material::{BoundaryKind, Material};
    use std::mem::offset_of;
    use std::path::Path;

    #[test]
    fn buffer_structs_match_std430() {
        assert_eq!((size_of::<GpuMedium>(), align_of::<GpuMedium>()), (48, 4));
        assert_eq!(offset_of!(GpuMedium, g), 24);
        assert_eq!(offset_of!(GpuMedium, eta), 32);
        assert_eq!((size_of::<WalkStats>(), align_of::<WalkStats>()), (36, 4));
        assert_eq!(offset_of!(WalkStats, exited), 16);
        assert_eq!(offset_of!(WalkStats, cut), 32);
        assert_eq!(
            (size_of::<WalkPixelState>(), align_of::<WalkPixelState>()),
            (64, 8)
        );
        assert_eq!(offset_of!(WalkPixelState, sum), 32);
        assert_eq!(offset_of!(WalkPixelState, finite), 56);
    }

    /// `bumpy`'s translucent material maps to the CPU's medium bit for bit, with the material's
    /// boundary (diffuse by default, a dielectric with its `ior` when asked); its Lambert ones
    /// are opaque; a `dmfp` material is the CPU's configuration error.
    #[test]
    fn scene_media_are_the_cpu_media() {
        let scene = Scene::builtin("bumpy").expect("built-in");
        let media = scene_media(&scene).unwrap();
        assert_eq!(media.len(), scene.materials.len());
        for (m, gpu) in scene.materials.iter().zip(&media) {
            match m {
                Material::Translucent(t) => {
                    let cpu = Medium::from_translucent(t, Path::new("x"), "m").unwrap();
                    assert_eq!(*gpu, GpuMedium::new(&cpu));
                    assert_eq!(gpu.interface, BoundaryKind::Diffuse.code());
                }
                Material::Lambert(_) => assert_eq!(*gpu, GpuMedium::default()),
            }
        }
        let mut dielectric = Scene::builtin("bumpy").expect("built-in");
        for m in &mut dielectric.materials {
            if let Material::Translucent(t) = m {
                t.boundary = BoundaryKind::Dielectric;
            }
        }
        for (m, gpu) in dielectric
            .materials
            .iter()
            .zip(scene_media(&dielectric).unwrap())
        {
            if let Material::Translucent(t) = m {
                assert_eq!(
                    (gpu.interface, gpu.eta),
                    (BoundaryKind::Dielectric.code(), t.ior)
                );
            }
        }
        let mut dmfp = Scene::builtin("bumpy").expect("built-in");
        for m in &mut dmfp.materials {
            if let Material::Translucent(t) = m {
                t.fit = sss::profile::ScaleFit::Dmfp;
            }
        }
        assert!(matches!(scene_media(&dmfp), Err(PipelineError::Config(_))));
    }
}
