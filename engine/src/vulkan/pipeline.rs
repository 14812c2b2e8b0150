//! The ReSTIR frame pipeline on the GPU (DESIGN §6): the twin of `cpu::run`.
//!
//! A [`Renderer`] holds the [`Context`], the compiled kernels and the uploaded [`GpuScene`]
//! across runs (creating a pipeline on lavapipe compiles LLVM code: it is done once per shader).
//! A run allocates its buffers once and records each distinct frame — G-buffer, the preset's
//! passes, shade, then read-back copies — into a command buffer once; frames are re-submitted.
//! Frames differ only in which buffers play "current" and "previous" (the G-buffer alternates,
//! the final reservoir buffer rotates among three), so a run records at most six command
//! buffers. `FrameParams` is copied from a staging buffer at the start of every frame, and a
//! timestamp pair around each pass gives [`Run::timings`] in GPU seconds.

use std::collections::HashMap;
use std::collections::hash_map::Entry;

use ash::vk;
use restir::resample::ResampleError;
use restir::reservoir::InvalidCandidate;
use sss::scene::Scene;

use super::compute::bind_buffers;
use super::device::Context;
use super::error::{VulkanError, api};
use super::memory::{Allocation, Buffer, Placement, barrier};
use super::random_walk::{RANDOM_WALK, render_random_walk, scene_media};
use super::scene::{GBUFFER, GpuScene};
use super::shaders::Shader;
use super::timing::Timestamps;
use super::{FrameInput, Kernel, PT, groups_for, render_pt};
use crate::candidates::ProbeCounts;
use crate::contract::{
    FrameParams, GpuPixel, HIT_OVERFLOW, KEPT_HITS, LOOP_BUDGET_CUT, PassParams,
};
use crate::diagnostics::{Counters, HybridChoice};
use crate::image::Image;
use crate::plan::PassKernel;
use crate::reuse::ShiftCounts;
use crate::{PassTiming, PipelineError, Run, RunConfig};
use shifts::PixelReservoir;
use shifts::preset::{PassSpec, Preset};

use crate::plan::{Plan, Resource, Rotation, Step};

/// `pass_candidates.glsl` ([`PassKernel::Candidates`]).
pub const CANDIDATES: Shader = Shader::of(PassKernel::Candidates);
/// `pass_temporal.glsl` ([`PassKernel::Temporal`]).
pub const TEMPORAL: Shader = Shader::of(PassKernel::Temporal);
/// `pass_spatial.glsl` ([`PassKernel::Spatial`]).
pub const SPATIAL: Shader = Shader::of(PassKernel::Spatial);

impl PassParams {
    /// The push constants of pass `pass` of a preset (`spec = None`: G-buffer or shade).
    pub fn new(pass: u32, spec: Option<&PassSpec>, collect_diagnostics: bool) -> PassParams {
        let base = PassParams {
            pass,
            collect_diagnostics: collect_diagnostics as u32,
            ..PassParams::default()
        };
        match spec {
            None => base,
            Some(&PassSpec::Candidates {
                bssrdf_samples,
                shared_light,
            }) => PassParams {
                bssrdf_samples,
                shared_light: shared_light as u32,
                ..base
            },
            Some(&PassSpec::Temporal {
                shift,
                mis,
                confidence_cap,
            }) => PassParams {
                shift: shift.code(),
                mis: mis.code(),
                confidence_cap,
                ..base
            },
            Some(&PassSpec::Spatial {
                shift,
                mis,
                neighbours,
                confidence_cap,
            }) => PassParams {
                shift: shift.code(),
                mis: mis.code(),
                neighbours,
                confidence_cap: confidence_cap.unwrap_or(0.0),
                ..base
            },
        }
    }
}

/// Decodes a pass's per-pixel error code (diag `w`; 0 = none, [`LOOP_BUDGET_CUT`] and
/// [`HIT_OVERFLOW`] are handled before) with [`ResampleError::from_gpu`]. A code outside the
/// contract's `ResampleCode`s is reported as a `Weight(NaN)` of the pass.
pub fn decode_error(code: u32) -> ResampleError {
    ResampleError::from_gpu(code).unwrap_or(ResampleError::Candidate {
        source: ((code >> 8) & 0xff) as usize,
        error: InvalidCandidate::Weight(f32::NAN),
    })
}

