//! The Vulkan backend (DESIGN §6), loaded at run time with `ash`: device choice ([`Context`]),
//! device-local storage buffers with staging ([`Buffer`]), compute kernels ([`Kernel`]), timed
//! dispatches, the scene on the device ([`GpuScene`], [`GpuBvh`]), the frame pipeline with
//! persistent command buffers and per-pass timestamps ([`Renderer`]), and the embedded SPIR-V
//! of `engine/glsl/` or of another crate's kernels ([`Shader`]). A method brings its own kernel as a
//! [`Shader::compiled`] constant and drives it through [`Renderer::gbuffer`], [`Renderer::parts`],
//! [`FrameInput::bindings`], [`Context::dispatch`] and [`FrameInput::read_image`]
//! (`methods/src/image_space/vulkan.rs`).
//!
//! A machine without libvulkan, without a driver, or a build without `glslc` gets a
//! [`VulkanError`] that says in one line what to install; nothing here panics for that.
//! The buffer structs below are `#[repr(C)]` + `bytemuck` twins of std430 structs of the GLSL.

mod bvh;
mod compute;
mod decode;
mod device;
mod error;
mod frame;
mod frame_input;
mod memory;
mod method_frame;
mod pass_params;
mod renderer;
mod scene;
mod shade;
mod shaders;
mod stream;
mod svgf;
pub mod testing;
mod timing;
mod validation;

use bytemuck::{Pod, Zeroable};

pub use bvh::{BVH_MAX_HITS, BvhRayInput, BvhRayOutput, GpuBvh};
pub use compute::{Dispatch, Kernel, groups_for};
pub use decode::decode_error;
pub use device::{Context, DEVICE_ENV, DeviceDetails, DeviceInfo, DeviceKind, choose_device};
pub use error::VulkanError;
pub use frame::{CANDIDATES, SPATIAL, TEMPORAL};
pub use frame_input::{DeviceImage, FrameInput};
pub use memory::Buffer;
pub use method_frame::LoopsCut;
pub use renderer::Renderer;
pub use scene::{GBUFFER, GpuScene};
pub use shade::{SHADE, shade};
pub use svgf::{SVGF, svgf_filter};

pub use crate::contract::{
    FrameParams, GpuCamera, GpuLight, GpuMaterial, GpuPixel, GpuTriangle, MethodParams, PassParams,
};
pub use shaders::{Code, Shader};
pub use stream::VulkanStream;
pub use validation::{Checks, Message, Severity, VALIDATION_ENV};

/// The environment variable that turns "Vulkan unavailable, skipped" into a failure in tests.
pub const REQUIRE_ENV: &str = "RESHIFT_REQUIRE_VULKAN";

impl Kernel {
    /// The pipeline of one embedded shader.
    pub fn for_shader(context: &Context, shader: Shader) -> Result<Kernel, VulkanError> {
        Kernel::new(context, shader.spirv()?, shader.buffers, shader.push_bytes)
    }
}

/// `restir/glsl/rng.glsl`'s `StreamKey` (std430: four `uint`, 16 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct GpuStreamKey {
    pub pixel: u32,
    pub frame: u32,
    pub pass: u32,
    pub purpose: u32,
}

impl From<restir::rng::StreamKey> for GpuStreamKey {
    fn from(k: restir::rng::StreamKey) -> Self {
        GpuStreamKey {
            pixel: k.pixel,
            frame: k.frame,
            pass: k.pass,
            purpose: k.purpose,
        }
    }
}

/// Push constants of [`Shader::PARITY_RNG`] (key count, draws per key, run seed split in halves)
/// and [`Shader::PARITY_PAIRING`] (query count, pixels per query, run seed).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct RngParams {
    pub count: u32,
    pub draws: u32,
    pub seed_lo: u32,
    pub seed_hi: u32,
}

/// `parity_pairing.glsl`'s `PairingQuery` (std430: four 4-byte scalars, 16 bytes): the arguments
/// of [`Pairing::draw`](crate::reciprocal::Pairing::draw) but the run seed.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct PairingQuery {
    pub radius: f32,
    pub slot: u32,
    pub frame: u32,
    pub pass: u32,
}

/// `parity_burley.glsl`'s `BurleyInput` (std430: three `float`, 12 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct BurleyInput {
    pub d: f32,
    pub r: f32,
    pub u: f32,
}

/// `parity_burley.glsl`'s `BurleyOutput` (std430: five `float`, 20 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct BurleyOutput {
    pub pdf_radius: f32,
    pub pdf_disk: f32,
    pub cdf: f32,
    /// The textbook `1 − ¼e^{−r/d} − ¾e^{−r/3d}`: the negative control of the parity test.
    pub cdf_naive: f32,
    pub sample_radius: f32,
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::mem::offset_of;

    /// std430: scalars align to 4, a struct of scalars to 4, arrays of it stride by its size.
    #[test]
    fn buffer_structs_match_std430() {
        assert_eq!(
            (size_of::<GpuStreamKey>(), align_of::<GpuStreamKey>()),
            (16, 4)
        );
        assert_eq!(offset_of!(GpuStreamKey, purpose), 12);
        assert_eq!(size_of::<RngParams>() as u32, Shader::PARITY_RNG.push_bytes);
        assert_eq!(offset_of!(RngParams, seed_hi), 12);
        assert_eq!(
            size_of::<RngParams>() as u32,
            Shader::PARITY_PAIRING.push_bytes
        );
        assert_eq!(
            (size_of::<PairingQuery>(), align_of::<PairingQuery>()),
            (16, 4)
        );
        assert_eq!(offset_of!(PairingQuery, pass), 12);
        assert_eq!(
            (size_of::<BurleyInput>(), align_of::<BurleyInput>()),
            (12, 4)
        );
        assert_eq!(offset_of!(BurleyInput, u), 8);
        assert_eq!(
            (size_of::<BurleyOutput>(), align_of::<BurleyOutput>()),
            (20, 4)
        );
        assert_eq!(offset_of!(BurleyOutput, sample_radius), 16);
    }

    #[test]
    fn every_shader_is_embedded_or_explains_why_not() {
        for shader in [
            Shader::PARITY_RNG,
            Shader::PARITY_BURLEY,
            Shader::PARITY_BVH,
        ] {
            match shader.spirv() {
                // SPIR-V magic number, little endian.
                Ok(words) => assert_eq!(&words[..4], &[0x03, 0x02, 0x23, 0x07], "{shader:?}"),
                Err(e) => assert_eq!(e, VulkanError::NoGlslc),
            }
        }
        let line = VulkanError::NoGlslc.to_string();
        assert!(line.contains("apt-get install glslc") && !line.contains('\n'));
    }
}
