//! The image-space method of paper 002 on the device (`method_image_space.glsl`, twin of
//! [`cpu::render`](super::cpu::render)): per pass an irradiance dispatch and a gather dispatch over one frame's
//! G-buffer, driven through the engine's [`Renderer`] ([`render`]).
//!
//! The gather needs per-material values that `GpuMaterial` lacks (the three dipoles, `ρ_c`, the
//! renormalised `P(c)`): they live in this method's own buffer, binding 12 ([`GpuGatherProfile`]),
//! computed on the host by [`GatherProfile::new`] exactly as the CPU computes them (the dipole's
//! constants take `sqrt`, `exp` and the boundary term, which the GPU must not redo). Binding 11 is
//! the pass's irradiance, binding 13 carries each pixel's sum, tallies and [`EntryCounts`] between
//! dispatches ([`ImageSpaceState`]).

use bytemuck::{Pod, Zeroable};
use engine::image::Image;
use engine::vulkan::{
    Buffer, Context, DeviceImage, FrameInput, Kernel, LoopsCut, Renderer, Shader, VulkanError,
    groups_for,
};
use sss::material::FresnelTransmission;
use sss::profile::{Dipole, Pole};
use sss::scene::Scene;

use super::contract::{ImageSpaceParams, ImageSpaceStage, ImageSpaceState};
use super::cpu::{EntryCounts, GatherProfile, ImageSpaceSettings, gather_profiles};

/// `method_image_space.glsl`: scene bindings 0–8, 9 G-buffer (`GpuPixel`), 10 `vec4` out (mean,
/// `w` = pass values left out), 11 `vec4` irradiance per pixel, 12 [`GpuGatherProfile`] per
/// material, 13 [`ImageSpaceState`] per pixel. Push constants: [`ImageSpaceParams`].
pub const IMAGE_SPACE: Shader = Shader::compiled(
    "method_image_space",
    crate::spirv!("method_image_space"),
    14,
    size_of::<ImageSpaceParams>() as u32,
);

/// The `image-space:spp` method at `frame` with the default sample counts
/// ([`ImageSpaceSettings::default`]): the image and the pass values left out; a dispatch whose
/// loops the device cut short is an error.
pub fn render(
    renderer: &mut Renderer,
    scene: &Scene,
    frame: u32,
    seed: u64,
    spp: u32,
) -> Result<(Image, u64), VulkanError> {
    let settings = ImageSpaceSettings::default();
    let profiles = scene_gather_profiles(scene, &settings);
    let (out, _) =
        renderer.method_frame(scene, frame, seed, IMAGE_SPACE, |context, kernel, input| {
            render_image_space(context, kernel, input, &profiles, &settings, spp)
        })?;
    Ok((out.image.image, out.image.left_out))
}

/// `dipole.glsl`'s `GpuDipole` (std430, 24 bytes): a [`Dipole`]'s constants with its real pole's
/// probability and `ρ`, computed on the host.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuDipole {
    pub reduced_albedo: f32,
    pub sigma_tr: f32,
    pub z_r: f32,
    pub z_v: f32,
    /// [`Dipole::pole_probability`] of the real pole.
    pub p_real: f32,
    /// [`Dipole::total_reflectance`].
    pub rho: f32,
}

impl GpuDipole {
    pub fn new(d: &Dipole) -> GpuDipole {
        GpuDipole {
            reduced_albedo: d.reduced_albedo(),
            sigma_tr: d.sigma_tr(),
            z_r: d.depth(Pole::Real),
            z_v: d.depth(Pole::Virtual),
            p_real: d.pole_probability(Pole::Real),
            rho: d.total_reflectance(),
        }
    }
}

/// `image_space.glsl`'s `GatherProfile` (std430, 108 bytes): `GpuDipoleProfiles` (three
/// [`GpuDipole`]s and `r_max_all`), the material's `FresnelTransmission`, `ρ_c` and `P(c)`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuGatherProfile {
    pub dipoles: [GpuDipole; 3],
    pub r_max_all: f32,
    /// [`FresnelTransmission::eta`] and `::normalization`.
    pub fresnel: [f32; 2],
    pub reflectance: [f32; 3],
    pub channel: [f32; 3],
}

impl GpuGatherProfile {
    pub fn new(p: &GatherProfile) -> GpuGatherProfile {
        let FresnelTransmission { eta, normalization } = p.fresnel;
        GpuGatherProfile {
            dipoles: p.dipoles.channels.map(|d| GpuDipole::new(&d)),
            r_max_all: p.dipoles.r_max_all,
            fresnel: [eta, normalization],
            reflectance: p.reflectance,
            channel: p.channel,
        }
    }
}

/// The gather profiles of `scene`'s materials as the CPU builds them ([`gather_profiles`]),
/// Lambert ones a zeroed placeholder.
pub fn scene_gather_profiles(
    scene: &Scene,
    settings: &ImageSpaceSettings,
) -> Vec<GpuGatherProfile> {
    gather_profiles(scene, settings)
        .iter()
        .map(|p| {
            p.as_ref()
                .map_or_else(GpuGatherProfile::default, GpuGatherProfile::new)
        })
        .collect()
}