/// A Vulkan device with its kernels and the last uploaded scene, reused across runs.
pub struct Renderer {
    context: Context,
    kernels: HashMap<&'static str, Kernel>,
    /// The uploaded scene and the fingerprint of the [`Scene`] it came from.
    scene: Option<(u64, GpuScene)>,
}

impl Renderer {
    /// A renderer on `context`; kernels are built on first use.
    pub fn new(context: Context) -> Renderer {
        Renderer {
            context,
            kernels: HashMap::new(),
            scene: None,
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
        }
        Ok(())
    }

    /// The uploaded scene (after [`Renderer::upload`]).
    pub fn gpu_scene(&self) -> Result<&GpuScene, VulkanError> {
        self.scene
            .as_ref()
            .map(|(_, s)| s)
            .ok_or_else(|| VulkanError::Binding("no scene was uploaded".into()))
    }

    /// The context, a built kernel and the uploaded scene, borrowed together.
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

    /// The `pt:spp` method at `frame`: the image and the samples left out of the means.
    pub fn pt(
        &mut self,
        scene: &Scene,
        frame: u32,
        seed: u64,
        spp: u32,
    ) -> Result<(Image, u64), VulkanError> {
        let (gbuffer, params) = self.gbuffer(scene, frame, seed)?;
        let (context, kernel, gpu) = self.parts(PT)?;
        let input = FrameInput {
            scene: gpu,
            params: &params,
            gbuffer: &gbuffer,
            width: scene.camera.width(),
            height: scene.camera.height(),
        };
        let out = render_pt(context, kernel, &input, spp)?;
        Ok((out.image, out.left_out))
    }

    /// The `random-walk:spp` method at `frame`: the image and the samples left out.
    pub fn random_walk(
        &mut self,
        scene: &Scene,
        frame: u32,
        seed: u64,
        spp: u32,
    ) -> Result<(Image, u64), PipelineError> {
        let media = scene_media(scene)?;
        let (gbuffer, params) = self.gbuffer(scene, frame, seed)?;
        let (context, kernel, gpu) = self.parts(RANDOM_WALK)?;
        let input = FrameInput {
            scene: gpu,
            params: &params,
            gbuffer: &gbuffer,
            width: scene.camera.width(),
            height: scene.camera.height(),
        };
        let out = render_random_walk(context, kernel, &input, &media, spp)?;
        if out.cut > 0 {
            return Err(PipelineError::Vulkan(VulkanError::LoopsCut {
                shader: RANDOM_WALK.name,
                count: out.cut,
            }));
        }
        Ok((out.image.image, out.image.left_out))
    }

    /// Renders `config.frames` frames of `scene` with `preset` (validated by the caller) on
    /// the device: the GPU twin of [`crate::run`]. `Run::timings` are GPU seconds from the
    /// timestamps; they are empty on a queue that writes no timestamps.
    pub fn run(
        &mut self,
        scene: &Scene,
        preset: &Preset,
        config: &RunConfig,
    ) -> Result<Run, PipelineError> {
        let plan = Plan::lower(preset);
        let shaders: Vec<Shader> = plan.steps.iter().map(|s| Shader::of(s.kernel)).collect();
        self.prepare(&shaders)?;
        self.upload(scene)?;
        let gpu = self.gpu_scene()?;
        FrameRun::new(&self.context, gpu, &self.kernels, scene, &plan, config)?.run(scene)
    }
}

fn pixel_count(scene: &Scene) -> usize {
    scene.camera.width() as usize * scene.camera.height() as usize
}

