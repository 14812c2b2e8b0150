//! A preset's stream on a Vulkan device: a [`FrameRun`] on its renderer, which the stream holds
//! (locked, on a shared backend) for as long as it lives.

use std::ops::DerefMut;

use sss::scene::Scene;

use super::frame::FrameRun;
use super::renderer::Renderer;
use super::shaders::Shader;
use crate::plan::Plan;
use crate::stream::frame::{Finished, Frame};
use crate::{PassSpec, PipelineError, Preset, RadiusRule, RunConfig};
use shifts::preset::Pairs;

/// The device side of an `engine::Stream`.
pub struct VulkanStream<'a> {
    renderer: Box<dyn DerefMut<Target = Renderer> + 'a>,
    scene: &'a Scene,
    run: FrameRun,
}

impl<'a> VulkanStream<'a> {
    /// The stream of `preset` (validated by the caller) on `scene`: its kernels built, the
    /// scene uploaded and the frame buffers allocated. The target must have a kernel
    /// ([`shifts::Target::has_kernel`]) and the spatial kernel clamps its radius
    /// ([`RadiusRule::Clamped`]) with independent neighbours (reciprocal pairs,
    /// `crate::reciprocal`, have no kernel yet): any other choice is a one-line configuration
    /// error.
    pub fn new(
        mut renderer: impl DerefMut<Target = Renderer> + 'a,
        scene: &'a Scene,
        preset: &Preset,
        config: &RunConfig,
    ) -> Result<VulkanStream<'a>, PipelineError> {
        if !preset.target.has_kernel() {
            return Err(PipelineError::Config(format!(
                "preset `{}`: target {} has no Vulkan kernel (luminance, red, green and blue have); use the CPU backend",
                preset.name,
                preset.target.name()
            )));
        }
        if let Some(pass) = preset.passes.iter().find(
            |p| matches!(p, PassSpec::Spatial { radius, .. } if *radius != RadiusRule::Clamped),
        ) {
            return Err(PipelineError::Config(format!(
                "preset `{}`: {} with a non-clamped radius has no Vulkan kernel; use the CPU backend",
                preset.name,
                pass.label()
            )));
        }
        if let Some(pass) = preset
            .passes
            .iter()
            .find(|p| matches!(p, PassSpec::Spatial { pairs, .. } if *pairs != Pairs::Independent))
        {
            return Err(PipelineError::Config(format!(
                "preset `{}`: {} (reciprocal pairs) has no Vulkan kernel; use the CPU backend",
                preset.name,
                pass.label()
            )));
        }
        let plan = Plan::lower(preset);
        let shaders: Vec<Shader> = plan.steps.iter().map(|s| Shader::of(s.kernel)).collect();
        renderer.prepare(&shaders)?;
        renderer.upload(scene)?;
        let run = FrameRun::new(renderer.context(), scene, plan, config)?;
        Ok(VulkanStream {
            renderer: Box::new(renderer),
            scene,
            run,
        })
    }

    /// The labels of the plan's steps, in execution order.
    pub fn labels(&self) -> Vec<String> {
        self.run.labels()
    }

    /// Renders and reads back the next frame.
    pub fn frame(&mut self) -> Result<Frame, PipelineError> {
        let parts = self.renderer.frame_parts()?;
        self.run.frame(&parts, self.scene)
    }

    /// The last frame's final reservoirs and the diagnostics.
    pub fn finish(mut self) -> Result<Finished, PipelineError> {
        Ok(self.run.finish()?)
    }

    /// Its frame run, for a test that leaves out a barrier.
    #[cfg(test)]
    pub(super) fn run_mut(&mut self) -> &mut FrameRun {
        &mut self.run
    }
}
