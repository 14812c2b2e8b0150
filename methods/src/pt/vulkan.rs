//! The path tracer on the device (`method_pt.glsl`, twin of `sss::integrator::pt::render`): the
//! mean of `spp` samples per pixel over one frame's G-buffer, one dispatch per sample, driven
//! through the engine's [`Renderer::method_frame`] ([`render`]).

use sss::integrator::pt::HitPolicy;
use sss::scene::Scene;

use engine::contract::PtHits;
use engine::image::Image;
use engine::vulkan::{
    Buffer, Context, DeviceImage, FrameInput, Kernel, LoopsCut, Renderer, Shader, VulkanError,
    groups_for,
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
/// means. A frame whose loops the device cut short is an error.
pub fn render(
    renderer: &mut Renderer,
    scene: &Scene,
    frame: u32,
    seed: u64,
    spp: u32,
    hits: HitPolicy,
) -> Result<(Image, u64), VulkanError> {
    let (out, _) = renderer.method_frame(scene, frame, seed, PT, |context, kernel, input| {
        render_pt(context, kernel, input, spp, hits)
    })?;
    Ok((out.image.image, out.image.left_out))
}

/// The path tracer's frame: its image and the samples whose loops the device cut short.
#[derive(Clone, Debug)]
pub struct PtImage {
    pub image: DeviceImage,
    pub cut: u64,
}

impl LoopsCut for PtImage {
    fn loops_cut(&self) -> u64 {
        self.cut
    }
}

/// The path tracer on one frame (the kernel of [`PT`]): per pixel the mean of samples `0..spp`
/// with the probe hits chosen by `hits`, and the count of samples whose loops the device cut
/// short.
pub fn render_pt(
    context: &mut Context,
    kernel: &Kernel,
    frame: &FrameInput,
    spp: u32,
    hits: HitPolicy,
) -> Result<PtImage, VulkanError> {
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
    let cut = state
        .read::<PtState>()?
        .iter()
        .map(|s| u64::from(s.cut))
        .sum();
    Ok(PtImage {
        image: frame.read_image(&output)?,
        cut,
    })
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
