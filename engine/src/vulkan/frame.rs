//! A preset's [`Plan`] frame after frame on the device: the twin of `cpu::CpuStream`.
//!
//! A [`FrameRun`] allocates its buffers once and records each distinct frame — the plan's steps, each
//! bound to the frame's buffers in its kernel's binding order with a barrier where
//! [`Plan::waits`] says, then read-back copies — into a command buffer once; frames are
//! re-submitted; the buffers (G-buffers, reservoirs) stay on the device between frames. Frames
//! differ only in which buffers play "current" and "previous" (the
//! G-buffer alternates, the reservoir buffers rotate as [`Rotation`] says), so a run records at
//! most six command buffers. `FrameParams` is copied from a staging buffer at the start of
//! every frame, and a timestamp pair around each step gives [`Run::timings`] in GPU seconds.

use std::collections::HashMap;
use std::sync::Arc;

use ash::vk;
use sss::scene::Scene;

use super::compute::bind_buffers;
use super::decode::{add_diag, check_diag};
use super::device::{Context, Shared};
use super::error::{VulkanError, api};
use super::memory::{Allocation, Buffer, Placement, barrier};
use super::scene::GpuScene;
use super::shaders::Shader;
use super::timing::Timestamps;
use super::{Kernel, groups_for};
use crate::clock::{Clock, Timing};
use crate::contract::{FrameParams, GpuPixel, PassParams};
use crate::diagnostics::Counters;
use crate::image::Image;
use crate::plan::{PassKernel, Plan, Resource, Rotation};
use crate::stream::frame::{Finished, Frame, mean_confidence};
use crate::{PipelineError, RunConfig};
use shifts::PixelReservoir;

/// `pass_candidates.glsl` ([`PassKernel::Candidates`]).
pub const CANDIDATES: Shader = Shader::of(PassKernel::Candidates);
/// `pass_temporal.glsl` ([`PassKernel::Temporal`]).
pub const TEMPORAL: Shader = Shader::of(PassKernel::Temporal);
/// `pass_spatial.glsl` ([`PassKernel::Spatial`]).
pub const SPATIAL: Shader = Shader::of(PassKernel::Spatial);

/// Bytes per pixel of a diag buffer (`uvec4`) and of the shaded image (`vec4`).
const TEXEL: usize = 16;

/// What a frame borrows from its renderer: the device, the uploaded scene and the kernels.
pub(super) struct Parts<'r> {
    pub(super) context: &'r Context,
    pub(super) scene: &'r GpuScene,
    pub(super) kernels: &'r HashMap<&'static str, Kernel>,
}

/// A stream's buffers, recorded frames, read-back staging and the state between its frames.
pub(super) struct FrameRun {
    shared: Arc<Shared>,
    pub(super) plan: Plan,
    /// [`Plan::waits`]: where a step waits for the steps before it (a barrier).
    pub(super) waits: Vec<bool>,
    config: RunConfig,
    width: u32,
    height: u32,
    params: Buffer,
    params_staging: Allocation,
    gpixels: [Buffer; 2],
    reservoirs: [Buffer; 3],
    /// One per preset pass.
    diags: Vec<Buffer>,
    image: Buffer,
    /// [`Resource::RaoBlackwellised`]: a texel per pixel where the plan clears it
    /// (`Shade::AllInputs`), else one texel that no kernel reads or writes.
    rao_blackwellised: Buffer,
    /// Image, then each pass's diag, then the final reservoirs.
    readback: Allocation,
    descriptor_pool: vk::DescriptorPool,
    /// Recorded frames by (current G-buffer, reservoir rotation).
    recorded: HashMap<(usize, Rotation), Recorded>,
    /// The rotation of the next frame's reservoir buffers.
    rotation: Rotation,
    /// The frame [`FrameRun::frame`] renders next.
    next: u32,
    counters: Option<Counters>,
}

/// A recorded frame.
struct Recorded {
    cb: vk::CommandBuffer,
    timestamps: Option<Timestamps>,
}

