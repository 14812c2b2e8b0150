//! Compute kernels (one pipeline per SPIR-V module) and single timed dispatches.
//!
//! Binding `i` of a kernel is the `i`-th buffer of a dispatch; push constants are raw bytes (a
//! `#[repr(C)]` + `bytemuck` struct on the Rust side). A frame of several passes is recorded
//! once and re-submitted by [`super::pipeline`].

use std::sync::Arc;

use ash::vk;

use super::device::{Context, Shared};
use super::error::{VulkanError, api};
use super::memory::Buffer;

/// One compute pipeline: a SPIR-V module with `buffers` storage-buffer bindings (0, 1, …) and
/// `push_bytes` bytes of push constants, entry point `main`.
pub struct Kernel {
    shared: Arc<Shared>,
    module: vk::ShaderModule,
    pub(crate) set_layout: vk::DescriptorSetLayout,
    pub(crate) layout: vk::PipelineLayout,
    pub(crate) pipeline: vk::Pipeline,
    pub(crate) buffers: u32,
    pub(crate) push_bytes: u32,
}

impl Kernel {
    /// Builds the pipeline; `push_bytes` must be a multiple of 4 (Vulkan's rule).
    pub fn new(
        context: &Context,
        spirv: &[u8],
        buffers: u32,
        push_bytes: u32,
    ) -> Result<Kernel, VulkanError> {
        if !push_bytes.is_multiple_of(4) {
            return Err(VulkanError::Binding(format!(
                "{push_bytes} push-constant bytes is not a multiple of 4"
            )));
        }
        let words = ash::util::read_spv(&mut std::io::Cursor::new(spirv))
            .map_err(|e| VulkanError::InvalidSpirv(e.to_string()))?;
        let shared = context.shared.clone();
        let device = &shared.device;
        // Every handle starts null: `Drop` destroys what was created if a later step fails.
        let mut kernel = Kernel {
            shared: shared.clone(),
            module: vk::ShaderModule::null(),
            set_layout: vk::DescriptorSetLayout::null(),
            layout: vk::PipelineLayout::null(),
            pipeline: vk::Pipeline::null(),
            buffers,
            push_bytes,
        };
        let bindings: Vec<_> = (0..buffers)
            .map(|binding| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(binding)
                    .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                    .descriptor_count(1)
                    .stage_flags(vk::ShaderStageFlags::COMPUTE)
            })
            .collect();
        // SAFETY: valid create infos on a live device.
        unsafe {
            kernel.module = device
                .create_shader_module(&vk::ShaderModuleCreateInfo::default().code(&words), None)
                .map_err(api("vkCreateShaderModule"))?;
            kernel.set_layout = device
                .create_descriptor_set_layout(
                    &vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings),
                    None,
                )
                .map_err(api("vkCreateDescriptorSetLayout"))?;
            let ranges = [vk::PushConstantRange::default()
                .stage_flags(vk::ShaderStageFlags::COMPUTE)
                .size(push_bytes)];
            let set_layouts = [kernel.set_layout];
            let layout_info = vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts);
            let layout_info = if push_bytes > 0 {
                layout_info.push_constant_ranges(&ranges)
            } else {
                layout_info
            };
            kernel.layout = device
                .create_pipeline_layout(&layout_info, None)
                .map_err(api("vkCreatePipelineLayout"))?;
            let stage = vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::COMPUTE)
                .module(kernel.module)
                .name(c"main");
            let info = vk::ComputePipelineCreateInfo::default()
                .stage(stage)
                .layout(kernel.layout);
            kernel.pipeline = device
                .create_compute_pipelines(vk::PipelineCache::null(), &[info], None)
                .map_err(|(_, result)| api("vkCreateComputePipelines")(result))?[0];
        }
        shared.check_validation()?;
        Ok(kernel)
    }
}

impl Drop for Kernel {
    fn drop(&mut self) {
        let device = &self.shared.device;
        // SAFETY: null handles are ignored by vkDestroy*; dispatches have completed.
        unsafe {
            device.destroy_pipeline(self.pipeline, None);
            device.destroy_pipeline_layout(self.layout, None);
            device.destroy_descriptor_set_layout(self.set_layout, None);
            device.destroy_shader_module(self.module, None);
        }
    }
}

