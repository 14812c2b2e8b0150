//! The adaptive method of paper 004 on the device (`method_adaptive.glsl`, twin of
//! [`cpu::render_frame`](super::cpu::render_frame) and [`cpu::run`](super::cpu::run), driven through the engine's [`Renderer`] ([`run`])):
//! per frame of the trajectory its G-buffer, then `b_max` dispatches (one per sample index) that
//! reproject the previous frame's histories, take each pixel's count of samples and write the
//! mean, the count and the next histories.
//!
//! The per-pixel history crosses frames in two buffers that swap roles ([`GpuHistory`], valid = 0
//! where the CPU has `None`); binding 14 carries each pixel's count, sum and tallies between the
//! dispatches of one frame ([`AdaptiveState`]).

use bytemuck::{Pod, Zeroable};
use engine::vulkan::{
    Buffer, Context, DeviceImage, FrameInput, Kernel, LoopsCut, Renderer, Shader, VulkanError,
    groups_for,
};
use sss::scene::Scene;

use super::contract::{AdaptiveMethodParams, AdaptiveState};
use super::cpu::{AdaptiveParams, History};

/// `method_adaptive.glsl`: scene bindings 0–8, 9 G-buffer (`GpuPixel`), 10 `vec4` out (mean,
/// `w` = samples left out), 11 the previous frame's G-buffer, 12 the previous frame's
/// [`GpuHistory`] per pixel, 13 this frame's, 14 [`AdaptiveState`] per pixel. Push constants:
/// [`AdaptiveMethodParams`].
pub const ADAPTIVE: Shader = Shader::compiled(
    "method_adaptive",
    crate::spirv!("method_adaptive"),
    15,
    size_of::<AdaptiveMethodParams>() as u32,
);

/// `adaptive.glsl`'s `History` (std430, 16 bytes): `Option<History>`, `valid = 0` for `None`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuHistory {
    pub mean_count: f32,
    pub mean: f32,
    pub variance: f32,
    pub valid: u32,
}

impl GpuHistory {
    /// The CPU's history of a pixel.
    pub fn to_cpu(self) -> Option<History> {
        (self.valid != 0).then_some(History {
            mean_count: self.mean_count,
            mean: self.mean,
            variance: self.variance,
        })
    }
}

/// One frame of the adaptive method read back: the image (`left_out` = non-finite samples and
/// samples with more probe hits than kept), the samples per pixel (0 without a primary hit),
/// the dispatches whose loops the device cut short (non-zero: the frame is not to be trusted).
#[derive(Clone, Debug, PartialEq)]
pub struct AdaptiveImage {
    pub image: DeviceImage,
    pub counts: Vec<u32>,
    pub cut: u64,
}

/// A frame of the method and the history it leaves for the next ([`render_adaptive_frame`]).
struct Step {
    out: AdaptiveImage,
    history: Buffer,
}

impl LoopsCut for Step {
    fn loops_cut(&self) -> u64 {
        self.out.cut
    }
}

/// One frame of the adaptive method with controller `params` (validated) on `frame`, whose
/// `FrameParams` carry the previous frame's camera when `previous` (that frame's G-buffer and
/// [`GpuHistory`] buffer) is given: `b_max` dispatches. Returns the frame and its histories, the
/// `previous` of the next frame together with `frame.gbuffer`.
pub fn render_adaptive_frame(
    context: &mut Context,
    kernel: &Kernel,
    frame: &FrameInput,
    previous: Option<(&Buffer, &Buffer)>,
    params: &AdaptiveParams,
) -> Result<(AdaptiveImage, Buffer), VulkanError> {
    let count = frame.width * frame.height;
    let history_bytes = count as usize * size_of::<GpuHistory>();
    let output = Buffer::zeroed(context, count as usize * 16)?;
    let next = Buffer::zeroed(context, history_bytes)?;
    let state = Buffer::zeroed(context, count as usize * size_of::<AdaptiveState>())?;
    // Without a previous frame the kernel reads neither binding 11 nor 12: stand-ins.
    let stand_in;
    let (previous_gbuffer, previous_history) = match previous {
        Some(p) => p,
        None => {
            stand_in = Buffer::zeroed(context, history_bytes)?;
            (frame.gbuffer, &stand_in)
        }
    };
    let buffers = frame.bindings(&[&output, previous_gbuffer, previous_history, &next, &state])?;
    for sample_index in 0..params.b_max {
        let push = AdaptiveMethodParams {
            alpha: params.alpha,
            target_variance: params.target_variance,
            kappa: params.kappa,
            b_min: params.b_min,
            b_max: params.b_max,
            radius: params.radius.code(),
            sample_index,
            pad: 0,
        };
        context.dispatch(
            kernel,
            &buffers,
            bytemuck::bytes_of(&push),
            [groups_for(count, ADAPTIVE.local_size), 1, 1],
        )?;
    }
    let states = state.read::<AdaptiveState>()?;
    let image = AdaptiveImage {
        image: frame.read_image(&output)?,
        counts: states.iter().map(|s| s.count).collect(),
        cut: states.iter().map(|s| u64::from(s.cut)).sum(),
    };
    Ok((image, next))
}

/// The `adaptive` method with controller `params` (validated) over frames `0..frames` of
/// `scene`'s trajectory, each handed to `each` as it is done (the twin of [`cpu::run`](super::cpu::run)); returns
/// the last (`None` for no frames). A frame whose loops the device cut short is an error.
pub fn run(
    renderer: &mut Renderer,
    scene: &Scene,
    params: &AdaptiveParams,
    seed: u64,
    frames: u32,
    mut each: impl FnMut(&AdaptiveImage),
) -> Result<Option<AdaptiveImage>, VulkanError> {
    let mut previous: Option<(Buffer, Buffer)> = None;
    let mut last = None;
    for frame in 0..frames {
        let carried = previous.as_ref().map(|(g, h)| (g, h));
        let (Step { out, history }, gbuffer) =
            renderer.method_frame(scene, frame, seed, ADAPTIVE, |context, kernel, input| {
                render_adaptive_frame(context, kernel, input, carried, params)
                    .map(|(out, history)| Step { out, history })
            })?;
        each(&out);
        previous = Some((gbuffer, history));
        last = Some(out);
    }
    Ok(last)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::mem::offset_of;

    #[test]
    fn buffer_structs_match_std430() {
        assert_eq!((size_of::<GpuHistory>(), align_of::<GpuHistory>()), (16, 4));
        assert_eq!(offset_of!(GpuHistory, valid), 12);
        assert_eq!(size_of::<AdaptiveMethodParams>(), 32);
        assert_eq!(size_of::<AdaptiveState>(), 56);
        assert_eq!(
            GpuHistory {
                mean_count: 1.0,
                mean: 2.0,
                variance: 3.0,
                valid: 1
            }
            .to_cpu(),
            Some(History {
                mean_count: 1.0,
                mean: 2.0,
                variance: 3.0
            })
        );
        assert_eq!(GpuHistory::default().to_cpu(), None);
    }
}
