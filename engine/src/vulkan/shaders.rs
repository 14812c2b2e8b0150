//! The compute shaders: the engine's, compiled by `build.rs` (one per `engine/glsl/*.glsl`) and
//! embedded as SPIR-V when `glslc` was found at build time, and those another crate compiles
//! and hands over with [`Shader::compiled`] (a method's kernel, `methods/build.rs`). A shader is
//! named by its file stem; the module that dispatches it declares its binding interface as a
//! [`Shader`] constant next to the code that fills the buffers.

use super::error::VulkanError;
use crate::plan::{PassKernel, SCENE_BINDINGS};

/// A compute shader and its binding interface: storage buffers at bindings `0..buffers`,
/// `push_bytes` of push constants, `local_size` invocations per group. Kernels are built and
/// cached by name ([`Renderer::prepare`](super::Renderer::prepare)), so names are unique.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Shader {
    /// The GLSL file stem.
    pub name: &'static str,
    pub buffers: u32,
    pub push_bytes: u32,
    /// `local_size_x` in the GLSL.
    pub local_size: u32,
    pub code: Code,
}

/// Where a [`Shader`]'s SPIR-V comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Code {
    /// `engine/glsl/<name>.glsl`, compiled by the engine's build script.
    Engine,
    /// Compiled by another crate's build script; `None` when it was built without `glslc`.
    Compiled(Option<&'static [u8]>),
}

impl Shader {
    /// `parity_rng.glsl`: keys (`StreamKey`) → `draws` u32 and `draws` f32 per key.
    /// Push constants: [`RngParams`](super::RngParams).
    pub const PARITY_RNG: Shader = Shader::new("parity_rng", 3, 16);
    /// `parity_pairing.glsl`: queries ([`PairingQuery`](super::PairingQuery)) and pixels
    /// (`[i32; 2]`) → the partner of each pixel per query. Push constants:
    /// [`RngParams`](super::RngParams).
    pub const PARITY_PAIRING: Shader = Shader::new("parity_pairing", 3, 16);
    /// `parity_burley.glsl`: [`BurleyInput`](super::BurleyInput) →
    /// [`BurleyOutput`](super::BurleyOutput). Push constants: the count (`u32`).
    pub const PARITY_BURLEY: Shader = Shader::new("parity_burley", 2, 4);
    /// `parity_bvh.glsl`: [`BvhRayInput`](super::BvhRayInput) →
    /// [`BvhRayOutput`](super::BvhRayOutput), then the four buffers of a
    /// [`GpuBvh`](super::GpuBvh). Push constants: ray count and node count (`[u32; 2]`).
    pub const PARITY_BVH: Shader = Shader::new("parity_bvh", 6, 8);

    /// The shader of a pass kernel: the scene's buffers and the kernel's, [`PassParams`]
    /// push constants.
    ///
    /// [`PassParams`]: crate::contract::PassParams
    pub const fn of(kernel: PassKernel) -> Shader {
        Shader::new(
            kernel.name(),
            SCENE_BINDINGS + kernel.buffers().len() as u32,
            size_of::<crate::contract::PassParams>() as u32,
        )
    }

    /// A shader of `engine/glsl/` with 64 invocations per group.
    pub const fn new(name: &'static str, buffers: u32, push_bytes: u32) -> Shader {
        Shader {
            name,
            buffers,
            push_bytes,
            local_size: 64,
            code: Code::Engine,
        }
    }

    /// A shader with 64 invocations per group whose SPIR-V another crate compiled (`None`: it
    /// was built without `glslc`): how a method brings its own kernel.
    pub const fn compiled(
        name: &'static str,
        spirv: Option<&'static [u8]>,
        buffers: u32,
        push_bytes: u32,
    ) -> Shader {
        Shader {
            code: Code::Compiled(spirv),
            ..Shader::new(name, buffers, push_bytes)
        }
    }

    /// The SPIR-V, or [`VulkanError::NoGlslc`] when its crate was built without `glslc`.
    pub fn spirv(self) -> Result<&'static [u8], VulkanError> {
        match self.code {
            Code::Engine => embedded(self.name),
            Code::Compiled(spirv) => spirv.ok_or(VulkanError::NoGlslc),
        }
    }
}

#[cfg(reshift_glslc)]
mod table {
    include!(concat!(env!("OUT_DIR"), "/spirv_table.rs"));
}

#[cfg(reshift_glslc)]
fn embedded(name: &str) -> Result<&'static [u8], VulkanError> {
    table::embedded_named(name).ok_or_else(|| VulkanError::UnknownShader(name.to_string()))
}

#[cfg(not(reshift_glslc))]
fn embedded(_: &str) -> Result<&'static [u8], VulkanError> {
    Err(VulkanError::NoGlslc)
}
