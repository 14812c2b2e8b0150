//! Screenshots of the window: the swapchain image a frame presents, copied into a host-visible
//! buffer in the frame's own command buffer ([`Readback`]) and returned as RGB ([`Capture`]).

use ash::vk;

use crate::vulkan_failure as fail;

/// An RGB capture of a presented frame.
pub struct Capture {
    pub width: u32,
    pub height: u32,
    /// Row-major from the top row, 3 bytes a pixel (the swapchain's 8-bit sRGB values).
    pub rgb: Vec<u8>,
}

/// A host-visible buffer a presented image is copied into.
pub struct Readback {
    buffer: vk::Buffer,
    memory: vk::DeviceMemory,
}

impl Readback {
    pub fn new(
        instance: &ash::Instance,
        physical: vk::PhysicalDevice,
        device: &ash::Device,
        extent: vk::Extent2D,
    ) -> Result<Readback, String> {
        let size = 4 * extent.width as u64 * extent.height as u64;
        let info = vk::BufferCreateInfo::default()
            .size(size)
            .usage(vk::BufferUsageFlags::TRANSFER_DST);
        // SAFETY: valid create and allocate infos; freed in `finish` (or on error below).
        unsafe {
            let buffer = device
                .create_buffer(&info, None)
                .map_err(fail("capture buffer"))?;
            let needs = device.get_buffer_memory_requirements(buffer);
            let types = instance.get_physical_device_memory_properties(physical);
            let wanted =
                vk::MemoryPropertyFlags::HOST_VISIBLE | vk::MemoryPropertyFlags::HOST_COHERENT;
            let Some(kind) = (0..types.memory_type_count).find(|&i| {
                needs.memory_type_bits & (1 << i) != 0
                    && types.memory_types[i as usize]
                        .property_flags
                        .contains(wanted)
            }) else {
                device.destroy_buffer(buffer, None);
                return Err("window presentation: no host-visible memory for a capture".into());
            };
            let alloc = vk::MemoryAllocateInfo::default()
                .allocation_size(needs.size)
                .memory_type_index(kind);
            let memory = match device.allocate_memory(&alloc, None) {
                Ok(memory) => memory,
                Err(e) => {
                    device.destroy_buffer(buffer, None);
                    return Err(fail("capture memory")(e));
                }
            };
            if let Err(e) = device.bind_buffer_memory(buffer, memory, 0) {
                device.destroy_buffer(buffer, None);
                device.free_memory(memory, None);
                return Err(fail("bind capture memory")(e));
            }
            Ok(Readback { buffer, memory })
        }
    }

    /// Records the copy of `image` (in `PRESENT_SRC_KHR` after the render pass) into the
    /// buffer, leaving the image ready to present.
    pub fn record(
        &self,
        device: &ash::Device,
        cmd: vk::CommandBuffer,
        image: vk::Image,
        extent: vk::Extent2D,
    ) {
        let range = vk::ImageSubresourceRange::default()
            .aspect_mask(vk::ImageAspectFlags::COLOR)
            .level_count(1)
            .layer_count(1);
        let barrier = |from, to, src, dst| {
            vk::ImageMemoryBarrier::default()
                .old_layout(from)
                .new_layout(to)
                .src_access_mask(src)
                .dst_access_mask(dst)
                .image(image)
                .subresource_range(range)
        };
        let layers = vk::ImageSubresourceLayers::default()
            .aspect_mask(vk::ImageAspectFlags::COLOR)
            .layer_count(1);
        let region = vk::BufferImageCopy::default()
            .image_subresource(layers)
            .image_extent(vk::Extent3D {
                width: extent.width,
                height: extent.height,
                depth: 1,
            });
        // SAFETY: recording into a command buffer in the recording state; live handles.
        unsafe {
            device.cmd_pipeline_barrier(
                cmd,
                vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT,
                vk::PipelineStageFlags::TRANSFER,
                vk::DependencyFlags::empty(),
                &[],
                &[],
                &[barrier(
                    vk::ImageLayout::PRESENT_SRC_KHR,
                    vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                    vk::AccessFlags::COLOR_ATTACHMENT_WRITE,
                    vk::AccessFlags::TRANSFER_READ,
                )],
            );
            device.cmd_copy_image_to_buffer(
                cmd,
                image,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                self.buffer,
                &[region],
            );
            let to_host = vk::BufferMemoryBarrier::default()
                .src_access_mask(vk::AccessFlags::TRANSFER_WRITE)
                .dst_access_mask(vk::AccessFlags::HOST_READ)
                .buffer(self.buffer)
                .size(vk::WHOLE_SIZE);
            device.cmd_pipeline_barrier(
                cmd,
                vk::PipelineStageFlags::TRANSFER,
                vk::PipelineStageFlags::BOTTOM_OF_PIPE | vk::PipelineStageFlags::HOST,
                vk::DependencyFlags::empty(),
                &[],
                &[to_host],
                &[barrier(
                    vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                    vk::ImageLayout::PRESENT_SRC_KHR,
                    vk::AccessFlags::TRANSFER_READ,
                    vk::AccessFlags::empty(),
                )],
            );
        }
    }

    /// The copied pixels as RGB (after the submit completed); frees the buffer.
    pub fn finish(
        self,
        device: &ash::Device,
        extent: vk::Extent2D,
        format: vk::Format,
    ) -> Result<Capture, String> {
        let n = extent.width as usize * extent.height as usize;
        // SAFETY: the copy completed (fence waited); the mapping covers the buffer's 4n bytes
        // and is unmapped before the memory is freed.
        let rgb = unsafe {
            let mapped =
                device.map_memory(self.memory, 0, vk::WHOLE_SIZE, vk::MemoryMapFlags::empty());
            let rgb = mapped.map_err(fail("map capture")).map(|ptr| {
                let bytes = std::slice::from_raw_parts(ptr as *const u8, 4 * n);
                let bgr = matches!(
                    format,
                    vk::Format::B8G8R8A8_UNORM | vk::Format::B8G8R8A8_SRGB
                );
                bytes
                    .chunks_exact(4)
                    .flat_map(|p| {
                        if bgr {
                            [p[2], p[1], p[0]]
                        } else {
                            [p[0], p[1], p[2]]
                        }
                    })
                    .collect()
            });
            if rgb.is_ok() {
                device.unmap_memory(self.memory);
            }
            device.destroy_buffer(self.buffer, None);
            device.free_memory(self.memory, None);
            rgb?
        };
        Ok(Capture {
            width: extent.width,
            height: extent.height,
            rgb,
        })
    }
}
