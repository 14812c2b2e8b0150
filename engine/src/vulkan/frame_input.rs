//! What a per-pixel kernel of one frame reads and writes: its input ([`FrameInput`]: the
//! uploaded scene, the frame's `FrameParams` and G-buffer, and the kernel's own buffers after
//! them) and the image it writes back ([`DeviceImage`]). The shade pass ([`shade`](super::shade))
//! and the methods' kernels (`methods/src/<folder>/vulkan.rs`) dispatch through it.

use glam::Vec3;

use sss::scene::Scene;

use super::{Buffer, GpuPixel, GpuScene, VulkanError};
use crate::image::Image;

/// What a per-pixel kernel of one frame reads: the uploaded scene, the frame's `FrameParams`
/// buffer (binding 8) and its G-buffer (binding 9, `width × height` `GpuPixel`s).
pub struct FrameInput<'a> {
    pub scene: &'a GpuScene,
    pub params: &'a Buffer,
    pub gbuffer: &'a Buffer,
    pub width: u32,
    pub height: u32,
}

impl<'a> FrameInput<'a> {
    /// The input of a frame of `scene` at its camera's resolution.
    pub fn new(
        scene: &Scene,
        gpu: &'a GpuScene,
        params: &'a Buffer,
        gbuffer: &'a Buffer,
    ) -> FrameInput<'a> {
        FrameInput {
            scene: gpu,
            params,
            gbuffer,
            width: scene.camera.width(),
            height: scene.camera.height(),
        }
    }
}

/// An image read back from the device, and how many samples (a method's kernel) or pixels
/// (`pass_shade`) were left out of a mean or written as 0: NaN or infinite values, as on the CPU,
/// and path-traced samples whose probe had more than [`KEPT_HITS`](crate::contract::KEPT_HITS)
/// hits.
#[derive(Clone, Debug, PartialEq)]
pub struct DeviceImage {
    pub image: Image,
    pub left_out: u64,
}

impl<'a> FrameInput<'a> {
    /// The frame's bindings (scene, `FrameParams`, G-buffer) followed by `extra`, after checking
    /// that the G-buffer covers the frame: the buffers of a per-pixel kernel's dispatch.
    pub fn bindings(&self, extra: &[&'a Buffer]) -> Result<Vec<&'a Buffer>, VulkanError> {
        let frame = self;
        let count = frame.width as usize * frame.height as usize;
        let pixel_bytes = size_of::<GpuPixel>();
        if frame.gbuffer.bytes() < count * pixel_bytes {
            return Err(VulkanError::Binding(format!(
                "G-buffer of {} bytes for {}×{} pixels of {pixel_bytes} bytes",
                frame.gbuffer.bytes(),
                frame.width,
                frame.height
            )));
        }
        let mut buffers: Vec<&Buffer> = frame.scene.buffers().to_vec();
        buffers.push(frame.params);
        buffers.push(frame.gbuffer);
        buffers.extend_from_slice(extra);
        Ok(buffers)
    }

    /// Reads a per-pixel `vec4` output back as the frame's image and the count of its texels with
    /// `w ≠ 0` summed.
    pub fn read_image(&self, output: &Buffer) -> Result<DeviceImage, VulkanError> {
        let texels = output.read::<[f32; 4]>()?;
        Ok(DeviceImage {
            image: Image {
                width: self.width,
                height: self.height,
                pixels: texels.iter().map(|t| Vec3::new(t[0], t[1], t[2])).collect(),
            },
            left_out: texels.iter().map(|t| t[3] as u64).sum(),
        })
    }
}
