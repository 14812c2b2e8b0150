//! Loading Vulkan at run time, choosing a device, and the [`Context`] every kernel runs in.
//!
//! Choice: a device needs a compute queue, `shaderInt64` (the stream RNG is 64-bit) and
//! `shaderFloat64` (the watertight triangle test's exact fallback); among
//! those a discrete GPU wins, then integrated, virtual, CPU (Mesa lavapipe) and other devices,
//! ties to the lower index. `RESHIFT_VULKAN_DEVICE=<substring>` (case-insensitive, of the device
//! name) restricts the choice.

use std::sync::{Arc, Mutex, MutexGuard};

use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, Allocator, AllocatorCreateDesc};

use super::error::{VulkanError, api};
use super::validation::{self, Checks, Message, Validation};

/// The environment variable that restricts the device choice to names containing its value.
pub const DEVICE_ENV: &str = "RESHIFT_VULKAN_DEVICE";

/// What kind of implementation a device is, in order of preference.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum DeviceKind {
    DiscreteGpu,
    IntegratedGpu,
    VirtualGpu,
    Cpu,
    Other,
}

impl DeviceKind {
    fn from_vk(kind: vk::PhysicalDeviceType) -> DeviceKind {
        match kind {
            vk::PhysicalDeviceType::DISCRETE_GPU => DeviceKind::DiscreteGpu,
            vk::PhysicalDeviceType::INTEGRATED_GPU => DeviceKind::IntegratedGpu,
            vk::PhysicalDeviceType::VIRTUAL_GPU => DeviceKind::VirtualGpu,
            vk::PhysicalDeviceType::CPU => DeviceKind::Cpu,
            _ => DeviceKind::Other,
        }
    }
}

/// One physical device as the selection sees it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DeviceInfo {
    pub name: String,
    pub kind: DeviceKind,
    /// A queue family with compute, if any.
    pub compute_family: Option<u32>,
    pub shader_int64: bool,
    pub shader_float64: bool,
}

impl DeviceInfo {
    fn usable(&self) -> bool {
        self.compute_family.is_some() && self.shader_int64 && self.shader_float64
    }
}

/// The chosen device's identity, driver and the limits that bound the backend (what
/// `reshift gpu-report` prints).
#[derive(Clone, Debug, PartialEq)]
pub struct DeviceDetails {
    /// The Vulkan version the device supports, `major.minor.patch`.
    pub api_version: String,
    /// The driver's name and information string (Vulkan 1.2 driver properties), when known.
    pub driver: Option<String>,
    /// The vendor-specific driver version, raw.
    pub driver_version: u32,
    pub vendor_id: u32,
    pub device_id: u32,
    pub max_storage_buffer_range: u32,
    pub max_compute_work_group_invocations: u32,
    pub max_compute_shared_memory_size: u32,
    pub max_push_constants_size: u32,
    /// Nanoseconds per timestamp tick.
    pub timestamp_period: f32,
    /// Valid bits of the compute queue's timestamps (0: none).
    pub timestamp_valid_bits: u32,
    /// The sum of the device-local memory heaps, bytes.
    pub device_local_bytes: u64,
}

/// The index of the device to use: usable devices whose name contains `wanted`
/// (case-insensitive; `None` or empty = any), best [`DeviceKind`] first, then lowest index.
pub fn choose_device(devices: &[DeviceInfo], wanted: Option<&str>) -> Result<usize, VulkanError> {
    let wanted = wanted.map(str::trim).filter(|w| !w.is_empty());
    let matches =
        |d: &DeviceInfo| wanted.is_none_or(|w| d.name.to_lowercase().contains(&w.to_lowercase()));
    let best = devices
        .iter()
        .enumerate()
        .filter(|(_, d)| d.usable() && matches(d))
        .min_by_key(|(i, d)| (d.kind, *i))
        .map(|(i, _)| i);
    best.ok_or_else(|| {
        let available = devices.iter().map(|d| d.name.clone()).collect();
        match wanted {
            Some(w) => VulkanError::NoMatchingDevice {
                wanted: w.to_string(),
                available,
            },
            None => VulkanError::NoDevice { available },
        }
    })
}

