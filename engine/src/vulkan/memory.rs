//! Storage buffers: device-local memory, filled and read back through host-visible staging
//! buffers. Memory comes from `gpu-allocator`, which sub-allocates buffers from large blocks
//! (256 MiB device-local, 64 MiB host-visible by default) instead of one `vkAllocateMemory`
//! per buffer; [`memory_type`] still decides which memory type a buffer lives in.
//!
//! A memory type that is device-local *and* host-visible + host-coherent (a CPU device such as
//! lavapipe, or a unified-memory GPU) is mapped directly and needs no staging; a discrete GPU's
//! device-local heap is reached by `vkCmdCopyBuffer` through a staging buffer. Devices with no
//! device-local type at all use host-visible memory, mapped.

use std::sync::Arc;

use ash::vk;
use bytemuck::Pod;
use gpu_allocator::MemoryLocation;
use gpu_allocator::vulkan::{self as allocator, AllocationCreateDesc, AllocationScheme};

use super::device::{Context, Shared};
use super::error::{VulkanError, api};

/// One `vk::Buffer` bound to a range of a block of the allocator, optionally mapped.
pub(crate) struct Allocation {
    shared: Arc<Shared>,
    pub(crate) buffer: vk::Buffer,
    /// The buffer's range of device memory (`None` until bound; returned in `Drop`).
    memory: Option<allocator::Allocation>,
    /// The mapping of the buffer's range, when the memory is host-visible and coherent.
    mapped: Option<*mut u8>,
    /// Bytes allocated (≥ 4).
    size: u64,
}

/// Where an allocation should live.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Placement {
    /// Device-local first (not host-visible first, then host-visible), else host-visible.
    Device,
    /// Host-visible and coherent (cached preferred): staging for uploads and read-backs.
    Host,
}

/// The memory type index for `placement` among those allowed by `type_bits`.
fn memory_type(
    properties: &vk::PhysicalDeviceMemoryProperties,
    type_bits: u32,
    placement: Placement,
) -> Option<u32> {
    use vk::MemoryPropertyFlags as F;
    let host = F::HOST_VISIBLE | F::HOST_COHERENT;
    let preferences: &[(F, F)] = match placement {
        // (must have, must not have)
        Placement::Device => &[
            (F::DEVICE_LOCAL, F::HOST_VISIBLE),
            (F::DEVICE_LOCAL, F::empty()),
            (host, F::empty()),
        ],
        Placement::Host => &[(host | F::HOST_CACHED, F::empty()), (host, F::empty())],
    };
    preferences.iter().find_map(|&(wanted, unwanted)| {
        (0..properties.memory_type_count).find(|&i| {
            let flags = properties.memory_types[i as usize].property_flags;
            type_bits & (1 << i) != 0 && flags.contains(wanted) && !flags.intersects(unwanted)
        })
    })
}

impl Allocation {
    /// A buffer of `bytes` (at least 4: Vulkan has no empty buffers) in `placement` memory,
    /// mapped when that memory is host-visible and coherent. Contents are undefined.
    pub(crate) fn new(
        shared: &Arc<Shared>,
        bytes: u64,
        usage: vk::BufferUsageFlags,
        placement: Placement,
    ) -> Result<Allocation, VulkanError> {
        let device = &shared.device;
        let size = bytes.max(4);
        let info = vk::BufferCreateInfo::default()
            .size(size)
            .usage(usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE);
        // Every handle starts null: `Drop` releases what was created if a later step fails.
        let mut allocation = Allocation {
            shared: shared.clone(),
            buffer: vk::Buffer::null(),
            memory: None,
            mapped: None,
            size,
        };
        // SAFETY: valid create info on a live device.
        allocation.buffer =
            unsafe { device.create_buffer(&info, None) }.map_err(api("vkCreateBuffer"))?;
        // SAFETY: a live buffer.
        let mut requirements = unsafe { device.get_buffer_memory_requirements(allocation.buffer) };
        let index = memory_type(&shared.memory, requirements.memory_type_bits, placement)
            .ok_or(VulkanError::NoMemoryType)?;
        let flags = shared.memory.memory_types[index as usize].property_flags;
        let host = vk::MemoryPropertyFlags::HOST_VISIBLE | vk::MemoryPropertyFlags::HOST_COHERENT;
        // The allocator sees only the chosen type; its location must accept that type's flags.
        requirements.memory_type_bits = 1 << index;
        // `GpuOnly` requires device-local memory, `GpuToCpu` host-visible and coherent memory,
        // which every other type `memory_type` picks has.
        let device_local = flags.contains(vk::MemoryPropertyFlags::DEVICE_LOCAL);
        let location = if placement == Placement::Device && device_local {
            MemoryLocation::GpuOnly
        } else {
            MemoryLocation::GpuToCpu
        };
        let memory = allocation.shared.allocate(&AllocationCreateDesc {
            name: "reshift buffer",
            requirements,
            location,
            linear: true,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        })?;
        // SAFETY: the range was allocated for this buffer's requirements and is freed after
        // the buffer is destroyed.
        unsafe { device.bind_buffer_memory(allocation.buffer, memory.memory(), memory.offset()) }
            .map_err(api("vkBindBufferMemory"))?;
        if flags.contains(host) {
            // Host-visible blocks stay mapped for their lifetime; this is the buffer's range.
            allocation.mapped = memory.mapped_ptr().map(|p| p.as_ptr().cast());
        }
        allocation.memory = Some(memory);
        Ok(allocation)
    }