/// One frame of the image-space method read back: the image (`left_out` = non-finite pass
/// values and path-traced samples with more probe hits than kept), the gather's entry counts
/// summed over pixels and passes, and the dispatches whose loops the device cut short (non-zero:
/// the image is not to be trusted).
#[derive(Clone, Debug, PartialEq)]
pub struct ImageSpaceImage {
    pub image: DeviceImage,
    pub entries: EntryCounts,
    pub cut: u64,
}

impl LoopsCut for ImageSpaceImage {
    fn loops_cut(&self) -> u64 {
        self.cut
    }
}

/// The `image-space:spp` method on one frame (the kernel of [`IMAGE_SPACE`]) with the sample
/// counts of `settings` and the gather profiles `profiles` (one per material of the scene, e.g.
/// [`scene_gather_profiles`] of the same settings): `2 spp` dispatches.
pub fn render_image_space(
    context: &mut Context,
    kernel: &Kernel,
    frame: &FrameInput,
    profiles: &[GpuGatherProfile],
    settings: &ImageSpaceSettings,
    spp: u32,
) -> Result<ImageSpaceImage, VulkanError> {
    let count = frame.width * frame.height;
    // Vulkan buffers cannot be empty; a scene without materials has no pixel that reads one.
    let profiles = if profiles.is_empty() {
        Buffer::from_slice(context, &[GpuGatherProfile::default()])?
    } else {
        Buffer::from_slice(context, profiles)?
    };
    let output = Buffer::zeroed(context, count as usize * 16)?;
    let irradiance = Buffer::zeroed(context, count as usize * 16)?;
    let state = Buffer::zeroed(context, count as usize * size_of::<ImageSpaceState>())?;
    let buffers = frame.bindings(&[&output, &irradiance, &profiles, &state])?;
    for pass in 0..spp {
        for stage in [ImageSpaceStage::Irradiance, ImageSpaceStage::Gather] {
            let params = ImageSpaceParams {
                spp,
                pass,
                stage: stage.code(),
                irradiance_samples: settings.irradiance_samples,
                importance_samples: settings.importance_samples,
                uniform_samples: settings.uniform_samples,
                pad: [0; 2],
            };
            context.dispatch(
                kernel,
                &buffers,
                bytemuck::bytes_of(&params),
                [groups_for(count, IMAGE_SPACE.local_size), 1, 1],
            )?;
        }
    }
    let states = state.read::<ImageSpaceState>()?;
    let mut entries = EntryCounts::default();
    for s in &states {
        entries.samples += u64::from(s.samples);
        entries.off_screen += u64::from(s.off_screen);
        entries.occluded += u64::from(s.occluded);
        entries.outside += u64::from(s.outside);
        entries.edge_on += u64::from(s.edge_on);
    }
    Ok(ImageSpaceImage {
        image: frame.read_image(&output)?,
        entries,
        cut: states.iter().map(|s| u64::from(s.cut)).sum(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use sss::material::Material;
    use std::mem::offset_of;

    #[test]
    fn buffer_structs_match_std430() {
        assert_eq!((size_of::<GpuDipole>(), align_of::<GpuDipole>()), (24, 4));
        assert_eq!(offset_of!(GpuDipole, rho), 20);
        assert_eq!(
            (
                size_of::<GpuGatherProfile>(),
                align_of::<GpuGatherProfile>()
            ),
            (108, 4)
        );
        assert_eq!(offset_of!(GpuGatherProfile, r_max_all), 72);
        assert_eq!(offset_of!(GpuGatherProfile, fresnel), 76);
        assert_eq!(offset_of!(GpuGatherProfile, reflectance), 84);
        assert_eq!(offset_of!(GpuGatherProfile, channel), 96);
        assert_eq!(size_of::<ImageSpaceParams>(), 32);
        assert_eq!(size_of::<ImageSpaceState>(), 56);
    }

    /// `bumpy`'s translucent material maps to the CPU's gather profile bit for bit; its Lambert
    /// ones are zeroed placeholders.
    #[test]
    fn scene_profiles_are_the_cpu_profiles() {
        let scene = Scene::builtin("bumpy").expect("built-in");
        let settings = ImageSpaceSettings::default();
        let gpu = scene_gather_profiles(&scene, &settings);
        assert_eq!(gpu.len(), scene.materials.len());
        let mut translucent = 0;
        for (m, g) in scene.materials.iter().zip(&gpu) {
            match m {
                Material::Translucent(t) => {
                    translucent += 1;
                    let cpu = GatherProfile::new(t, settings.channel);
                    assert_eq!(g.channel, cpu.channel);
                    assert_eq!(g.r_max_all, cpu.dipoles.r_max_all);
                    for (gd, cd) in g.dipoles.iter().zip(&cpu.dipoles.channels) {
                        assert_eq!(gd.rho, cd.total_reflectance());
                        assert_eq!(gd.z_v, cd.depth(Pole::Virtual));
                    }
                    assert!(g.reflectance.iter().all(|&r| r > 0.0));
                }
                Material::Lambert(_) => assert_eq!(*g, GpuGatherProfile::default()),
            }
        }
        assert!(translucent > 0);
    }
}