/// The instance and device, destroyed when the last [`Context`], buffer or kernel is dropped.
pub(crate) struct Shared {
    pub(crate) instance: ash::Instance,
    pub(crate) device: ash::Device,
    pub(crate) memory: vk::PhysicalDeviceMemoryProperties,
    /// The compute queue and the command pool: Vulkan requires external synchronisation of
    /// both, so they are used only while this lock is held.
    pub(crate) submit: Mutex<Submit>,
    /// The device-memory allocator (taken in `drop`, before the device is destroyed).
    allocator: Mutex<Option<Allocator>>,
    /// The validation layer's messenger and messages, when validation was requested.
    validation: Option<Validation>,
    /// Keeps libvulkan loaded until the instance is destroyed (fields drop after `drop`).
    _entry: ash::Entry,
}

/// What [`Shared::submit`] guards.
pub(crate) struct Submit {
    pub(crate) queue: vk::Queue,
    pub(crate) command_pool: vk::CommandPool,
}

impl Shared {
    /// The lock on the queue and command pool (a poisoned lock still guards valid handles).
    pub(crate) fn lock(&self) -> MutexGuard<'_, Submit> {
        self.submit.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Records `record` into a fresh command buffer, submits it and waits for it.
    pub(crate) fn one_shot(
        &self,
        record: impl FnOnce(&ash::Device, vk::CommandBuffer),
    ) -> Result<(), VulkanError> {
        let submit = self.lock();
        let device = &self.device;
        // SAFETY: the command buffer and fence are created here, used while the queue lock is
        // held, waited on, and freed before returning.
        unsafe {
            let cb = device
                .allocate_command_buffers(
                    &vk::CommandBufferAllocateInfo::default()
                        .command_pool(submit.command_pool)
                        .level(vk::CommandBufferLevel::PRIMARY)
                        .command_buffer_count(1),
                )
                .map_err(api("vkAllocateCommandBuffers"))?[0];
            let result = (|| {
                device
                    .begin_command_buffer(
                        cb,
                        &vk::CommandBufferBeginInfo::default()
                            .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
                    )
                    .map_err(api("vkBeginCommandBuffer"))?;
                record(device, cb);
                device
                    .end_command_buffer(cb)
                    .map_err(api("vkEndCommandBuffer"))?;
                self.submit_and_wait(submit.queue, cb)
            })();
            device.free_command_buffers(submit.command_pool, &[cb]);
            result
        }
    }

    /// Submits `cb` to `queue`, waits for it with a fence of its own, and reports the first
    /// validation error of its recording or execution, if validation is on.
    ///
    /// # Safety
    /// `cb` is a recorded command buffer of the device and the caller holds the queue lock.
    pub(crate) unsafe fn submit_and_wait(
        &self,
        queue: vk::Queue,
        cb: vk::CommandBuffer,
    ) -> Result<(), VulkanError> {
        let device = &self.device;
        // SAFETY: the fence is destroyed after the wait (or the failed submit).
        unsafe {
            let fence = device
                .create_fence(&vk::FenceCreateInfo::default(), None)
                .map_err(api("vkCreateFence"))?;
            let command_buffers = [cb];
            let submit = vk::SubmitInfo::default().command_buffers(&command_buffers);
            let result = device
                .queue_submit(queue, &[submit], fence)
                .map_err(api("vkQueueSubmit"))
                .and_then(|()| {
                    device
                        .wait_for_fences(&[fence], true, u64::MAX)
                        .map_err(api("vkWaitForFences"))
                });
            device.destroy_fence(fence, None);
            result?;
        }
        self.check_validation()
    }

    /// A range of device memory for `desc` from the allocator's blocks.
    pub(crate) fn allocate(&self, desc: &AllocationCreateDesc) -> Result<Allocation, VulkanError> {
        let mut allocator = self.allocator.lock().unwrap_or_else(|e| e.into_inner());
        let allocator = allocator
            .as_mut()
            .expect("the allocator lives until `drop`");
        allocator
            .allocate(desc)
            .map_err(|e| VulkanError::Allocation(e.to_string()))
    }

    /// Returns `allocation` to the allocator (its buffer is destroyed and unused by the GPU).
    pub(crate) fn free(&self, allocation: Allocation) {
        let mut allocator = self.allocator.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(allocator) = allocator.as_mut() {
            // Freeing fails only for an allocation of another allocator; there is one.
            let _ = allocator.free(allocation);
        }
    }

    /// `Err` naming the first validation error since the last check (none without validation).
    pub(crate) fn check_validation(&self) -> Result<(), VulkanError> {
        self.validation.as_ref().map_or(Ok(()), Validation::check)
    }
}