    /// The mapped bytes, when host-visible. The caller orders access after GPU writes (fences).
    pub(crate) fn mapped(&self) -> Option<&[u8]> {
        // SAFETY: the mapping covers `size` bytes for the allocation's lifetime.
        self.mapped
            .map(|p| unsafe { std::slice::from_raw_parts(p, self.size as usize) })
    }

    /// The mapped bytes for writing, when host-visible.
    pub(crate) fn mapped_mut(&mut self) -> Option<&mut [u8]> {
        // SAFETY: as `mapped`, and `&mut self` excludes other host access.
        self.mapped
            .map(|p| unsafe { std::slice::from_raw_parts_mut(p, self.size as usize) })
    }
}

impl Drop for Allocation {
    fn drop(&mut self) {
        // SAFETY: submissions are waited on before returning, so the GPU no longer uses the
        // buffer; null handles are ignored.
        unsafe { self.shared.device.destroy_buffer(self.buffer, None) };
        if let Some(memory) = self.memory.take() {
            self.shared.free(memory);
        }
    }
}

// SAFETY: the mapping is process memory valid from any thread; host writes need `&mut`.
unsafe impl Send for Allocation {}
// SAFETY: shared access only reads the mapping.
unsafe impl Sync for Allocation {}

/// A storage buffer in device memory (see the module comment for where it lives).
pub struct Buffer {
    pub(crate) allocation: Allocation,
    bytes: usize,
}

