//! The path tracer on the device (`method_pt.glsl`, twin of `sss::integrator::pt::render`): the
//! mean of `spp` samples per pixel over one frame's G-buffer, one dispatch per sample, driven
//! through the engine's [`Renderer`] ([`render`]).

use sss::integrator::pt::HitPolicy;
use sss::scene::Scene;

use engine::contract::PtHits;
use engine::image::Image;
use engine::vulkan::{
    Buffer, Context, DeviceImage, FrameInput, Kernel, Renderer, Shader, VulkanError, groups_for,
};

use super::contract::{PtParams, PtState};

/// `method_pt.glsl`: scene bindings 0–8, 9 G-buffer (`GpuPixel`), 10 `vec4` out (mean of `spp`
/// samples, `w` = samples left out, see [`DeviceImage`]), 11 the per-pixel running sum between
/// its dispatches ([`PtState`], one dispatch per sample). Push constants: [`PtParams`].
pub const PT: Shader = Shader::compiled(
    "method_pt",
    crate::spirv!("method_pt"),
    12,
    size_of::<PtParams>() as u32,
);

/// The path tracer at `frame` with the probe hits chosen by `hits` (`pt:spp` keeps all of
/// them): the G-buffer kernel, then [`render_pt`]; the image and the samples left out of the
/// means.
pub fn render(
    renderer: &mut Renderer,
    scene: &Scene,
    frame: u32,
    seed: u64,
    spp: u32,
    hits: HitPolicy,
) -> Result<(Image, u64), VulkanError> {
    let (gbuffer, params) = renderer.gbuffer(scene, frame, seed)?;
    let (context, kernel, gpu) = renderer.parts(PT)?;
    let input = FrameInput::new(scene, gpu, &params, &gbuffer);
    let out = render_pt(context, kernel, &input, spp, hits)?;
    Ok((out.image, out.left_out))
}

/// The path tracer on one frame (the kernel of [`PT`]): per pixel the mean of samples `0..spp`
/// with the probe hits chosen by `hits`; a dispatch whose loops the device cut short is an
/// error.
pub fn render_pt(
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

#[cfg(test)]
mod tests {
    use super::*;
    use std::mem::offset_of;

    #[test]
    fn buffer_structs_match_std430() {
        assert_eq!(size_of::<PtParams>(), 32);
        assert_eq!(offset_of!(PtParams, hits), 4);
        assert_eq!(offset_of!(PtParams, sample_index), 8);
        assert_eq!((size_of::<PtState>(), align_of::<PtState>()), (32, 8));
        assert_eq!(offset_of!(PtState, cut), 28);
    }
}