impl Drop for Shared {
    fn drop(&mut self) {
        let pool = self.lock().command_pool;
        // Frees the memory blocks while the device lives.
        drop(
            self.allocator
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .take(),
        );
        // SAFETY: every object created from the device holds an `Arc<Shared>`, so none is alive.
        unsafe {
            let _ = self.device.device_wait_idle();
            self.device.destroy_command_pool(pool, None);
            self.device.destroy_device(None);
            if let Some(validation) = &self.validation {
                validation.destroy();
            }
            self.instance.destroy_instance(None);
        }
    }
}

/// A Vulkan device with one compute queue: the place buffers live and kernels run.
pub struct Context {
    pub(crate) shared: Arc<Shared>,
    pub(crate) max_storage_range: u32,
    /// Nanoseconds per timestamp tick, when the queue writes timestamps.
    pub(crate) timestamp_period: Option<f64>,
    info: DeviceInfo,
    details: DeviceDetails,
}

impl Context {
    /// Loads Vulkan and opens the preferred device, honouring [`DEVICE_ENV`] and
    /// [`validation::VALIDATION_ENV`].
    pub fn new() -> Result<Context, VulkanError> {
        let wanted = std::env::var(DEVICE_ENV).ok();
        Context::with_device(wanted.as_deref())
    }

    /// Loads Vulkan and opens the best usable device whose name contains `wanted`, with the
    /// validation [`validation::VALIDATION_ENV`] asks for.
    pub fn with_device(wanted: Option<&str>) -> Result<Context, VulkanError> {
        Context::with_validation(wanted, Checks::from_env()?)
    }

    /// As [`Context::with_device`], with the validation layer running `checks`.
    pub fn with_validation(wanted: Option<&str>, checks: Checks) -> Result<Context, VulkanError> {
        // SAFETY: loading libvulkan runs its initialisers; it is the system's Vulkan loader.
        let entry =
            unsafe { ash::Entry::load() }.map_err(|e| VulkanError::NoLoader(e.to_string()))?;
        let app = vk::ApplicationInfo::default()
            .application_name(c"reshift")
            .api_version(vk::API_VERSION_1_2);
        let (layers, extensions) = validation::requirements(&entry, checks)?;
        let mut features = validation::features(checks);
        let create = vk::InstanceCreateInfo::default()
            .application_info(&app)
            .enabled_layer_names(&layers)
            .enabled_extension_names(&extensions);
        let create = if checks == Checks::Off {
            create
        } else {
            create.push_next(&mut features)
        };
        // SAFETY: valid create info; the instance is destroyed by `Shared` or below.
        let instance =
            unsafe { entry.create_instance(&create, None) }.map_err(VulkanError::NoDriver)?;
        let validation = match checks {
            Checks::Off => None,
            _ => match Validation::new(&entry, &instance) {
                Ok(validation) => Some(validation),
                Err(e) => {
                    // SAFETY: nothing else was created from the instance.
                    unsafe { instance.destroy_instance(None) };
                    return Err(e);
                }
            },
        };
        match open_device(&instance, wanted) {
            Ok((physical, device, info)) => {
                Context::assemble(entry, instance, validation, physical, device, info)
            }
            Err(e) => {
                // SAFETY: nothing but the messenger was created from the instance.
                unsafe {
                    if let Some(validation) = &validation {
                        validation.destroy();
                    }
                    instance.destroy_instance(None);
                }
                Err(e)
            }
        }
    }

