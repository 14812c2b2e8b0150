//! Paper 000's hybrid estimator on the device (`method_single_scatter.glsl`, twin of the
//! `single-scatter` method over [`sss::integrator::single_scatter::render`]): path-traced zero
//! and single scattering plus diffusion with `R − R1` on translucent pixels, the path tracer's
//! direct lighting elsewhere, the exits lit by the scene's lights with shadow rays; driven
//! through the engine's [`Renderer`] ([`render`]).
//!
//! The estimator needs per-material values that `GpuMaterial` lacks: the medium (binding 11,
//! the random walk's [`GpuMedium`]) and the multiple-scattering profiles (binding 13,
//! [`GpuSingleScatterProfile`]), both computed on the host exactly as the CPU computes them
//! ([`Medium::from_translucent`], [`MultipleScattering::new`]: colour mapping and `r_max` take
//! transcendentals the GPU must not redo). Binding 12 carries each pixel's light-selection stream,
//! sum and tallies between dispatches ([`SingleScatterPixelState`]).
//!
//! **One dispatch per sample**, as the random walk ([`render_random_walk`](crate::random_walk::vulkan::render_random_walk)):
//! lavapipe cuts every loop of an invocation group after 65 535 iterations; the kernel counts the
//! dispatches where it did, [`SingleScatterImage::cut`] sums them, and a caller must treat a
//! non-zero count as a failed render.

use bytemuck::{Pod, Zeroable};
use engine::PipelineError;
use engine::contract::PtHits;
use engine::image::Image;
use engine::vulkan::{
    Buffer, Context, DeviceImage, FrameInput, Kernel, LoopsCut, Renderer, Shader, VulkanError,
    groups_for,
};
use sss::integrator::HitPolicy;
use sss::integrator::pt::PtSettings;
use sss::integrator::single_scatter::{
    ChannelSelection, MultipleScattering, SingleScatterSettings,
};
use sss::random_walk::Medium;
use sss::scene::Scene;

use super::contract::SingleScatterParams;
use crate::random_walk::vulkan::GpuMedium;

/// `method_single_scatter.glsl`: scene bindings 0–8, 9 G-buffer (`GpuPixel`), 10 `vec4` out
/// (mean, `w` = samples left out), 11 [`GpuMedium`] per material, 12 [`SingleScatterPixelState`]
/// per pixel, 13 [`GpuSingleScatterProfile`] per material. Push constants:
/// [`SingleScatterParams`].
pub const SINGLE_SCATTER: Shader = Shader::compiled(
    "method_single_scatter",
    crate::spirv!("method_single_scatter"),
    14,
    size_of::<SingleScatterParams>() as u32,
);

/// The `single-scatter:spp` method at `frame` with distance channels drawn by `channels` (the
/// rest of [`SingleScatterSettings::default`]): the image and the samples left out; a dispatch
/// whose loops the device cut short is an error.
pub fn render(
    renderer: &mut Renderer,
    scene: &Scene,
    frame: u32,
    seed: u64,
    spp: u32,
    channels: ChannelSelection,
) -> Result<(Image, u64), PipelineError> {
    let settings = SingleScatterSettings {
        channel: channels,
        ..SingleScatterSettings::default()
    };
    let media = scene_single_scatter_media(scene)?;
    let (out, _) = renderer.method_frame(
        scene,
        frame,
        seed,
        SINGLE_SCATTER,
        |context, kernel, input| {
            render_single_scatter(context, kernel, input, &media, &settings, spp)
        },
    )?;
    Ok((out.image.image, out.image.left_out))
}

/// `single_scatter.glsl`'s `SingleScatterProfile` (std430, 60 bytes): [`MultipleScattering`]
/// with the full profiles' `r_max` computed on the host.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuSingleScatterProfile {
    pub full_albedo: [f32; 3],
    pub full_d: [f32; 3],
    pub full_r_max: [f32; 3],
    pub single_albedo: [f32; 3],
    pub single_d: [f32; 3],
}

impl GpuSingleScatterProfile {
    pub fn new(m: &MultipleScattering) -> GpuSingleScatterProfile {
        GpuSingleScatterProfile {
            full_albedo: m.full_albedo.to_array(),
            full_d: m.full.map(|b| b.d),
            full_r_max: m.full.map(|b| b.r_max()),
            single_albedo: m.single_albedo.to_array(),
            single_d: m.single.map(|b| b.d),
        }
    }
}

