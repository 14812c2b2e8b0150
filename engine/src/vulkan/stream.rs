//! A preset's stream on a Vulkan device: a [`FrameRun`] on its renderer, which the stream holds
//! (locked, on a shared backend) for as long as it lives.

use std::borrow::Cow;
use std::ops::DerefMut;
use std::sync::{Arc, Mutex};

use sss::scene::{Pose, Scene};

use super::frame::FrameRun;
use super::renderer::Renderer;
use super::shaders::Shader;
use crate::plan::Plan;
use crate::stream::frame::{Finished, Frame};
use crate::{PassSpec, PipelineError, Preset, RadiusRule, RunConfig};
use shifts::preset::{Duplication, Pairs};

/// The device side of an `engine::Stream`.
pub struct VulkanStream<'a> {
    renderer: Held<'a>,
    /// The scene, owned once a frame moves its camera ([`VulkanStream::move_camera`]).
    scene: Cow<'a, Scene>,
    /// The renderer's upload ([`Renderer::uploads`]) the frames' commands bind.
    upload: u64,
    run: FrameRun,
}

/// How a stream holds its renderer.
enum Held<'a> {
    /// Locked (or borrowed) for the stream's life.
    Locked(Box<dyn DerefMut<Target = Renderer> + 'a>),
    /// Shared with other users of the backend (a viewer presents and renders its reference
    /// through it between frames), locked frame by frame.
    Shared(Arc<Mutex<Renderer>>),
}

fn lock(renderer: &Mutex<Renderer>) -> std::sync::MutexGuard<'_, Renderer> {
    renderer.lock().unwrap_or_else(|e| e.into_inner())
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
        let (upload, run) = Self::prepare(&mut renderer, scene, preset, config)?;
        Ok(VulkanStream {
            renderer: Held::Locked(Box::new(renderer)),
            scene: Cow::Borrowed(scene),
            upload,
            run,
        })
    }

    /// [`VulkanStream::new`] on a shared renderer, locked only while a frame renders, with a
    /// scene of its own. Its frames fail (one line) if the renderer uploads another scene in
    /// between, since their recorded commands bind the uploaded one.
    pub fn shared(
        renderer: Arc<Mutex<Renderer>>,
        scene: Scene,
        preset: &Preset,
        config: &RunConfig,
    ) -> Result<VulkanStream<'static>, PipelineError> {
        let (upload, run) = Self::prepare(&mut lock(&renderer), &scene, preset, config)?;
        Ok(VulkanStream {
            renderer: Held::Shared(renderer),
            scene: Cow::Owned(scene),
            upload,
            run,
        })
    }

    fn prepare(
        renderer: &mut Renderer,
        scene: &Scene,
        preset: &Preset,
        config: &RunConfig,
    ) -> Result<(u64, FrameRun), PipelineError> {
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
        if preset.duplication != Duplication::Ignored {
            return Err(PipelineError::Config(format!(
                "preset `{}`: duplication={} has no Vulkan kernel; use the CPU backend",
                preset.name,
                preset.duplication.name()
            )));
        }
        let plan = Plan::lower(preset);
        let shaders: Vec<Shader> = plan.steps.iter().map(|s| Shader::of(s.kernel)).collect();
        renderer.prepare(&shaders)?;
        renderer.upload(scene)?;
        let run = FrameRun::new(renderer.context(), scene, plan, config)?;
        Ok((renderer.uploads(), run))
    }

    /// The labels of the plan's steps, in execution order.
    pub fn labels(&self) -> Vec<String> {
        self.run.labels()
    }

    /// Renders and reads back the next frame.
    pub fn frame(&mut self) -> Result<Frame, PipelineError> {
        let shared;
        let renderer: &Renderer = match &self.renderer {
            Held::Locked(renderer) => renderer,
            Held::Shared(renderer) => {
                shared = lock(renderer);
                &shared
            }
        };
        if renderer.uploads() != self.upload {
            return Err(PipelineError::Config(
                "the renderer uploaded another scene during the stream; start a new stream".into(),
            ));
        }
        let parts = renderer.frame_parts()?;
        self.run.frame(&parts, &self.scene)
    }

    /// Moves the camera to `pose` from the next frame on ([`sss::scene::Camera::moved_to`]).
    pub fn move_camera(&mut self, pose: Pose) {
        let camera = &mut self.scene.to_mut().camera;
        *camera = camera.moved_to(self.run.next(), pose);
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
