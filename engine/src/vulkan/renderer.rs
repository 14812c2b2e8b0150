//! The front of the Vulkan backend (DESIGN §6): a [`Renderer`] holds the [`Context`], the
//! compiled kernels and the uploaded [`GpuScene`] across runs (creating a pipeline on lavapipe
//! compiles LLVM code, so it is done once per shader) and runs on them a preset's frames
//! (`VulkanStream`) and the spatiotemporal denoiser. A method with a kernel of its own (the
//! `methods` crate: the path tracer, random walk, ...) drives it through [`Renderer::gbuffer`]
//! and [`Renderer::parts`].

use std::collections::HashMap;
use std::collections::hash_map::Entry;

use sss::scene::Scene;

use super::device::Context;
use super::error::VulkanError;
use super::frame::Parts;
use super::memory::Buffer;
use super::scene::{GBUFFER, GpuScene};
use super::shaders::Shader;
use super::svgf::{SVGF, svgf_filter};
use super::{Kernel, groups_for};
use crate::contract::{FrameParams, GpuPixel, PassParams};
use crate::denoise::Guide;
use crate::denoise::svgf::Params as SvgfSettings;
use crate::hash::Fnv1a;
use crate::image::Image;
use crate::stream::{Keep, Stream};
use crate::{PipelineError, Run, RunConfig};
use shifts::preset::Preset;

/// A Vulkan device with its kernels and the last uploaded scene, reused across runs.
pub struct Renderer {
    context: Context,
    kernels: HashMap<&'static str, Kernel>,
    /// The uploaded scene and the fingerprint of the [`Scene`] it came from.
    scene: Option<(u64, GpuScene)>,
    /// How many scenes it has uploaded.
    uploads: u64,
}

impl Renderer {
    /// A renderer on `context`; kernels are built on first use.
    pub fn new(context: Context) -> Renderer {
        Renderer {
            context,
            kernels: HashMap::new(),
            scene: None,
            uploads: 0,
        }
    }

    /// The device the renderer runs on.
    pub fn context(&self) -> &Context {
        &self.context
    }

    /// Builds (once) the kernels of `shaders`.
    pub fn prepare(&mut self, shaders: &[Shader]) -> Result<(), VulkanError> {
        for &shader in shaders {
            if let Entry::Vacant(slot) = self.kernels.entry(shader.name) {
                slot.insert(Kernel::for_shader(&self.context, shader)?);
            }
        }
        Ok(())
    }

    /// Uploads `scene` unless the cached upload came from an identical scene (cameras aside:
    /// the camera travels in [`FrameParams`]).
    pub fn upload(&mut self, scene: &Scene) -> Result<(), VulkanError> {
        let key = fingerprint(scene);
        if self.scene.as_ref().is_none_or(|(k, _)| *k != key) {
            self.scene = None;
            self.scene = Some((key, GpuScene::upload(&self.context, scene)?));
            self.uploads += 1;
        }
        Ok(())
    }

    /// How many scenes it has uploaded: a count that changes when the uploaded scene does.
    pub fn uploads(&self) -> u64 {
        self.uploads
    }

    /// The uploaded scene (after [`Renderer::upload`]).
    pub fn gpu_scene(&self) -> Result<&GpuScene, VulkanError> {
        self.scene
            .as_ref()
            .map(|(_, s)| s)
            .ok_or_else(|| VulkanError::Binding("no scene was uploaded".into()))
    }

    /// The context, the kernel of `shader` (built on first use) and the uploaded scene, borrowed
    /// together: what a method's host code needs to dispatch its kernel on a frame.
    pub fn parts(
        &mut self,
        shader: Shader,
    ) -> Result<(&mut Context, &Kernel, &GpuScene), VulkanError> {
        self.prepare(&[shader])?;
        let scene = self
            .scene
            .as_ref()
            .map(|(_, s)| s)
            .ok_or_else(|| VulkanError::Binding("no scene was uploaded".into()))?;
        Ok((&mut self.context, &self.kernels[shader.name], scene))
    }

    /// The G-buffer of `frame` of `scene`'s trajectory on the device (uploading the scene if
    /// needed), with the frame's parameter buffer: the input of the memoryless methods.
    pub fn gbuffer(
        &mut self,
        scene: &Scene,
        frame: u32,
        seed: u64,
    ) -> Result<(Buffer, Buffer), VulkanError> {
        self.upload(scene)?;
        let n = pixel_count(scene);
        let params = FrameParams::new(scene, frame, frame.checked_sub(1), seed);
        let params = Buffer::from_slice(&self.context, &[params])?;
        let gpixels = Buffer::zeroed(&self.context, n * size_of::<GpuPixel>())?;
        let (context, kernel, gpu) = self.parts(GBUFFER)?;
        let mut buffers: Vec<&Buffer> = gpu.buffers().to_vec();
        buffers.extend([&params, &gpixels]);
        let push = PassParams::new(0, None, false);
        context.dispatch(
            kernel,
            &buffers,
            bytemuck::bytes_of(&push),
            [groups_for(n as u32, GBUFFER.local_size), 1, 1],
        )?;
        Ok((gpixels, params))
    }