/// The media and multiple-scattering profiles of `scene`'s materials as the CPU estimator builds
/// them ([`Medium::of_scene`], [`MultipleScattering::new`]), Lambert ones zeroed placeholders.
/// The CPU's error for a material the medium mapping rejects (`fit = "dmfp"`).
pub fn scene_single_scatter_media(
    scene: &Scene,
) -> Result<(Vec<GpuMedium>, Vec<GpuSingleScatterProfile>), PipelineError> {
    let media = Medium::of_scene(scene)
        .map_err(|e| PipelineError::Config(format!("single-scatter: {e}")))?;
    Ok(media
        .iter()
        .map(|m| match m {
            Some(m) => (
                GpuMedium::new(m),
                GpuSingleScatterProfile::new(&MultipleScattering::new(m)),
            ),
            None => Default::default(),
        })
        .unzip())
}

/// `method_single_scatter.glsl`'s `SingleScatterPixelState` (std430, 56 bytes): the
/// light-selection stream (PCG32 state and increment), the f64 sum of finite samples, the samples
/// left out, the samples whose chain was cut, the dispatches whose loops the device cut short.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct SingleScatterPixelState {
    pub selection: [u64; 2],
    pub sum: [f64; 3],
    pub left_out: u32,
    /// Samples with `Orders::truncated` (a chain cut at `max_segments`, or a mesh query past
    /// the device's entry-skip cap).
    pub truncated: u32,
    pub cut: u32,
    pub pad: u32,
}

/// One frame of the single-scatter method read back: the image (`left_out` = non-finite samples
/// and samples whose probe had more hits than kept), the samples whose chain was cut, and the
/// dispatches whose loops the device cut short (non-zero: the image is not to be trusted).
#[derive(Clone, Debug, PartialEq)]
pub struct SingleScatterImage {
    pub image: DeviceImage,
    pub truncated: u64,
    pub cut: u64,
}

impl LoopsCut for SingleScatterImage {
    fn loops_cut(&self) -> u64 {
        self.cut
    }
}

/// The `single-scatter:spp` method on one frame (the kernel of [`SINGLE_SCATTER`]): samples
/// `0..spp` of every pixel with `settings` (its channel selection, the diffusion's hit policy and
/// `max_segments`; the kernel's diffusion has [`PtSettings::default`]'s techniques, radii and
/// profile, so other `settings.diffusion` are a configuration error), in the media and profiles
/// `media` (one pair per material, e.g. [`scene_single_scatter_media`]), in `spp` dispatches.
pub fn render_single_scatter(
    context: &mut Context,
    kernel: &Kernel,
    frame: &FrameInput,
    media: &(Vec<GpuMedium>, Vec<GpuSingleScatterProfile>),
    settings: &SingleScatterSettings,
    spp: u32,
) -> Result<SingleScatterImage, VulkanError> {
    let hits = kernel_hits(&settings.diffusion)?;
    let count = frame.width * frame.height;
    // Vulkan buffers cannot be empty; a scene without materials has no pixel that reads one.
    let (media, profiles) = if media.0.is_empty() {
        (
            Buffer::from_slice(context, &[GpuMedium::default()])?,
            Buffer::from_slice(context, &[GpuSingleScatterProfile::default()])?,
        )
    } else {
        (
            Buffer::from_slice(context, &media.0)?,
            Buffer::from_slice(context, &media.1)?,
        )
    };
    let output = Buffer::zeroed(context, count as usize * 16)?;
    let states = Buffer::zeroed(
        context,
        count as usize * size_of::<SingleScatterPixelState>(),
    )?;
    let buffers = frame.bindings(&[&output, &media, &states, &profiles])?;
    for sample_index in 0..spp {
        let params = SingleScatterParams {
            spp,
            sample_index,
            channel_selection: settings.channel.code(),
            hits,
            max_segments: settings.max_segments,
            pad: [0; 3],
        };
        context.dispatch(
            kernel,
            &buffers,
            bytemuck::bytes_of(&params),
            [groups_for(count, SINGLE_SCATTER.local_size), 1, 1],
        )?;
    }
    let states = states.read::<SingleScatterPixelState>()?;
    Ok(SingleScatterImage {
        image: frame.read_image(&output)?,
        truncated: states.iter().map(|s| u64::from(s.truncated)).sum(),
        cut: states.iter().map(|s| u64::from(s.cut)).sum(),
    })
}

