//! The compute shaders compiled by `build.rs` (one per `experiments/glsl/*.glsl`), embedded as
//! SPIR-V when `glslc` was found at build time.

use super::error::VulkanError;

/// A compute shader of `experiments/glsl/`, with its binding interface.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Shader {
    /// `parity_rng.glsl`: keys (`StreamKey`) → `draws` u32 and `draws` f32 per key.
    /// Push constants: [`RngParams`](super::RngParams).
    ParityRng,
    /// `parity_burley.glsl`: [`BurleyInput`](super::BurleyInput) →
    /// [`BurleyOutput`](super::BurleyOutput). Push constants: the count (`u32`).
    ParityBurley,
    /// `parity_bvh.glsl`: [`BvhRayInput`](super::BvhRayInput) →
    /// [`BvhRayOutput`](super::BvhRayOutput), then the four buffers of a
    /// [`GpuBvh`](super::GpuBvh). Push constants: ray count and node count (`[u32; 2]`).
    ParityBvh,
}

impl Shader {
    /// Every shader, in a fixed order.
    pub const ALL: [Shader; 3] = [Shader::ParityRng, Shader::ParityBurley, Shader::ParityBvh];

    /// The GLSL file stem.
    pub fn name(self) -> &'static str {
        match self {
            Shader::ParityRng => "parity_rng",
            Shader::ParityBurley => "parity_burley",
            Shader::ParityBvh => "parity_bvh",
        }
    }

    /// Storage buffers at bindings `0..buffers()`.
    pub fn buffers(self) -> u32 {
        match self {
            Shader::ParityRng => 3,
            Shader::ParityBurley => 2,
            Shader::ParityBvh => 6,
        }
    }

    /// Push-constant bytes.
    pub fn push_bytes(self) -> u32 {
        match self {
            Shader::ParityRng => 16,
            Shader::ParityBurley => 4,
            Shader::ParityBvh => 8,
        }
    }

    /// Invocations per work group (`local_size_x` in the GLSL).
    pub fn local_size(self) -> u32 {
        64
    }

    /// The SPIR-V, or [`VulkanError::NoGlslc`] when the crate was built without `glslc`.
    pub fn spirv(self) -> Result<&'static [u8], VulkanError> {
        embedded(self)
    }
}

#[cfg(reshift_glslc)]
fn embedded(shader: Shader) -> Result<&'static [u8], VulkanError> {
    Ok(match shader {
        Shader::ParityRng => include_bytes!(concat!(env!("OUT_DIR"), "/parity_rng.spv")),
        Shader::ParityBurley => include_bytes!(concat!(env!("OUT_DIR"), "/parity_burley.spv")),
        Shader::ParityBvh => include_bytes!(concat!(env!("OUT_DIR"), "/parity_bvh.spv")),
    })
}

#[cfg(not(reshift_glslc))]
fn embedded(_: Shader) -> Result<&'static [u8], VulkanError> {
    Err(VulkanError::NoGlslc)
}