    /// The spatiotemporal variance-guided filter's twin over `frames` with their `guides`
    /// (validated by `crate::denoise::denoise`): the filtered last frame.
    pub fn svgf(
        &mut self,
        guides: &[Guide],
        frames: &[Image],
        params: &SvgfSettings,
    ) -> Result<Image, VulkanError> {
        self.prepare(&[SVGF])?;
        svgf_filter(
            &mut self.context,
            &self.kernels[SVGF.name],
            guides,
            frames,
            params,
        )
    }

    /// What a frame of a stream borrows: the device, the uploaded scene and the kernels.
    pub(super) fn frame_parts(&self) -> Result<Parts<'_>, VulkanError> {
        Ok(Parts {
            context: &self.context,
            scene: self.gpu_scene()?,
            kernels: &self.kernels,
        })
    }

    /// Renders `config.frames` frames of `scene` with `preset` on the device: the GPU twin of
    /// [`crate::run`], a loop over a stream on this renderer (`VulkanStream::new` says which
    /// presets have kernels). `Run::timings` are GPU seconds from the timestamps; they are
    /// empty on a queue that writes no timestamps.
    pub fn run(
        &mut self,
        scene: &Scene,
        preset: &Preset,
        config: &RunConfig,
    ) -> Result<Run, PipelineError> {
        Stream::on_renderer(self, scene, preset, config)?.run(config.frames, Keep::Every)
    }
}

fn pixel_count(scene: &Scene) -> usize {
    scene.camera.width() as usize * scene.camera.height() as usize
}

/// FNV-1a over what [`GpuScene`] is built from: materials, objects, lights, every triangle's
/// vertices, shading normals and object. Two scenes with the same fingerprint upload the same
/// buffers.
fn fingerprint(scene: &Scene) -> u64 {
    let mut hash = Fnv1a::new();
    hash.write(format!("{:?}{:?}{:?}", scene.materials, scene.objects, scene.lights).as_bytes());
    let geometry = &scene.geometry;
    for prim in 0..geometry.triangle_count() {
        for v in geometry.vertices(prim) {
            hash.write(bytemuck::bytes_of(&v.to_array()));
        }
        for bary in [[0.0f32, 0.0], [1.0, 0.0], [0.0, 1.0]] {
            let n = geometry.shading_normal(prim, glam::Vec2::from_array(bary));
            hash.write(bytemuck::bytes_of(&n.to_array()));
        }
        hash.write(&geometry.object_of(prim).to_le_bytes());
    }
    hash.finish()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vulkan::VulkanStream;
    use crate::vulkan::testing::validated_or_skip;
    use crate::vulkan::validation::Checks;

    /// The negative control of synchronization validation: a frame recorded without the
    /// barrier before one of its passes (one that clears nothing, whose fills would order the
    /// access anyway) is a hazard the layer reports and the run returns; the same frame with
    /// every barrier runs clean.
    #[test]
    fn a_missing_barrier_is_caught() {
        let Some(mut renderer) = validated_or_skip("a_missing_barrier_is_caught", Checks::Sync)
        else {
            return;
        };
        let mut scene = Scene::builtin("bumpy").expect("built-in scene");
        scene.camera = scene.camera.with_resolution(8, 8);
        let preset = Preset::named("reconnection").expect("registered preset");
        let config = RunConfig {
            seed: 1,
            frames: 1,
            collect_diagnostics: false,
        };
        let mut run = |omit: bool| {
            let mut stream = VulkanStream::new(&mut renderer, &scene, &preset, &config)?;
            if omit {
                let run = stream.run_mut();
                let step = (0..run.plan.steps.len())
                    .position(|i| run.waits[i] && run.plan.steps[i].clears.is_empty())
                    .expect("a plan step behind a barrier of its own");
                run.waits[step] = false;
            }
            stream.frame()
        };
        run(false).expect("every barrier: no validation error");
        match run(true) {
            Err(PipelineError::Vulkan(VulkanError::Validation(message))) => {
                assert!(message.contains("SYNC-HAZARD"), "{message}")
            }
            other => panic!("a missing barrier was not caught: {:?}", other.map(|_| ())),
        }
    }
}
