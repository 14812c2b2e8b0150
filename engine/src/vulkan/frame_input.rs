//! The path-tracer method (`method_pt.glsl`, twin of `sss::integrator::pt::render`) and the shade
//! pass (`pass_shade.glsl`, twin of the CPU backend's `shade`) on the device: dispatch over one
//! frame's G-buffer and read back an [`Image`].

use glam::Vec3;

use sss::integrator::pt::HitPolicy;
use sss::scene::Scene;

use super::{
    Buffer, Context, GpuPixel, GpuScene, Kernel, PassParams, Shader, VulkanError, groups_for,
};
use crate::contract::{PtHits, PtParams, PtState};
use crate::image::Image;
use crate::plan::PassKernel;

/// `method_pt.glsl`: scene bindings 0–8, 9 G-buffer (`GpuPixel`), 10 `vec4` out (mean of `spp`
/// samples, `w` = samples left out, see [`DeviceImage`]), 11 the per-pixel running sum between
/// its dispatches (one per sample). Push constants: [`PtParams`].
pub const PT: Shader = Shader::new("method_pt", 12, 32);
/// `pass_shade.glsl` ([`PassKernel::Shade`]): `f(Y)·W` or one path-traced sample, `w` = 1 where the
/// value was written as 0 (see [`DeviceImage`]). Of its [`PassParams`] only `pass` is read.
pub const SHADE: Shader = Shader::of(PassKernel::Shade);

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

/// An image read back from the device, and how many samples (`method_pt`) or pixels
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

/// The `pt:spp` method on one frame: per pixel the mean of samples `0..spp` with every probe hit
/// (`PtSettings::default()`, the kernel of [`PT`]).
pub fn render_pt(
    context: &mut Context,
    kernel: &Kernel,
    frame: &FrameInput,
    spp: u32,
) -> Result<DeviceImage, VulkanError> {
    render_pt_hits(context, kernel, frame, spp, HitPolicy::All)
}

/// [`render_pt`] with the probe hits chosen by `hits`.
pub fn render_pt_hits(
    context: &mut Context,
    kernel: &Kernel,
    frame: &FrameInput,
    spp: u32,
    hits: HitPolicy,
) -> Result<DeviceImage, VulkanError> {
    let hits = match hits {
        HitPolicy::UniformOne => PtHits::UniformOne,
        HitPolicy::All => PtHits::All,
    }
    .code();
    let count = frame.width * frame.height;
    let output = Buffer::zeroed(context, count as usize * 16)?;
    let state = Buffer::zeroed(context, count as usize * size_of::<PtState>())?;
    let buffers = frame.bindings(&[&output, &state])?;
    for sample_index in 0..spp {
        let params = PtParams {
            spp,
            hits,
            sample_index,
            pad: [0; 5],
        };
        context.dispatch(
            kernel,
            &buffers,
            bytemuck::bytes_of(&params),
            [groups_for(count, PT.local_size), 1, 1],
        )?;
    }
    let cut: u64 = state
        .read::<PtState>()?
        .iter()
        .map(|s| u64::from(s.cut))
        .sum();
    if cut > 0 {
        return Err(VulkanError::LoopsCut {
            shader: PT.name,
            count: cut,
        });
    }
    frame.read_image(&output)
}
/// The shade pass on one frame with selected shading: `f(Y)·W` of `reservoirs`
/// (`PixelReservoir`s) on translucent pixels, one path-traced sample elsewhere, keyed by `pass`
/// (the kernel of [`SHADE`]).
pub fn shade(
    context: &mut Context,
    kernel: &Kernel,
    frame: &FrameInput,
    reservoirs: &Buffer,
    pass: u32,
) -> Result<DeviceImage, VulkanError> {
    let count = frame.width * frame.height;
    let output = Buffer::zeroed(context, count as usize * 16)?;
    // Selected shading reads no Rao-Blackwellised value: one texel stands in for the buffer.
    let unread = Buffer::zeroed(context, 16)?;
    let buffers = frame.bindings(&[reservoirs, &output, &unread])?;
    let params = PassParams::new(pass, None, false);
    context.dispatch(
        kernel,
        &buffers,
        bytemuck::bytes_of(&params),
        [groups_for(count, SHADE.local_size), 1, 1],
    )?;
    frame.read_image(&output)
}
#[cfg(test)]
mod tests {
    use super::*;
    use crate::contract::MethodParams;

    #[test]
    fn push_constants_are_32_bytes() {
        assert_eq!(size_of::<MethodParams>() as u32, PT.push_bytes);
        assert_eq!(size_of::<PtParams>() as u32, PT.push_bytes);
        assert_eq!(std::mem::offset_of!(PtParams, hits), 4);
        assert_eq!(std::mem::offset_of!(PtParams, sample_index), 8);
        assert_eq!(size_of::<PtState>(), 32);
        assert_eq!(std::mem::offset_of!(PtState, cut), 28);
        assert_eq!(size_of::<PassParams>() as u32, SHADE.push_bytes);
    }
}