impl FrameRun {
    pub(super) fn new(
        context: &Context,
        scene: &Scene,
        plan: Plan,
        config: &RunConfig,
    ) -> Result<FrameRun, VulkanError> {
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
        let reuse_labels = plan
            .passes()
            .filter(|(_, step)| step.spec.is_some_and(|s| s.shift().is_some()))
            .map(|(_, step)| step.label.clone());
        let counters = config
            .collect_diagnostics
            .then(|| Counters::new(width, height, reuse_labels.collect()));
        let rao_blackwellised_bytes = match plan.clears(Resource::RaoBlackwellised) {
            true => n * TEXEL,
            false => TEXEL,
        };
        let mut run = FrameRun {
            shared: context.shared.clone(),
            waits: plan.waits(),
            plan,
            config: *config,
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
            rao_blackwellised: zeroed(rao_blackwellised_bytes)?,
            readback: Allocation::new(
                &context.shared,
                ((passes + 1) * n * TEXEL + reservoir_bytes) as u64,
                vk::BufferUsageFlags::TRANSFER_DST,
                Placement::Host,
            )?,
            descriptor_pool,
            recorded: HashMap::new(),
            rotation: Rotation::FIRST,
            next: 0,
            counters,
        };
        run.diags = (0..passes)
            .map(|_| zeroed(n * TEXEL))
            .collect::<Result<_, _>>()?;
        Ok(run)
    }