    fn assemble(
        entry: ash::Entry,
        instance: ash::Instance,
        validation: Option<Validation>,
        physical: vk::PhysicalDevice,
        device: ash::Device,
        info: DeviceInfo,
    ) -> Result<Context, VulkanError> {
        let family = info
            .compute_family
            .expect("chosen devices have a compute queue");
        // SAFETY: `physical` belongs to `instance`, `device` was created with this family.
        let (properties, families, memory, queue) = unsafe {
            (
                instance.get_physical_device_properties(physical),
                instance.get_physical_device_queue_family_properties(physical),
                instance.get_physical_device_memory_properties(physical),
                device.get_device_queue(family, 0),
            )
        };
        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(family)
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
        // SAFETY: valid create info on a live device.
        let command_pool = match unsafe { device.create_command_pool(&pool_info, None) } {
            Ok(pool) => pool,
            Err(result) => {
                // SAFETY: nothing else was created from the device.
                unsafe {
                    device.destroy_device(None);
                    if let Some(validation) = &validation {
                        validation.destroy();
                    }
                    instance.destroy_instance(None);
                }
                return Err(api("vkCreateCommandPool")(result));
            }
        };
        let allocator = Allocator::new(&AllocatorCreateDesc {
            instance: instance.clone(),
            device: device.clone(),
            physical_device: physical,
            debug_settings: Default::default(),
            buffer_device_address: false,
            allocation_sizes: Default::default(),
        });
        let allocator = match allocator {
            Ok(allocator) => allocator,
            Err(e) => {
                // SAFETY: nothing but the command pool was created from the device.
                unsafe {
                    device.destroy_command_pool(command_pool, None);
                    device.destroy_device(None);
                    if let Some(validation) = &validation {
                        validation.destroy();
                    }
                    instance.destroy_instance(None);
                }
                return Err(VulkanError::Allocation(e.to_string()));
            }
        };
        let details = details(
            &instance,
            physical,
            &properties,
            &memory,
            &families[family as usize],
        );
        let timestamps = families[family as usize].timestamp_valid_bits > 0
            && properties.limits.timestamp_period > 0.0;
        Ok(Context {
            shared: Arc::new(Shared {
                instance,
                device,
                memory,
                submit: Mutex::new(Submit {
                    queue,
                    command_pool,
                }),
                allocator: Mutex::new(Some(allocator)),
                validation,
                _entry: entry,
            }),
            max_storage_range: properties.limits.max_storage_buffer_range,
            timestamp_period: timestamps.then_some(properties.limits.timestamp_period as f64),
            info,
            details,
        })
    }

    /// The chosen device.
    pub fn device(&self) -> &DeviceInfo {
        &self.info
    }

    /// The chosen device's driver and limits.
    pub fn details(&self) -> &DeviceDetails {
        &self.details
    }

    /// Every warning and error the validation layer reported so far (none without validation).
    pub fn validation_messages(&self) -> Vec<Message> {
        self.shared
            .validation
            .as_ref()
            .map_or_else(Vec::new, Validation::messages)
    }

    /// Whether GPU times of dispatches are measured (timestamp queries on the compute queue).
    pub fn has_timestamps(&self) -> bool {
        self.timestamp_period.is_some()
    }
}

/// Describes every physical device, chooses one, and creates its logical device.
fn open_device(
    instance: &ash::Instance,
    wanted: Option<&str>,
) -> Result<(vk::PhysicalDevice, ash::Device, DeviceInfo), VulkanError> {
    // SAFETY: a live instance.
    let physicals = unsafe { instance.enumerate_physical_devices() }
        .map_err(api("vkEnumeratePhysicalDevices"))?;
    let infos: Vec<DeviceInfo> = physicals
        .iter()
        .map(|&physical| describe(instance, physical))
        .collect();
    let index = choose_device(&infos, wanted)?;
    let info = infos[index].clone();
    let family = info
        .compute_family
        .expect("usable devices have a compute queue");
    let priorities = [1.0f32];
    let queues = [vk::DeviceQueueCreateInfo::default()
        .queue_family_index(family)
        .queue_priorities(&priorities)];
    let features = vk::PhysicalDeviceFeatures::default()
        .shader_int64(true)
        .shader_float64(true);
    let create = vk::DeviceCreateInfo::default()
        .queue_create_infos(&queues)
        .enabled_features(&features);
    // SAFETY: the device supports the family and the features (checked by `choose_device`).
    let device = unsafe { instance.create_device(physicals[index], &create, None) }
        .map_err(api("vkCreateDevice"))?;
    Ok((physicals[index], device, info))
}