/// FNV-1a over what [`GpuScene`] is built from: materials, objects, lights, every triangle's
/// vertices, shading normals and object. Two scenes with the same fingerprint upload the same
/// buffers.
fn fingerprint(scene: &Scene) -> u64 {
    let mut hash = 0xcbf2_9ce4_8422_2325u64;
    let mut eat = |bytes: &[u8]| {
        for &b in bytes {
            hash = (hash ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3);
        }
    };
    eat(format!("{:?}{:?}{:?}", scene.materials, scene.objects, scene.lights).as_bytes());
    let geometry = &scene.geometry;
    for prim in 0..geometry.triangle_count() {
        for v in geometry.vertices(prim) {
            eat(bytemuck::bytes_of(&v.to_array()));
        }
        for bary in [[0.0f32, 0.0], [1.0, 0.0], [0.0, 1.0]] {
            let n = geometry.shading_normal(prim, glam::Vec2::from_array(bary));
            eat(bytemuck::bytes_of(&n.to_array()));
        }
        eat(&geometry.object_of(prim).to_le_bytes());
    }
    hash
}

/// Bytes per pixel of a diag buffer (`uvec4`) and of the shaded image (`vec4`).
const TEXEL: usize = 16;

/// One run's buffers, recorded frames and read-back staging.
struct FrameRun<'a> {
    context: &'a Context,
    scene: &'a GpuScene,
    kernels: &'a HashMap<&'static str, Kernel>,
    plan: &'a Plan,
    /// [`Plan::waits`]: where a step waits for the steps before it (a barrier).
    waits: Vec<bool>,
    config: &'a RunConfig,
    width: u32,
    height: u32,
    params: Buffer,
    params_staging: Allocation,
    gpixels: [Buffer; 2],
    reservoirs: [Buffer; 3],
    /// One per preset pass.
    diags: Vec<Buffer>,
    image: Buffer,
    /// Image, then each pass's diag, then the final reservoirs.
    readback: Allocation,
    descriptor_pool: vk::DescriptorPool,
    /// Recorded frames by (current G-buffer, reservoir rotation).
    recorded: HashMap<(usize, Rotation), Recorded>,
}

/// A recorded frame.
struct Recorded {
    cb: vk::CommandBuffer,
    timestamps: Option<Timestamps>,
}

