//! Why the Vulkan backend cannot run: each variant prints as one line that says what to do.

use std::fmt;

use ash::vk;

/// A failure of the Vulkan backend.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum VulkanError {
    /// `libvulkan.so.1` (the Vulkan loader) could not be loaded.
    NoLoader(String),
    /// The loader found no driver (`vkCreateInstance` failed).
    NoDriver(vk::Result),
    /// Drivers exist, but no device offers a compute queue and 64-bit integers and floats.
    NoDevice { available: Vec<String> },
    /// No usable device's name contains the requested substring.
    NoMatchingDevice {
        wanted: String,
        available: Vec<String>,
    },
    /// `--require-gpu`: the chosen device is a CPU implementation (e.g. lavapipe).
    CpuDevice(String),
    /// The crate was built without `glslc`, so it has no SPIR-V.
    NoGlslc,
    /// A Vulkan call failed.
    Api {
        call: &'static str,
        result: vk::Result,
    },
    /// No host-visible, host-coherent memory type fits a buffer.
    NoMemoryType,
    /// A buffer is larger than the device's `maxStorageBufferRange`.
    BufferTooLarge { bytes: u64, limit: u32 },
    /// Buffers or push constants do not match what a kernel was created with.
    Binding(String),
    /// The embedded SPIR-V is not a valid word stream.
    InvalidSpirv(String),
    /// The device ended loops of `shader` early (lavapipe's per-group loop budget, see
    /// `restir/glsl/loop_budget.glsl`) for `count` pixels or samples; the results are void.
    LoopsCut { shader: &'static str, count: u64 },
    /// A BSSRDF probe of `shader` hit its object more often than the `kept` hits the shader
    /// stores (`BVH_MAX_HITS`), for `count` pixels; the CPU would use them all, so the results
    /// are void.
    TooManyHits {
        shader: &'static str,
        kept: u32,
        count: u64,
    },
    /// No `engine/glsl/<name>.glsl` was compiled into the crate.
    UnknownShader(String),
    /// Validation was requested but `VK_LAYER_KHRONOS_validation` is not installed.
    NoValidationLayer,
    /// The validation layer reported an error (an invalid use or a synchronization hazard):
    /// its id and message.
    Validation(String),
    /// The device-memory allocator (`gpu-allocator`) failed.
    Allocation(String),
    /// An environment setting of the backend has a value it does not know.
    BadSetting(String),
    /// The scene of file `file` has a moving object, `object`: the device renders scenes at
    /// rest (`sss::scene::motion`).
    MovingScene { file: String, object: String },
}

impl fmt::Display for VulkanError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::NoLoader(why) => write!(
                f,
                "the Vulkan loader libvulkan.so.1 was not found ({why}); install it \
                 (apt-get install libvulkan1 mesa-vulkan-drivers) or use the CPU backend"
            ),
            Self::NoDriver(result) => write!(
                f,
                "no Vulkan driver is installed (vkCreateInstance: {result}); install a GPU \
                 driver or Mesa's CPU device (apt-get install mesa-vulkan-drivers)"
            ),
            Self::NoDevice { available } => write!(
                f,
                "no Vulkan device has a compute queue, shaderInt64 and shaderFloat64 (devices: {})",
                list(available)
            ),
            Self::NoMatchingDevice { wanted, available } => write!(
                f,
                "no usable Vulkan device name contains \"{wanted}\" (RESHIFT_VULKAN_DEVICE); \
                 devices: {}",
                list(available)
            ),
            Self::CpuDevice(name) => write!(
                f,
                "the Vulkan device \"{name}\" is a CPU implementation and a GPU was required \
                 (--require-gpu); choose another with --device or RESHIFT_VULKAN_DEVICE"
            ),
            Self::NoGlslc => write!(
                f,
                "glslc was not found at build time; install it (apt-get install glslc) and rebuild"
            ),
            Self::Api { call, result } => write!(f, "Vulkan call {call} failed: {result}"),
            Self::NoMemoryType => write!(
                f,
                "the Vulkan device has no host-visible, host-coherent memory for storage buffers"
            ),
            Self::BufferTooLarge { bytes, limit } => write!(
                f,
                "a {bytes}-byte storage buffer exceeds the device's maxStorageBufferRange ({limit})"
            ),
            Self::Binding(why) => write!(f, "kernel binding mismatch: {why}"),
            Self::InvalidSpirv(why) => write!(f, "invalid embedded SPIR-V: {why}"),
            Self::LoopsCut { shader, count } => write!(
                f,
                "the Vulkan device cut loops of {shader} short for {count} pixels or samples \
                 (lavapipe ends all loops of a group after 65 535 iterations); the result is \
                 void: use a GPU, fewer samples per call or a smaller scene"
            ),
            Self::TooManyHits {
                shader,
                kept,
                count,
            } => write!(
                f,
                "{count} pixels of {shader} had a BSSRDF probe with more than {kept} hits, which \
                 the Vulkan backend does not keep (raise BVH_MAX_HITS there); use the CPU backend"
            ),
            Self::UnknownShader(name) => write!(
                f,
                "no compiled shader named {name:?} (engine/glsl/{name}.glsl is missing)"
            ),
            Self::NoValidationLayer => write!(
                f,
                "Vulkan validation was requested (RESHIFT_VULKAN_VALIDATION) but the layer \
                 VK_LAYER_KHRONOS_validation is not installed (apt-get install vulkan-validationlayers)"
            ),
            Self::Validation(message) => write!(f, "Vulkan validation error: {message}"),
            Self::Allocation(why) => write!(f, "allocating Vulkan device memory failed: {why}"),
            Self::BadSetting(why) => write!(f, "{why}"),
            Self::MovingScene { file, object } => write!(
                f,
                "{file}: object {object:?} moves, and the Vulkan backend renders only scenes at \
                 rest (run it with --backend cpu)"
            ),
        }
    }
}

impl std::error::Error for VulkanError {}

fn list(names: &[String]) -> String {
    if names.is_empty() {
        "none".into()
    } else {
        names.join(", ")
    }
}

/// Maps a failed Vulkan call to [`VulkanError::Api`].
pub(crate) fn api(call: &'static str) -> impl FnOnce(vk::Result) -> VulkanError {
    move |result| VulkanError::Api { call, result }
}