/// What a dispatch measured.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dispatch {
    /// GPU time between the timestamps around the dispatch, when the queue supports them.
    pub gpu_seconds: Option<f64>,
}

/// Per-dispatch objects, destroyed together whatever happens.
struct Submission<'a> {
    device: &'a ash::Device,
    pool: vk::CommandPool,
    descriptor_pool: vk::DescriptorPool,
    command_buffer: vk::CommandBuffer,
    fence: vk::Fence,
    queries: vk::QueryPool,
}

impl Drop for Submission<'_> {
    fn drop(&mut self) {
        // SAFETY: the fence was waited on (or never submitted); null handles are ignored.
        unsafe {
            if self.command_buffer != vk::CommandBuffer::null() {
                self.device
                    .free_command_buffers(self.pool, &[self.command_buffer]);
            }
            self.device.destroy_fence(self.fence, None);
            self.device.destroy_query_pool(self.queries, None);
            self.device
                .destroy_descriptor_pool(self.descriptor_pool, None);
        }
    }
}

/// A descriptor set of `kernel`'s layout from `pool`, with `buffers` bound in order to bindings
/// `0..`.
///
/// # Safety
/// `pool`, `kernel` and `buffers` must be live objects of `device`, and `pool` must have room
/// for one more set of `kernel.buffers` storage buffers.
pub(super) unsafe fn bind_buffers(
    device: &ash::Device,
    pool: vk::DescriptorPool,
    kernel: &Kernel,
    buffers: &[&Buffer],
) -> Result<vk::DescriptorSet, VulkanError> {
    let layouts = [kernel.set_layout];
    // SAFETY: the caller guarantees live objects and room in the pool.
    let set = unsafe {
        device.allocate_descriptor_sets(
            &vk::DescriptorSetAllocateInfo::default()
                .descriptor_pool(pool)
                .set_layouts(&layouts),
        )
    }
    .map_err(api("vkAllocateDescriptorSets"))?[0];
    let infos: Vec<[vk::DescriptorBufferInfo; 1]> = buffers
        .iter()
        .map(|b| {
            [vk::DescriptorBufferInfo::default()
                .buffer(b.allocation.buffer)
                .range(vk::WHOLE_SIZE)]
        })
        .collect();
    let writes: Vec<_> = infos
        .iter()
        .enumerate()
        .map(|(binding, info)| {
            vk::WriteDescriptorSet::default()
                .dst_set(set)
                .dst_binding(binding as u32)
                .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                .buffer_info(info)
        })
        .collect();
    // SAFETY: the set was just allocated and the buffers are live.
    unsafe { device.update_descriptor_sets(&writes, &[]) };
    Ok(set)
}

/// Work groups needed to cover `count` invocations with `local_size` per group.
pub fn groups_for(count: u32, local_size: u32) -> u32 {
    count.div_ceil(local_size.max(1))
}