impl<'a> FrameRun<'a> {
    fn new(
        context: &'a Context,
        scene_gpu: &'a GpuScene,
        kernels: &'a HashMap<&'static str, Kernel>,
        scene: &Scene,
        plan: &'a Plan,
        config: &'a RunConfig,
    ) -> Result<FrameRun<'a>, VulkanError> {
        let (width, height) = (scene.camera.width(), scene.camera.height());
        let n = width as usize * height as usize;
        let zeroed = |bytes| Buffer::zeroed(context, bytes);
        let reservoir_bytes = n * PixelReservoir::BYTES;
        let passes = plan.passes().count();
        // At most six recorded frames (two G-buffers × three rotations), one set per step.
        let per_frame = 6 * plan.steps.len() as u32;
        let sizes = [vk::DescriptorPoolSize::default()
            .ty(vk::DescriptorType::STORAGE_BUFFER)
            .descriptor_count(per_frame * 16)];
        // SAFETY: valid create info on a live device; destroyed in `Drop`.
        let descriptor_pool = unsafe {
            context.shared.device.create_descriptor_pool(
                &vk::DescriptorPoolCreateInfo::default()
                    .max_sets(per_frame)
                    .pool_sizes(&sizes),
                None,
            )
        }
        .map_err(api("vkCreateDescriptorPool"))?;
        let mut run = FrameRun {
            context,
            scene: scene_gpu,
            kernels,
            plan,
            waits: plan.waits(),
            config,
            width,
            height,
            params: zeroed(size_of::<FrameParams>())?,
            params_staging: Allocation::new(
                &context.shared,
                size_of::<FrameParams>() as u64,
                vk::BufferUsageFlags::TRANSFER_SRC,
                Placement::Host,
            )?,
            gpixels: [
                zeroed(n * size_of::<GpuPixel>())?,
                zeroed(n * size_of::<GpuPixel>())?,
            ],
            reservoirs: [
                zeroed(reservoir_bytes)?,
                zeroed(reservoir_bytes)?,
                zeroed(reservoir_bytes)?,
            ],
            diags: Vec::new(),
            image: zeroed(n * TEXEL)?,
            readback: Allocation::new(
                &context.shared,
                ((passes + 1) * n * TEXEL + reservoir_bytes) as u64,
                vk::BufferUsageFlags::TRANSFER_DST,
                Placement::Host,
            )?,
            descriptor_pool,
            recorded: HashMap::new(),
        };
        run.diags = (0..passes)
            .map(|_| zeroed(n * TEXEL))
            .collect::<Result<_, _>>()?;
        Ok(run)
    }

    fn pixels(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// Runs every frame and assembles the [`Run`].
    fn run(&mut self, scene: &Scene) -> Result<Run, PipelineError> {
        let n = self.pixels();
        let config = *self.config;
        let plan = self.plan;
        let passes = plan.passes().count();
        let reuse_labels = plan
            .passes()
            .filter(|(_, step)| step.spec.is_some_and(|s| s.shift().is_some()))
            .map(|(_, step)| step.label.clone());
        let mut counters = config
            .collect_diagnostics
            .then(|| Counters::new(self.width, self.height, reuse_labels.collect()));
        let mut seconds = vec![0.0f64; plan.steps.len()];
        let mut timed = true;
        let mut frames = Vec::with_capacity(config.frames as usize);
        let mut nan_count = 0;
        let mut rotation = Rotation::FIRST;
        for frame in 0..config.frames {
            let params = FrameParams::new(scene, frame, frame.checked_sub(1), config.seed);
            self.params_staging
                .mapped_mut()
                .ok_or(VulkanError::NoMemoryType)?[..size_of::<FrameParams>()]
                .copy_from_slice(bytemuck::bytes_of(&params));
            let key = ((frame % 2) as usize, rotation);
            if !self.recorded.contains_key(&key) {
                let recorded = self.record(key)?;
                self.recorded.insert(key, recorded);
            }
            let recorded = &self.recorded[&key];
            {
                let submit = self.context.shared.lock();
                // SAFETY: the command buffer was recorded by `record`; the lock is held.
                unsafe {
                    super::device::submit_and_wait(
                        &self.context.shared.device,
                        submit.queue,
                        recorded.cb,
                    )
                }?;
            }
            match &recorded.timestamps {
                Some(t) => {
                    for (s, t) in seconds.iter_mut().zip(t.seconds()?) {
                        *s += t;
                    }
                }
                None => timed = false,
            }
            rotation = rotation.next(plan);
            let bytes = self.readback.mapped().ok_or(VulkanError::NoMemoryType)?;
            let texels: &[[f32; 4]] = bytemuck::cast_slice(&bytes[..n * TEXEL]);
            nan_count += texels.iter().filter(|t| t[3] != 0.0).count() as u64;
            frames.push(Image {
                width: self.width,
                height: self.height,
                pixels: texels
                    .iter()
                    .map(|t| glam::Vec3::new(t[0], t[1], t[2]))
                    .collect(),
            });
            for (index, step) in plan.passes() {
                let start = (index + 1) * n * TEXEL;
                let diag: &[[u32; 4]] = bytemuck::cast_slice(&bytes[start..start + n * TEXEL]);
                check_diag(frame, index, step, diag)?;
                if let Some(counters) = &mut counters {
                    add_diag(counters, index, step, diag);
                }
            }
        }
        let bytes = self.readback.mapped().ok_or(VulkanError::NoMemoryType)?;
        let start = (passes + 1) * n * TEXEL;
        let reservoirs: &[PixelReservoir] =
            bytemuck::cast_slice(&bytes[start..start + n * PixelReservoir::BYTES]);
        let timings = if timed {
            plan.steps
                .iter()
                .zip(seconds)
                .map(|(step, seconds)| PassTiming {
                    label: step.label.clone(),
                    seconds,
                })
                .collect()
        } else {
            Vec::new()
        };
        Ok(Run {
            frames,
            timings,
            diagnostics: counters.map(|c| c.finish()),
            nan_count,
            reservoirs: reservoirs.to_vec(),
        })
    }

    /// The buffer that plays `resource` in the frame whose G-buffer is `gpixels[current]` and
    /// whose reservoir buffers rotate as `rotation`.
    fn buffer(&self, resource: Resource, current: usize, rotation: Rotation) -> &Buffer {
        match resource {
            Resource::GBuffer => &self.gpixels[current],
            Resource::PreviousGBuffer => &self.gpixels[1 - current],
            Resource::Reservoirs(slot) => &self.reservoirs[rotation.buffer(slot)],
            Resource::Diag(pass) => &self.diags[pass],
            Resource::Image => &self.image,
        }
    }

    /// Records the frame whose current G-buffer is `gpixels[current]` and whose reservoir
    /// buffers rotate as `rotation`: the plan's steps, each bound to the frame's buffers in its
    /// kernel's binding order, a barrier where [`Plan::waits`] says, then the read-back copies.
    fn record(&self, (current, rotation): (usize, Rotation)) -> Result<Recorded, VulkanError> {
        let device = &self.context.shared.device;
        let n = self.pixels();
        let passes = self.plan.passes().count();
        let timestamps = Timestamps::new(self.context, self.plan.steps.len() as u32)?;
        let cb = {
            let submit = self.context.shared.lock();
            // SAFETY: allocation from the pool while its lock is held.
            unsafe {
                device.allocate_command_buffers(
                    &vk::CommandBufferAllocateInfo::default()
                        .command_pool(submit.command_pool)
                        .level(vk::CommandBufferLevel::PRIMARY)
                        .command_buffer_count(1),
                )
            }
            .map_err(api("vkAllocateCommandBuffers"))?[0]
        };
        // The command buffer is freed with the pool's other buffers in `Drop` from here on.
        let recorded = Recorded { cb, timestamps };
        let groups = groups_for(n as u32, 64);
        // SAFETY: `cb` is recorded here from live objects of this run, which outlive it.
        unsafe {
            device
                .begin_command_buffer(cb, &vk::CommandBufferBeginInfo::default())
                .map_err(api("vkBeginCommandBuffer"))?;
            if let Some(t) = &recorded.timestamps {
                t.reset(cb);
            }
            // The previous submission's transfers are done (its fence was waited on); this
            // orders them before this frame's writes all the same.
            barrier(
                device,
                cb,
                (
                    vk::PipelineStageFlags::ALL_COMMANDS,
                    vk::AccessFlags::MEMORY_WRITE,
                ),
                (
                    vk::PipelineStageFlags::ALL_COMMANDS,
                    vk::AccessFlags::MEMORY_READ | vk::AccessFlags::MEMORY_WRITE,
                ),
            );
            let region = [vk::BufferCopy::default().size(size_of::<FrameParams>() as u64)];
            device.cmd_copy_buffer(
                cb,
                self.params_staging.buffer,
                self.params.allocation.buffer,
                &region,
            );
            barrier(
                device,
                cb,
                (
                    vk::PipelineStageFlags::TRANSFER,
                    vk::AccessFlags::TRANSFER_WRITE,
                ),
                (
                    vk::PipelineStageFlags::COMPUTE_SHADER,
                    vk::AccessFlags::SHADER_READ,
                ),
            );
            for (section, (step, wait)) in self.plan.steps.iter().zip(&self.waits).enumerate() {
                if *wait {
                    barrier(
                        device,
                        cb,
                        (
                            vk::PipelineStageFlags::COMPUTE_SHADER,
                            vk::AccessFlags::SHADER_WRITE,
                        ),
                        (
                            vk::PipelineStageFlags::COMPUTE_SHADER,
                            vk::AccessFlags::SHADER_READ | vk::AccessFlags::SHADER_WRITE,
                        ),
                    );
                }
                let mut buffers: Vec<&Buffer> = self.scene.buffers().to_vec();
                buffers.push(&self.params);
                buffers.extend(
                    step.buffers
                        .iter()
                        .map(|&(resource, _)| self.buffer(resource, current, rotation)),
                );
                let push = step.params(self.config.collect_diagnostics);
                let shader = Shader::of(step.kernel);
                self.dispatch(
                    cb,
                    &recorded,
                    section as u32,
                    shader,
                    &buffers,
                    &push,
                    groups,
                )?;
            }
            barrier(
                device,
                cb,
                (
                    vk::PipelineStageFlags::COMPUTE_SHADER,
                    vk::AccessFlags::SHADER_WRITE,
                ),
                (
                    vk::PipelineStageFlags::TRANSFER,
                    vk::AccessFlags::TRANSFER_READ,
                ),
            );
            let texels = (n * TEXEL) as u64;
            let copy = |src: &Buffer, offset: u64, size: u64| {
                let region = [vk::BufferCopy::default().dst_offset(offset).size(size)];
                device.cmd_copy_buffer(cb, src.allocation.buffer, self.readback.buffer, &region);
            };
            copy(&self.image, 0, texels);
            for (index, diag) in self.diags.iter().enumerate() {
                copy(diag, (index as u64 + 1) * texels, texels);
            }
            copy(
                &self.reservoirs[rotation.buffer(self.plan.final_reservoirs)],
                (passes as u64 + 1) * texels,
                (n * PixelReservoir::BYTES) as u64,
            );
            barrier(
                device,
                cb,
                (
                    vk::PipelineStageFlags::TRANSFER,
                    vk::AccessFlags::TRANSFER_WRITE,
                ),
                (vk::PipelineStageFlags::HOST, vk::AccessFlags::HOST_READ),
            );
            device
                .end_command_buffer(cb)
                .map_err(api("vkEndCommandBuffer"))?;
        }
        Ok(recorded)
    }

    /// Records one timed step: bind, push, dispatch.
    #[allow(clippy::too_many_arguments)]
    fn dispatch(
        &self,
        cb: vk::CommandBuffer,
        recorded: &Recorded,
        section: u32,
        shader: Shader,
        buffers: &[&Buffer],
        push: &PassParams,
        groups: u32,
    ) -> Result<(), VulkanError> {
        let kernel = self
            .kernels
            .get(shader.name)
            .ok_or_else(|| VulkanError::UnknownShader(shader.name.to_string()))?;
        if buffers.len() != kernel.buffers as usize
            || kernel.push_bytes as usize != size_of::<PassParams>()
        {
            return Err(VulkanError::Binding(format!(
                "{} takes {} buffers and {} push bytes, got {} and {}",
                shader.name,
                kernel.buffers,
                kernel.push_bytes,
                buffers.len(),
                size_of::<PassParams>()
            )));
        }
        let device = &self.context.shared.device;
        // SAFETY: the set is allocated from this run's pool with the kernel's layout and
        // written with live buffers; `cb` is recording.
        unsafe {
            let set = bind_buffers(device, self.descriptor_pool, kernel, buffers)?;
            if let Some(t) = &recorded.timestamps {
                t.begin(cb, section);
            }
            device.cmd_bind_pipeline(cb, vk::PipelineBindPoint::COMPUTE, kernel.pipeline);
            device.cmd_bind_descriptor_sets(
                cb,
                vk::PipelineBindPoint::COMPUTE,
                kernel.layout,
                0,
                &[set],
                &[],
            );
            device.cmd_push_constants(
                cb,
                kernel.layout,
                vk::ShaderStageFlags::COMPUTE,
                0,
                bytemuck::bytes_of(push),
            );
            device.cmd_dispatch(cb, groups, 1, 1);
            if let Some(t) = &recorded.timestamps {
                t.end(cb, section);
            }
        }
        Ok(())
    }
}

