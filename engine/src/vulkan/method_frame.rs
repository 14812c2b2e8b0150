//! The host-side sequence every method with a kernel of its own runs per frame: the frame's
//! G-buffer on the device, the kernel (built on first use) with the uploaded scene and the
//! frame's bindings, the method's dispatches, then the check that the device ran every loop.

use sss::scene::Scene;

use super::compute::Kernel;
use super::device::Context;
use super::error::VulkanError;
use super::frame_input::FrameInput;
use super::memory::Buffer;
use super::renderer::Renderer;
use super::shaders::Shader;

/// What a method's kernel counts besides its result: the pixels or samples whose loops the
/// device cut short (lavapipe's per-group loop budget, `restir/glsl/loop_budget.glsl`).
pub trait LoopsCut {
    fn loops_cut(&self) -> u64;
}

impl Renderer {
    /// One frame of a method's own kernel `shader` on `scene`: the G-buffer of `frame` (seed
    /// `seed`) on the device, then `render` with the device, the kernel and the frame's
    /// bindings. A result whose loops the device cut short is [`VulkanError::LoopsCut`] naming
    /// `shader`. Returns the result and the frame's G-buffer, which a method with history
    /// across frames keeps.
    pub fn method_frame<T: LoopsCut, E: From<VulkanError>>(
        &mut self,
        scene: &Scene,
        frame: u32,
        seed: u64,
        shader: Shader,
        render: impl FnOnce(&mut Context, &Kernel, &FrameInput) -> Result<T, E>,
    ) -> Result<(T, Buffer), E> {
        let (gbuffer, params) = self.gbuffer(scene, frame, seed)?;
        let out = {
            let (context, kernel, gpu) = self.parts(shader)?;
            render(
                context,
                kernel,
                &FrameInput::new(scene, gpu, &params, &gbuffer),
            )?
        };
        match out.loops_cut() {
            0 => Ok((out, gbuffer)),
            count => Err(VulkanError::LoopsCut {
                shader: shader.name,
                count,
            }
            .into()),
        }
    }
}