impl Buffer {
    /// A buffer holding a copy of `data`.
    pub fn from_slice<T: Pod>(context: &Context, data: &[T]) -> Result<Buffer, VulkanError> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let mut buffer = Buffer::uninitialised(context, bytes.len())?;
        buffer.write(data)?;
        Ok(buffer)
    }

    /// A zero-filled buffer of `bytes` bytes (at least 4 are allocated, Vulkan has no empty ones).
    pub fn zeroed(context: &Context, bytes: usize) -> Result<Buffer, VulkanError> {
        let mut buffer = Buffer::uninitialised(context, bytes)?;
        buffer.clear()?;
        Ok(buffer)
    }

    /// Sets every byte to 0.
    pub fn clear(&mut self) -> Result<(), VulkanError> {
        let raw = self.allocation.buffer;
        match self.allocation.mapped_mut() {
            Some(mapped) => {
                mapped.fill(0);
                Ok(())
            }
            None => self.allocation.shared.clone().one_shot(|device, cb| {
                // SAFETY: `cb` is recording; the buffer allows transfer writes.
                unsafe { device.cmd_fill_buffer(cb, raw, 0, vk::WHOLE_SIZE, 0) }
            }),
        }
    }

    fn uninitialised(context: &Context, bytes: usize) -> Result<Buffer, VulkanError> {
        if bytes as u64 > context.max_storage_range as u64 {
            return Err(VulkanError::BufferTooLarge {
                bytes: bytes as u64,
                limit: context.max_storage_range,
            });
        }
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER
            | vk::BufferUsageFlags::TRANSFER_SRC
            | vk::BufferUsageFlags::TRANSFER_DST;
        Ok(Buffer {
            allocation: Allocation::new(&context.shared, bytes as u64, usage, Placement::Device)?,
            bytes,
        })
    }

    /// Size in bytes as requested.
    pub fn bytes(&self) -> usize {
        self.bytes
    }

    /// Whether the buffer is mapped (no staging needed), e.g. on a CPU device.
    pub fn is_mapped(&self) -> bool {
        self.allocation.mapped.is_some()
    }

    /// Overwrites the buffer with `data`, which must be exactly [`Buffer::bytes`] long.
    pub fn write<T: Pod>(&mut self, data: &[T]) -> Result<(), VulkanError> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        if bytes.len() != self.bytes {
            return Err(VulkanError::Binding(format!(
                "writing {} bytes into a {}-byte buffer",
                bytes.len(),
                self.bytes
            )));
        }
        if let Some(mapped) = self.allocation.mapped_mut() {
            mapped[..bytes.len()].copy_from_slice(bytes);
            return Ok(());
        }
        let shared = self.allocation.shared.clone();
        let mut staging = Allocation::new(
            &shared,
            bytes.len() as u64,
            vk::BufferUsageFlags::TRANSFER_SRC,
            Placement::Host,
        )?;
        staging.mapped_mut().ok_or(VulkanError::NoMemoryType)?[..bytes.len()]
            .copy_from_slice(bytes);
        let (src, dst, size) = (staging.buffer, self.allocation.buffer, bytes.len().max(4));
        shared.one_shot(|device, cb| copy(device, cb, src, dst, size as u64))
    }

    /// The contents as `T`s; `Err` when the size is not a multiple of `size_of::<T>()`.
    pub fn read<T: Pod>(&self) -> Result<Vec<T>, VulkanError> {
        let size = size_of::<T>();
        if size == 0 || !self.bytes.is_multiple_of(size) {
            return Err(VulkanError::Binding(format!(
                "a {}-byte buffer is not a whole number of {size}-byte elements",
                self.bytes
            )));
        }
        let mut out = vec![T::zeroed(); self.bytes / size];
        let target = bytemuck::cast_slice_mut::<T, u8>(&mut out);
        if let Some(mapped) = self.allocation.mapped() {
            target.copy_from_slice(&mapped[..self.bytes]);
            return Ok(out);
        }
        let shared = &self.allocation.shared;
        let staging = Allocation::new(
            shared,
            self.bytes as u64,
            vk::BufferUsageFlags::TRANSFER_DST,
            Placement::Host,
        )?;
        let (src, dst) = (self.allocation.buffer, staging.buffer);
        shared.one_shot(|device, cb| copy(device, cb, src, dst, self.bytes.max(4) as u64))?;
        target.copy_from_slice(&staging.mapped().ok_or(VulkanError::NoMemoryType)?[..self.bytes]);
        Ok(out)
    }
}

/// Records a copy of `size` bytes from `src` to `dst`, ordered after earlier shader writes and
/// before later host reads and shader reads.
pub(crate) fn copy(
    device: &ash::Device,
    cb: vk::CommandBuffer,
    src: vk::Buffer,
    dst: vk::Buffer,
    size: u64,
) {
    let region = [vk::BufferCopy::default().size(size)];
    // SAFETY: `cb` is recording; both buffers are live and at least `size` bytes long.
    unsafe {
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
        device.cmd_copy_buffer(cb, src, dst, &region);
        barrier(
            device,
            cb,
            (
                vk::PipelineStageFlags::TRANSFER,
                vk::AccessFlags::TRANSFER_WRITE,
            ),
            (
                vk::PipelineStageFlags::HOST | vk::PipelineStageFlags::COMPUTE_SHADER,
                vk::AccessFlags::HOST_READ | vk::AccessFlags::SHADER_READ,
            ),
        );
    }
}

