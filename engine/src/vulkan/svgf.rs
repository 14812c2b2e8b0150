//! The spatiotemporal variance-guided filter on the device (`denoise_svgf.glsl`, twin of
//! [`crate::denoise::svgf::filter`]): per frame a temporal dispatch and a variance dispatch, then
//! à-trous dispatches (one on every frame but the last, `Params::iterations` on the last). The
//! guides' pixels ([`device_pixels`]) and the demodulated frames ([`demodulate`]) are uploaded
//! from the host; the filtered colour is read back and remodulated there, by the CPU's functions.

use glam::Vec3;

use super::{Buffer, Context, Kernel, Shader, VulkanError, groups_for};
use crate::contract::{SvgfHistory, SvgfParams, SvgfStage};
use crate::denoise::Guide;
use crate::denoise::svgf::{Params, demodulate, device_pixels, remodulate};
use crate::image::Image;

/// `denoise_svgf.glsl`: 0 [`SvgfPixel`] per pixel, 1 `vec4` demodulated frame, 2 the previous
/// frame's [`SvgfHistory`] (temporal; the current one in the variance stage), 3 the current
/// frame's history (written by the temporal stage and the feedback iteration), 4 `vec4` filter
/// input, 5 `vec4` filter output (colour, variance), 6 `uint` dispatches whose loops were cut.
/// Push constants: [`SvgfParams`].
pub const SVGF: Shader = Shader::new("denoise_svgf", 7, size_of::<SvgfParams>() as u32);

/// The filtered last of `frames` (at least one, with as many `guides` of the same size).
pub fn svgf_filter(
    context: &mut Context,
    kernel: &Kernel,
    guides: &[Guide],
    frames: &[Image],
    params: &Params,
) -> Result<Image, VulkanError> {
    let last = frames.len() - 1;
    let (width, height) = (frames[last].width, frames[last].height);
    let count = (width * height) as usize;
    let mut history = Buffer::zeroed(context, count * size_of::<SvgfHistory>())?;
    let mut current = Buffer::zeroed(context, count * size_of::<SvgfHistory>())?;
    let mut input = Buffer::zeroed(context, count * 16)?;
    let mut output = Buffer::zeroed(context, count * 16)?;
    let cut = Buffer::zeroed(context, 4)?;
    for (f, (guide, frame)) in guides.iter().zip(frames).enumerate() {
        let pixels = Buffer::from_slice(context, &device_pixels(guide))?;
        let colour: Vec<[f32; 4]> = demodulate(guide, frame)
            .iter()
            .map(|c| c.extend(0.0).to_array())
            .collect();
        let colour = Buffer::from_slice(context, &colour)?;
        let mut push = SvgfParams {
            stage: SvgfStage::Temporal.code(),
            width,
            height,
            step: 1,
            feedback: 0,
            alpha_colour: params.alpha_colour,
            alpha_moments: params.alpha_moments,
            variance_history: params.variance_history,
            variance_radius: params.variance_radius,
            sigma_depth: params.sigma_depth,
            sigma_normal: params.sigma_normal,
            sigma_luminance: params.sigma_luminance,
            epsilon_depth: params.epsilon_depth,
            epsilon_luminance: params.epsilon_luminance,
            pad: [0; 2],
        };
        let groups = [groups_for(count as u32, SVGF.local_size), 1, 1];
        let run = |context: &mut Context,
                   push: &SvgfParams,
                   read: &Buffer,
                   input: &Buffer,
                   output: &Buffer| {
            let buffers = [&pixels, &colour, read, &current, input, output, &cut];
            context.dispatch(kernel, &buffers, bytemuck::bytes_of(push), groups)
        };
        run(context, &push, &history, &input, &output)?;
        push.stage = SvgfStage::Variance.code();
        run(context, &push, &current, &input, &output)?;
        let iterations = if f == last { params.iterations } else { 1 };
        for i in 0..iterations {
            std::mem::swap(&mut input, &mut output);
            push.stage = SvgfStage::Atrous.code();
            push.step = 1 << i;
            push.feedback = u32::from(i == 0);
            run(context, &push, &history, &input, &output)?;
        }
        std::mem::swap(&mut history, &mut current);
    }
    let cut = cut.read::<u32>()?[0];
    if cut > 0 {
        return Err(VulkanError::LoopsCut {
            shader: SVGF.name,
            count: u64::from(cut),
        });
    }
    let filtered: Vec<Vec3> = output
        .read::<[f32; 4]>()?
        .iter()
        .map(|c| Vec3::new(c[0], c[1], c[2]))
        .collect();
    Ok(remodulate(&guides[last], &filtered))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contract::SvgfPixel;
    use std::mem::offset_of;

    #[test]
    fn buffer_structs_match_std430() {
        assert_eq!((size_of::<SvgfPixel>(), align_of::<SvgfPixel>()), (40, 4));
        assert_eq!(offset_of!(SvgfPixel, gradient), 16);
        assert_eq!(offset_of!(SvgfPixel, previous), 28);
        assert_eq!(offset_of!(SvgfPixel, taps), 36);
        assert_eq!(size_of::<SvgfHistory>(), 24);
        assert_eq!(offset_of!(SvgfHistory, frames), 20);
        assert_eq!(size_of::<SvgfParams>() as u32, SVGF.push_bytes);
        assert_eq!(SVGF.push_bytes, 64);
    }
}