/// The `PtHits` code of `diffusion`'s hit policy, or a [`VulkanError::Binding`] when its other
/// knobs are not the kernel's ([`PtSettings::default`]'s techniques, radii and profile).
fn kernel_hits(diffusion: &PtSettings) -> Result<u32, VulkanError> {
    let kernel = PtSettings {
        hits: diffusion.hits,
        ..PtSettings::default()
    };
    if *diffusion != kernel {
        return Err(VulkanError::Binding(format!(
            "single-scatter: the kernel's diffusion has the default techniques, radii and \
             profile, not {diffusion:?}"
        )));
    }
    Ok(match diffusion.hits {
        HitPolicy::UniformOne => PtHits::UniformOne,
        HitPolicy::All => PtHits::All,
    }
    .code())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::mem::offset_of;

    #[test]
    fn buffer_structs_match_std430() {
        assert_eq!(
            (
                size_of::<GpuSingleScatterProfile>(),
                align_of::<GpuSingleScatterProfile>()
            ),
            (60, 4)
        );
        assert_eq!(offset_of!(GpuSingleScatterProfile, single_d), 48);
        assert_eq!(
            (
                size_of::<SingleScatterPixelState>(),
                align_of::<SingleScatterPixelState>()
            ),
            (56, 8)
        );
        assert_eq!(offset_of!(SingleScatterPixelState, sum), 16);
        assert_eq!(offset_of!(SingleScatterPixelState, left_out), 40);
        assert_eq!(offset_of!(SingleScatterPixelState, cut), 48);
        // `method_single_scatter.glsl`'s push-constant block: eight `uint`s.
        assert_eq!(size_of::<SingleScatterParams>(), 32);
    }

    /// Both hit policies reach the kernel; a diffusion with other techniques, radii or profile
    /// than the kernel's is refused in one line.
    #[test]
    fn only_the_kernels_diffusion_is_accepted() {
        for (hits, code) in [
            (HitPolicy::All, PtHits::All),
            (HitPolicy::UniformOne, PtHits::UniformOne),
        ] {
            let diffusion = PtSettings {
                hits,
                ..PtSettings::default()
            };
            assert_eq!(kernel_hits(&diffusion).unwrap(), code.code());
        }
        let dipole = PtSettings {
            profile: sss::profile::ProfileKind::Dipole,
            ..PtSettings::default()
        };
        let line = kernel_hits(&dipole).unwrap_err().to_string();
        assert!(line.contains("Dipole") && !line.contains('\n'), "{line}");
    }

    /// `bumpy`'s translucent material gets the CPU's medium and profiles bit for bit, its Lambert
    /// ones zeroed placeholders; a `dmfp` material is the CPU's configuration error.
    #[test]
    fn scene_media_are_the_cpu_estimators() {
        let scene = Scene::builtin("bumpy").expect("built-in");
        let (media, profiles) = scene_single_scatter_media(&scene).unwrap();
        let cpu = Medium::of_scene(&scene).unwrap();
        assert_eq!((media.len(), profiles.len()), (cpu.len(), cpu.len()));
        assert!(cpu.iter().any(Option::is_some) && cpu.iter().any(Option::is_none));
        for ((m, gpu), profile) in cpu.iter().zip(&media).zip(&profiles) {
            match m {
                Some(m) => {
                    assert_eq!(*gpu, GpuMedium::new(m));
                    let multiple = MultipleScattering::new(m);
                    assert_eq!(profile.full_d, multiple.full.map(|b| b.d));
                    assert_eq!(profile.full_r_max, multiple.full.map(|b| b.r_max()));
                    assert!(profile.full_r_max.iter().all(|r| *r > 0.0));
                }
                None => {
                    assert_eq!(*gpu, GpuMedium::default());
                    assert_eq!(*profile, GpuSingleScatterProfile::default());
                }
            }
        }
        let mut dmfp = scene;
        for m in &mut dmfp.materials {
            if let sss::material::Material::Translucent(t) = m {
                t.fit = sss::profile::ScaleFit::Dmfp;
            }
        }
        assert!(matches!(
            scene_single_scatter_media(&dmfp),
            Err(PipelineError::Config(_))
        ));
    }
}