/// The error a pass's diag reports, if any: loops the device cut short
/// ([`LOOP_BUDGET_CUT`]), probes with more hits than kept ([`HIT_OVERFLOW`]), or the first
/// pixel's resampling error ([`decode_error`]).
fn check_diag(
    frame: u32,
    pass: usize,
    step: &Step,
    diag: &[[u32; 4]],
) -> Result<(), PipelineError> {
    let pixels_with = |code| diag.iter().filter(|d| d[3] == code).count() as u64;
    let shader = step.kernel.name();
    match (pixels_with(LOOP_BUDGET_CUT), pixels_with(HIT_OVERFLOW)) {
        (0, 0) => {}
        (0, count) => {
            return Err(PipelineError::Vulkan(VulkanError::TooManyHits {
                shader,
                kept: KEPT_HITS as u32,
                count,
            }));
        }
        (count, _) => {
            return Err(PipelineError::Vulkan(VulkanError::LoopsCut {
                shader,
                count,
            }));
        }
    }
    let Some(pixel) = diag.iter().position(|d| d[3] != 0) else {
        return Ok(());
    };
    let pixel = pixel as u32;
    Err(match (step.kernel, decode_error(diag[pixel as usize][3])) {
        (PassKernel::Candidates, ResampleError::Candidate { error, .. }) => {
            PipelineError::Candidate {
                frame,
                pixel,
                error,
            }
        }
        (_, error) => PipelineError::Resample {
            frame,
            pass,
            pixel,
            error,
        },
    })
}

