//! The path-tracer method (`method_pt.glsl`, twin of `sss::integrator::pt::render`) and the shade
//! pass (`pass_shade.glsl`, twin of the CPU backend's `shade`) on the device: dispatch over one
//! frame's G-buffer and read back an [`Image`].

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use sss::integrator::pt::HitPolicy;

use super::{
    Buffer, Context, GpuPixel, GpuScene, Kernel, PassParams, Shader, VulkanError, groups_for,
};
use crate::image::Image;

/// `method_pt.glsl`: scene bindings 0–8, 9 G-buffer (`GpuPixel`), 10 `vec4` out (mean of `spp`
/// samples, `w` = samples left out, see [`DeviceImage`]). Push constants: [`PtParams`].
pub const PT: Shader = Shader::new("method_pt", 11, 32);
/// `pass_shade.glsl`: scene bindings 0–8, 9 G-buffer, 10 `PixelReservoir` in, 11 `vec4` out
/// (`f(Y)·W` or one path-traced sample, `w` = 1 where the value was written as 0, see
/// [`DeviceImage`]). Push constants: [`PassParams`] (only `pass` is read).
pub const SHADE: Shader = Shader::new("pass_shade", 12, 32);

/// Push constants of the per-pixel methods (the contract's `uint spp; uint pad[7]`): samples per
/// pixel, padded to 32 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct MethodParams {
    pub spp: u32,
    pub pad: [u32; 7],
}

/// Push constants of `method_pt`: [`MethodParams`] whose first padding word carries the
/// path tracer's [`HitPolicy`] (declaration order: 0 = `UniformOne`, 1 = `All`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct PtParams {
    pub spp: u32,
    pub hits: u32,
    pub pad: [u32; 6],
}

/// What a per-pixel kernel of one frame reads: the uploaded scene, the frame's `FrameParams`
/// buffer (binding 8) and its G-buffer (binding 9, `width × height` `GpuPixel`s).
pub struct FrameInput<'a> {
    pub scene: &'a GpuScene,
    pub params: &'a Buffer,
    pub gbuffer: &'a Buffer,
    pub width: u32,
    pub height: u32,
}

/// Hits per probe that `method_pt` and `pass_shade` keep (their `BVH_MAX_HITS`). The CPU keeps
/// every hit; a GPU sample whose probe has more is left out like a non-finite one.
pub const PT_MAX_HITS: usize = 16;

/// An image read back from the device, and how many samples (`method_pt`) or pixels
/// (`pass_shade`) were left out of a mean or written as 0: NaN or infinite values, as on the CPU,
/// and path-traced samples whose probe had more than [`PT_MAX_HITS`] hits.
#[derive(Clone, Debug, PartialEq)]
pub struct DeviceImage {
    pub image: Image,
    pub left_out: u64,
}

/// Runs `kernel` (of [`PT`] or [`SHADE`]) with the frame's bindings, `extra` buffers after the
/// G-buffer and a fresh `vec4` output, and reads the output back.
fn run(
    context: &mut Context,
    kernel: &Kernel,
    frame: &FrameInput,
    extra: &[&Buffer],
    push: &[u8],
) -> Result<DeviceImage, VulkanError> {
    let count = frame.width * frame.height;
    let pixel_bytes = size_of::<GpuPixel>();
    if frame.gbuffer.bytes() < count as usize * pixel_bytes {
        return Err(VulkanError::Binding(format!(
            "G-buffer of {} bytes for {}×{} pixels of {pixel_bytes} bytes",
            frame.gbuffer.bytes(),
            frame.width,
            frame.height
        )));
    }
    let output = Buffer::zeroed(context, count as usize * 16)?;
    let mut buffers: Vec<&Buffer> = frame.scene.buffers().to_vec();
    buffers.push(frame.params);
    buffers.push(frame.gbuffer);
    buffers.extend_from_slice(extra);
    buffers.push(&output);
    context.dispatch(
        kernel,
        &buffers,
        push,
        [groups_for(count, PT.local_size), 1, 1],
    )?;
    let texels = output.read::<[f32; 4]>()?;
    Ok(DeviceImage {
        image: Image {
            width: frame.width,
            height: frame.height,
            pixels: texels.iter().map(|t| Vec3::new(t[0], t[1], t[2])).collect(),
        },
        left_out: texels.iter().map(|t| t[3] as u64).sum(),
    })
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
        HitPolicy::UniformOne => 0,
        HitPolicy::All => 1,
    };
    let params = PtParams {
        spp,
        hits,
        pad: [0; 6],
    };
    run(context, kernel, frame, &[], bytemuck::bytes_of(&params))
}

/// The shade pass on one frame: `f(Y)·W` of `reservoirs` (`PixelReservoir`s) on translucent
/// pixels, one path-traced sample elsewhere, keyed by `pass` (the kernel of [`SHADE`]).
pub fn shade(
    context: &mut Context,
    kernel: &Kernel,
    frame: &FrameInput,
    reservoirs: &Buffer,
    pass: u32,
) -> Result<DeviceImage, VulkanError> {
    let params = PassParams::new(pass, None, false);
    run(
        context,
        kernel,
        frame,
        &[reservoirs],
        bytemuck::bytes_of(&params),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn push_constants_are_32_bytes() {
        assert_eq!(size_of::<MethodParams>() as u32, PT.push_bytes);
        assert_eq!(size_of::<PtParams>() as u32, PT.push_bytes);
        assert_eq!(std::mem::offset_of!(PtParams, hits), 4);
        assert_eq!(size_of::<PassParams>() as u32, SHADE.push_bytes);
    }
}