fn details(
    instance: &ash::Instance,
    physical: vk::PhysicalDevice,
    properties: &vk::PhysicalDeviceProperties,
    memory: &vk::PhysicalDeviceMemoryProperties,
    family: &vk::QueueFamilyProperties,
) -> DeviceDetails {
    let v = properties.api_version;
    let driver = (v >= vk::API_VERSION_1_2).then(|| {
        let mut driver = vk::PhysicalDeviceDriverProperties::default();
        let mut all = vk::PhysicalDeviceProperties2::default().push_next(&mut driver);
        // SAFETY: `physical` belongs to `instance`, which supports Vulkan 1.2 (as the device).
        unsafe { instance.get_physical_device_properties2(physical, &mut all) };
        let text = |s: Result<&std::ffi::CStr, _>| {
            s.map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default()
        };
        format!(
            "{} ({})",
            text(driver.driver_name_as_c_str()),
            text(driver.driver_info_as_c_str())
        )
    });
    let limits = &properties.limits;
    DeviceDetails {
        api_version: format!(
            "{}.{}.{}",
            vk::api_version_major(v),
            vk::api_version_minor(v),
            vk::api_version_patch(v)
        ),
        driver,
        driver_version: properties.driver_version,
        vendor_id: properties.vendor_id,
        device_id: properties.device_id,
        max_storage_buffer_range: limits.max_storage_buffer_range,
        max_compute_work_group_invocations: limits.max_compute_work_group_invocations,
        max_compute_shared_memory_size: limits.max_compute_shared_memory_size,
        max_push_constants_size: limits.max_push_constants_size,
        timestamp_period: limits.timestamp_period,
        timestamp_valid_bits: family.timestamp_valid_bits,
        device_local_bytes: memory.memory_heaps[..memory.memory_heap_count as usize]
            .iter()
            .filter(|h| h.flags.contains(vk::MemoryHeapFlags::DEVICE_LOCAL))
            .map(|h| h.size)
            .sum(),
    }
}

fn describe(instance: &ash::Instance, physical: vk::PhysicalDevice) -> DeviceInfo {
    // SAFETY: `physical` was enumerated from `instance`.
    let (properties, features, families) = unsafe {
        (
            instance.get_physical_device_properties(physical),
            instance.get_physical_device_features(physical),
            instance.get_physical_device_queue_family_properties(physical),
        )
    };
    let name = properties
        .device_name_as_c_str()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|_| "<unnamed device>".into());
    let compute_family = families
        .iter()
        .position(|f| f.queue_flags.contains(vk::QueueFlags::COMPUTE))
        .map(|i| i as u32);
    DeviceInfo {
        name,
        kind: DeviceKind::from_vk(properties.device_type),
        compute_family,
        shader_int64: features.shader_int64 == vk::TRUE,
        shader_float64: features.shader_float64 == vk::TRUE,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn device(name: &str, kind: DeviceKind) -> DeviceInfo {
        DeviceInfo {
            name: name.into(),
            kind,
            compute_family: Some(0),
            shader_int64: true,
            shader_float64: true,
        }
    }

    #[test]
    fn discrete_gpu_preferred_then_cpu_fallback() {
        let lavapipe = device("llvmpipe (LLVM 15.0.6, 256 bits)", DeviceKind::Cpu);
        let nvidia = device("NVIDIA H100 80GB HBM3", DeviceKind::DiscreteGpu);
        let intel = device("Intel(R) UHD Graphics", DeviceKind::IntegratedGpu);
        let all = [lavapipe.clone(), intel.clone(), nvidia];
        assert_eq!(choose_device(&all, None), Ok(2));
        assert_eq!(choose_device(&all[..2], None), Ok(1));
        assert_eq!(choose_device(&all[..1], None), Ok(0));
        // A device without 64-bit integers, 64-bit floats or compute is never chosen.
        let no_int64 = DeviceInfo {
            shader_int64: false,
            ..device("old gpu", DeviceKind::DiscreteGpu)
        };
        let no_compute = DeviceInfo {
            compute_family: None,
            ..device("display only", DeviceKind::DiscreteGpu)
        };
        assert_eq!(
            choose_device(&[no_int64, no_compute, lavapipe], None),
            Ok(2)
        );
    }

    #[test]
    fn substring_override_and_its_errors() {
        let all = [
            device("NVIDIA GeForce RTX 3070", DeviceKind::DiscreteGpu),
            device("llvmpipe (LLVM 15.0.6, 256 bits)", DeviceKind::Cpu),
        ];
        assert_eq!(choose_device(&all, Some("LLVMPIPE")), Ok(1));
        assert_eq!(
            choose_device(&all, Some("  ")),
            Ok(0),
            "blank = no preference"
        );
        let err = choose_device(&all, Some("radeon")).unwrap_err();
        assert!(matches!(err, VulkanError::NoMatchingDevice { .. }));
        let line = err.to_string();
        assert!(
            line.contains("radeon") && line.contains("RTX 3070") && !line.contains('\n'),
            "{line}"
        );
        assert!(matches!(
            choose_device(&[], None),
            Err(VulkanError::NoDevice { .. })
        ));
    }
}