impl Context {
    /// Runs `kernel` over `groups` work groups with `buffers` bound in order and `push` as push
    /// constants, and waits for it; buffer contents are then readable.
    pub fn dispatch(
        &mut self,
        kernel: &Kernel,
        buffers: &[&Buffer],
        push: &[u8],
        groups: [u32; 3],
    ) -> Result<Dispatch, VulkanError> {
        if buffers.len() != kernel.buffers as usize || push.len() != kernel.push_bytes as usize {
            return Err(VulkanError::Binding(format!(
                "kernel takes {} buffers and {} push bytes, got {} and {}",
                kernel.buffers,
                kernel.push_bytes,
                buffers.len(),
                push.len()
            )));
        }
        let device = &self.shared.device;
        // Held until `submission` (declared after it, so dropped before it) is freed.
        let submit = self.shared.lock();
        let mut submission = Submission {
            device,
            pool: submit.command_pool,
            descriptor_pool: vk::DescriptorPool::null(),
            command_buffer: vk::CommandBuffer::null(),
            fence: vk::Fence::null(),
            queries: vk::QueryPool::null(),
        };
        // SAFETY: every handle below is created here from the live device and freed by
        // `submission`; the fence wait orders host reads after the GPU writes.
        unsafe {
            if kernel.buffers > 0 {
                let sizes = [vk::DescriptorPoolSize::default()
                    .ty(vk::DescriptorType::STORAGE_BUFFER)
                    .descriptor_count(kernel.buffers)];
                submission.descriptor_pool = device
                    .create_descriptor_pool(
                        &vk::DescriptorPoolCreateInfo::default()
                            .max_sets(1)
                            .pool_sizes(&sizes),
                        None,
                    )
                    .map_err(api("vkCreateDescriptorPool"))?;
            }
            let set = if kernel.buffers > 0 {
                Some(bind_buffers(
                    device,
                    submission.descriptor_pool,
                    kernel,
                    buffers,
                )?)
            } else {
                None
            };
            if self.timestamp_period.is_some() {
                submission.queries = device
                    .create_query_pool(
                        &vk::QueryPoolCreateInfo::default()
                            .query_type(vk::QueryType::TIMESTAMP)
                            .query_count(2),
                        None,
                    )
                    .map_err(api("vkCreateQueryPool"))?;
            }
            submission.command_buffer = device
                .allocate_command_buffers(
                    &vk::CommandBufferAllocateInfo::default()
                        .command_pool(submission.pool)
                        .level(vk::CommandBufferLevel::PRIMARY)
                        .command_buffer_count(1),
                )
                .map_err(api("vkAllocateCommandBuffers"))?[0];
            let cb = submission.command_buffer;
            device
                .begin_command_buffer(
                    cb,
                    &vk::CommandBufferBeginInfo::default()
                        .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
                )
                .map_err(api("vkBeginCommandBuffer"))?;
            let timed = submission.queries != vk::QueryPool::null();
            if timed {
                device.cmd_reset_query_pool(cb, submission.queries, 0, 2);
                device.cmd_write_timestamp(
                    cb,
                    vk::PipelineStageFlags::TOP_OF_PIPE,
                    submission.queries,
                    0,
                );
            }
            device.cmd_bind_pipeline(cb, vk::PipelineBindPoint::COMPUTE, kernel.pipeline);
            if let Some(set) = set {
                device.cmd_bind_descriptor_sets(
                    cb,
                    vk::PipelineBindPoint::COMPUTE,
                    kernel.layout,
                    0,
                    &[set],
                    &[],
                );
            }
            if !push.is_empty() {
                device.cmd_push_constants(
                    cb,
                    kernel.layout,
                    vk::ShaderStageFlags::COMPUTE,
                    0,
                    push,
                );
            }
            device.cmd_dispatch(cb, groups[0], groups[1], groups[2]);
            if timed {
                device.cmd_write_timestamp(
                    cb,
                    vk::PipelineStageFlags::BOTTOM_OF_PIPE,
                    submission.queries,
                    1,
                );
            }
            let barrier = vk::MemoryBarrier::default()
                .src_access_mask(vk::AccessFlags::SHADER_WRITE)
                .dst_access_mask(vk::AccessFlags::HOST_READ);
            device.cmd_pipeline_barrier(
                cb,
                vk::PipelineStageFlags::COMPUTE_SHADER,
                vk::PipelineStageFlags::HOST,
                vk::DependencyFlags::empty(),
                &[barrier],
                &[],
                &[],
            );
            device
                .end_command_buffer(cb)
                .map_err(api("vkEndCommandBuffer"))?;
            submission.fence = device
                .create_fence(&vk::FenceCreateInfo::default(), None)
                .map_err(api("vkCreateFence"))?;
            let command_buffers = [cb];
            let submit_info = vk::SubmitInfo::default().command_buffers(&command_buffers);
            device
                .queue_submit(submit.queue, &[submit_info], submission.fence)
                .map_err(api("vkQueueSubmit"))?;
            device
                .wait_for_fences(&[submission.fence], true, u64::MAX)
                .map_err(api("vkWaitForFences"))?;
            let gpu_seconds = match self.timestamp_period {
                Some(period) if timed => {
                    let mut ticks = [0u64; 2];
                    device
                        .get_query_pool_results(
                            submission.queries,
                            0,
                            &mut ticks,
                            vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
                        )
                        .map_err(api("vkGetQueryPoolResults"))?;
                    Some(ticks[1].wrapping_sub(ticks[0]) as f64 * period * 1e-9)
                }
                _ => None,
            };
            self.shared.check_validation()?;
            Ok(Dispatch { gpu_seconds })
        }
    }
}