/// Records a global memory barrier from `(stage, access)` to `(stage, access)`.
///
/// # Safety
/// `cb` is a command buffer of `device` in the recording state.
pub(crate) unsafe fn barrier(
    device: &ash::Device,
    cb: vk::CommandBuffer,
    (src_stage, src_access): (vk::PipelineStageFlags, vk::AccessFlags),
    (dst_stage, dst_access): (vk::PipelineStageFlags, vk::AccessFlags),
) {
    let barrier = vk::MemoryBarrier::default()
        .src_access_mask(src_access)
        .dst_access_mask(dst_access);
    // SAFETY: as the function's contract.
    unsafe {
        device.cmd_pipeline_barrier(
            cb,
            src_stage,
            dst_stage,
            vk::DependencyFlags::empty(),
            &[barrier],
            &[],
            &[],
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use vk::MemoryPropertyFlags as F;

    /// A buffer whose mapping is dropped, so uploads and read-backs take the staging path of
    /// a discrete GPU even on a device whose memory is all host-visible (lavapipe).
    fn staged(context: &Context, bytes: usize) -> Buffer {
        let mut buffer = Buffer::uninitialised(context, bytes).unwrap();
        // The block stays mapped for its other buffers; this buffer just stops using it.
        buffer.allocation.mapped = None;
        buffer
    }

    /// The staging path round-trips data, clears, and rejects a wrong size; the same test on a
    /// mapped buffer is the control that both paths agree. Skips without Vulkan.
    #[test]
    fn staging_round_trip() {
        let context = match Context::new() {
            Ok(c) => c,
            Err(e) if std::env::var(super::super::REQUIRE_ENV).as_deref() == Ok("1") => {
                panic!("RESHIFT_REQUIRE_VULKAN=1 but Vulkan is unavailable: {e}")
            }
            Err(e) => return eprintln!("staging_round_trip: skipped, Vulkan unavailable: {e}"),
        };
        let data: Vec<u32> = (0..1001u32).map(|i| i.wrapping_mul(0x9e37_79b9)).collect();
        for mut buffer in [
            staged(&context, 4004),
            Buffer::zeroed(&context, 4004).unwrap(),
        ] {
            buffer.write(&data).unwrap();
            assert_eq!(buffer.read::<u32>().unwrap(), data);
            buffer.clear().unwrap();
            assert!(buffer.read::<u32>().unwrap().iter().all(|&w| w == 0));
            assert!(buffer.write(&data[1..]).is_err());
        }
        assert!(!staged(&context, 8).is_mapped());
    }

    fn properties(types: &[F]) -> vk::PhysicalDeviceMemoryProperties {
        let mut p = vk::PhysicalDeviceMemoryProperties {
            memory_type_count: types.len() as u32,
            ..Default::default()
        };
        for (i, &flags) in types.iter().enumerate() {
            p.memory_types[i].property_flags = flags;
        }
        p
    }

    /// A discrete GPU: pure device-local for storage, cached host memory for staging; a
    /// resizable-BAR type (device-local + host-visible) is the second choice, not the first.
    #[test]
    fn discrete_gpu_uses_device_local_and_cached_staging() {
        let host = F::HOST_VISIBLE | F::HOST_COHERENT;
        let p = properties(&[
            host,
            F::DEVICE_LOCAL | host,
            F::DEVICE_LOCAL,
            host | F::HOST_CACHED,
        ]);
        assert_eq!(memory_type(&p, !0, Placement::Device), Some(2));
        assert_eq!(memory_type(&p, !0, Placement::Host), Some(3));
        assert_eq!(memory_type(&p, 0b0011, Placement::Device), Some(1));
        assert_eq!(memory_type(&p, 0b0001, Placement::Host), Some(0));
        assert_eq!(memory_type(&p, 0b0100, Placement::Host), None);
    }

    /// Lavapipe reports one type that is device-local and host-visible: both placements take it
    /// (mapped, no staging); a device with only host memory still gets storage buffers.
    #[test]
    fn unified_and_host_only_devices_are_mapped() {
        let all = F::DEVICE_LOCAL | F::HOST_VISIBLE | F::HOST_COHERENT | F::HOST_CACHED;
        let p = properties(&[all]);
        assert_eq!(memory_type(&p, 1, Placement::Device), Some(0));
        assert_eq!(memory_type(&p, 1, Placement::Host), Some(0));
        let p = properties(&[F::HOST_VISIBLE | F::HOST_COHERENT]);
        assert_eq!(memory_type(&p, 1, Placement::Device), Some(0));
        let p = properties(&[F::HOST_VISIBLE]);
        assert_eq!(memory_type(&p, 1, Placement::Host), None, "not coherent");
    }
}