/// Adds a pass's diag counters: shifted / failed / improved of a reuse pass, or probes, hits
/// and the hybrid choice (1 reconnection, 2 delayed) of the candidates pass.
fn add_diag(counters: &mut Counters, pass: usize, step: &Step, diag: &[[u32; 4]]) {
    if step.spec.is_some_and(|s| s.shift().is_some()) {
        let shifts: Vec<ShiftCounts> = diag
            .iter()
            .map(|d| ShiftCounts {
                shifted: d[0],
                failed: d[1],
                improved: d[2],
            })
            .collect();
        // Candidates are pass 0 and every later pass reuses (Preset::validate).
        counters.add_shifts(pass - 1, &shifts);
        return;
    }
    let probes: Vec<_> = diag
        .iter()
        .map(|d| {
            let choice = match d[2] {
                1 => HybridChoice::Reconnection,
                2 => HybridChoice::Delayed,
                _ => HybridChoice::None,
            };
            (
                ProbeCounts {
                    probes: d[0],
                    hits: d[1],
                },
                choice,
            )
        })
        .collect();
    counters.add_candidates(&probes);
}

impl Drop for FrameRun<'_> {
    fn drop(&mut self) {
        let device = &self.context.shared.device;
        let submit = self.context.shared.lock();
        let cbs: Vec<_> = self.recorded.values().map(|r| r.cb).collect();
        // SAFETY: every submission was waited on; the pool lock is held while freeing.
        unsafe {
            if !cbs.is_empty() {
                device.free_command_buffers(submit.command_pool, &cbs);
            }
            device.destroy_descriptor_pool(self.descriptor_pool, None);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use restir::mis::MisKind;
    use shifts::ShiftKind;
    use std::mem::offset_of;

    #[test]
    fn pass_params_match_the_contract() {
        assert_eq!(size_of::<PassParams>(), 32);
        assert_eq!(offset_of!(PassParams, confidence_cap), 16);
        assert_eq!(offset_of!(PassParams, collect_diagnostics), 28);
        let spatial = PassSpec::Spatial {
            shift: ShiftKind::ALL[3],
            mis: MisKind::DefensivePairwise,
            neighbours: 4,
            confidence_cap: None,
        };
        let p = PassParams::new(2, Some(&spatial), true);
        assert_eq!((p.pass, p.shift, p.mis, p.neighbours), (2, 3, 2, 4));
        assert_eq!((p.confidence_cap, p.collect_diagnostics), (0.0, 1));
        let candidates = PassSpec::Candidates {
            bssrdf_samples: 3,
            shared_light: true,
        };
        let p = PassParams::new(0, Some(&candidates), false);
        assert_eq!((p.bssrdf_samples, p.shared_light, p.shift), (3, 1, 0));
    }

    #[test]
    fn unknown_error_codes_are_errors_too() {
        assert!(matches!(
            decode_error(0x0107),
            ResampleError::BadJacobian { source: 1, .. }
        ));
        assert!(matches!(
            decode_error(0x0309),
            ResampleError::Candidate {
                source: 3,
                error: InvalidCandidate::Weight(_)
            }
        ));
    }
}