    fn pixels(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// The labels of the plan's steps, in execution order.
    pub(super) fn labels(&self) -> Vec<String> {
        self.plan.steps.iter().map(|s| s.label.clone()).collect()
    }

    /// The index of the frame [`FrameRun::frame`] renders next.
    pub(super) fn next(&self) -> u32 {
        self.next
    }

    /// Renders the next frame on `parts` (the renderer this run was created on) and reads it
    /// back.
    pub(super) fn frame(&mut self, parts: &Parts, scene: &Scene) -> Result<Frame, PipelineError> {
        let n = self.pixels();
        let frame = self.next;
        let params = FrameParams::new(scene, frame, frame.checked_sub(1), self.config.seed);
        self.params_staging
            .mapped_mut()
            .ok_or(VulkanError::NoMemoryType)?[..size_of::<FrameParams>()]
            .copy_from_slice(bytemuck::bytes_of(&params));
        let key = ((frame % 2) as usize, self.rotation);
        if !self.recorded.contains_key(&key) {
            let recorded = self.record(parts, key)?;
            self.recorded.insert(key, recorded);
        }
        let recorded = &self.recorded[&key];
        {
            let submit = self.shared.lock();
            // SAFETY: the command buffer was recorded by `record`; the lock is held.
            unsafe { self.shared.submit_and_wait(submit.queue, recorded.cb) }?;
        }
        let steps = match &recorded.timestamps {
            Some(t) => t
                .seconds()?
                .into_iter()
                .map(|seconds| Timing {
                    clock: Clock::Wall,
                    seconds,
                    wall_seconds: seconds,
                })
                .collect(),
            None => Vec::new(),
        };
        self.rotation = self.rotation.next(&self.plan);
        self.next += 1;
        let passes = self.plan.passes().count();
        let bytes = self.readback.mapped().ok_or(VulkanError::NoMemoryType)?;
        let texels: &[[f32; 4]] = bytemuck::cast_slice(&bytes[..n * TEXEL]);
        let nan_count = texels.iter().filter(|t| t[3] != 0.0).count() as u64;
        let image = Image {
            width: self.width,
            height: self.height,
            pixels: texels
                .iter()
                .map(|t| glam::Vec3::new(t[0], t[1], t[2]))
                .collect(),
        };
        for (index, step) in self.plan.passes() {
            let start = (index + 1) * n * TEXEL;
            let diag: &[[u32; 4]] = bytemuck::cast_slice(&bytes[start..start + n * TEXEL]);
            check_diag(frame, index, step, diag)?;
            if let Some(counters) = &mut self.counters {
                add_diag(counters, index, step, diag);
            }
        }
        let start = (passes + 1) * n * TEXEL;
        let reservoirs: &[PixelReservoir] =
            bytemuck::cast_slice(&bytes[start..start + n * PixelReservoir::BYTES]);
        Ok(Frame {
            index: frame,
            image,
            nan_count,
            steps,
            confidence: mean_confidence(reservoirs),
        })
    }

    /// The last frame's final reservoirs (read back with it) and the diagnostics.
    pub(super) fn finish(&mut self) -> Result<Finished, VulkanError> {
        let n = self.pixels();
        let passes = self.plan.passes().count();
        let bytes = self.readback.mapped().ok_or(VulkanError::NoMemoryType)?;
        let start = (passes + 1) * n * TEXEL;
        let reservoirs: &[PixelReservoir] =
            bytemuck::cast_slice(&bytes[start..start + n * PixelReservoir::BYTES]);
        Ok(Finished {
            diagnostics: self.counters.take().map(|c| c.finish()),
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
            Resource::RaoBlackwellised => &self.rao_blackwellised,
        }
    }

    /// Records the frame whose current G-buffer is `gpixels[current]` and whose reservoir
    /// buffers rotate as `rotation`: the plan's steps, each bound to the frame's buffers in its
    /// kernel's binding order, a barrier where [`Plan::waits`] says, then the read-back copies.
    fn record(
        &self,
        parts: &Parts,
        (current, rotation): (usize, Rotation),
    ) -> Result<Recorded, VulkanError> {
        let device = &self.shared.device;
        let n = self.pixels();
        let passes = self.plan.passes().count();
        let timestamps = Timestamps::new(parts.context, self.plan.steps.len() as u32)?;
        let cb = {
            let submit = self.shared.lock();
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
                if !step.clears.is_empty() {
                    self.clear(cb, &step.clears, current, rotation);
                }
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
                let mut buffers: Vec<&Buffer> = parts.scene.buffers().to_vec();
                buffers.push(&self.params);
                buffers.extend(
                    step.buffers
                        .iter()
                        .map(|&(resource, _)| self.buffer(resource, current, rotation)),
                );
                let push = step.params(self.config.collect_diagnostics);
                let shader = Shader::of(step.kernel);
                self.dispatch(
                    parts,
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

    /// Records zeroing `resources` after the compute work before it and before the compute work
    /// after it.
    ///
    /// # Safety
    /// `cb` is recording.
    unsafe fn clear(
        &self,
        cb: vk::CommandBuffer,
        resources: &[Resource],
        current: usize,
        rotation: Rotation,
    ) {
        let device = &self.shared.device;
        let compute = (
            vk::PipelineStageFlags::COMPUTE_SHADER,
            vk::AccessFlags::SHADER_READ | vk::AccessFlags::SHADER_WRITE,
        );
        let transfer = (
            vk::PipelineStageFlags::TRANSFER,
            vk::AccessFlags::TRANSFER_WRITE,
        );
        // SAFETY: `cb` is recording (the caller's contract); the buffers are this run's.
        unsafe {
            barrier(device, cb, compute, transfer);
            for &resource in resources {
                let buffer = self.buffer(resource, current, rotation).allocation.buffer;
                device.cmd_fill_buffer(cb, buffer, 0, vk::WHOLE_SIZE, 0);
            }
            barrier(device, cb, transfer, compute);
        }
    }

    /// Records one timed step: bind, push, dispatch.
    #[allow(clippy::too_many_arguments)]
    fn dispatch(
        &self,
        parts: &Parts,
        cb: vk::CommandBuffer,
        recorded: &Recorded,
        section: u32,
        shader: Shader,
        buffers: &[&Buffer],
        push: &PassParams,
        groups: u32,
    ) -> Result<(), VulkanError> {
        let kernel = parts
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
        let device = &self.shared.device;
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

impl Drop for FrameRun {
    fn drop(&mut self) {
        let device = &self.shared.device;
        let submit = self.shared.lock();
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
