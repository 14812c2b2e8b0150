//! Where runs execute (DESIGN §6): the CPU reference implementation or a Vulkan device. Both
//! take the same `(scene, preset, seed, frames)` and return the same [`Run`]; a Vulkan backend
//! keeps one [`Renderer`] (device, compiled kernels, uploaded scene) for all the runs it does.

use std::fmt;
use std::sync::{Arc, Mutex, MutexGuard};

use sss::scene::Scene;

use crate::stream::{Keep, Stream};
use crate::vulkan::{Context, DeviceInfo, DeviceKind, GBUFFER, Renderer, VulkanError};
use crate::{PipelineError, Preset, Run, RunConfig};

/// The backend of a run. Cloning a Vulkan backend shares its renderer.
#[derive(Clone, Default)]
pub enum Backend {
    /// The deterministic rayon implementation.
    #[default]
    Cpu,
    /// A Vulkan device.
    Vulkan(Arc<Mutex<Renderer>>),
}

impl Backend {
    /// A Vulkan backend on the best device whose name contains `device` (`None`: honour
    /// `RESHIFT_VULKAN_DEVICE`). With `require_gpu`, a CPU implementation (lavapipe) is an
    /// error rather than a silent fallback.
    pub fn vulkan(device: Option<&str>, require_gpu: bool) -> Result<Backend, VulkanError> {
        // A build without glslc has no kernels: say so before looking for a device.
        GBUFFER.spirv()?;
        let context = match device {
            Some(wanted) => Context::with_device(Some(wanted))?,
            None => Context::new()?,
        };
        if require_gpu && context.device().kind == DeviceKind::Cpu {
            return Err(VulkanError::CpuDevice(context.device().name.clone()));
        }
        Ok(Backend::Vulkan(Arc::new(Mutex::new(Renderer::new(
            context,
        )))))
    }

    /// The Vulkan device, if any.
    pub fn device(&self) -> Option<DeviceInfo> {
        match self {
            Backend::Cpu => None,
            Backend::Vulkan(_) => self.renderer().map(|r| r.context().device().clone()),
        }
    }

    /// The renderer of a Vulkan backend, locked (a poisoned lock still holds a valid
    /// renderer: runs leave no partial state behind).
    pub fn renderer(&self) -> Option<MutexGuard<'_, Renderer>> {
        match self {
            Backend::Cpu => None,
            Backend::Vulkan(r) => Some(r.lock().unwrap_or_else(|e| e.into_inner())),
        }
    }

    /// Renders `config.frames` frames of `scene`'s camera trajectory with `preset`: a loop over
    /// a [`Stream`] that keeps every frame. The resolution is the scene camera's (set it with
    /// `Camera::with_resolution`).
    pub fn run(
        &self,
        scene: &Scene,
        preset: &Preset,
        config: &RunConfig,
    ) -> Result<Run, PipelineError> {
        preset.validate()?;
        if config.frames == 0 {
            return Err(PipelineError::Config("frames = 0; need at least 1".into()));
        }
        Stream::new(self, scene, preset, config)?.run(config.frames, Keep::Every)
    }
}

impl fmt::Display for Backend {
    /// `cpu`, or `vulkan (<device name>)`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.device() {
            None => f.write_str("cpu"),
            Some(device) => write!(f, "vulkan ({})", device.name),
        }
    }
}

impl fmt::Debug for Backend {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Display::fmt(self, f)
    }
}
