//! The shade pass on the device (`pass_shade.glsl`, twin of the CPU backend's `shade`) on its
//! own: one dispatch over a frame's G-buffer and reservoirs, read back as a [`DeviceImage`]. A
//! preset's frames run the same kernel inside their pass schedule (`frame.rs`); this entry point
//! is what its parity test (`engine/tests/vulkan_shade.rs`) dispatches.

use super::{
    Buffer, Context, DeviceImage, FrameInput, Kernel, PassParams, Shader, VulkanError, groups_for,
};
use crate::plan::PassKernel;

/// `pass_shade.glsl` ([`PassKernel::Shade`]): `f(Y)·W` or one path-traced sample, `w` = 1 where the
/// value was written as 0 (see [`DeviceImage`]). Of its [`PassParams`] only `pass` is read.
pub const SHADE: Shader = Shader::of(PassKernel::Shade);

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

    #[test]
    fn push_constants_are_the_pass_params() {
        assert_eq!(size_of::<PassParams>() as u32, SHADE.push_bytes);
    }
}
