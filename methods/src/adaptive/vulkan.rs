//! The adaptive method of seed 004 on the device (`method_adaptive.glsl`, twin of
//! [`sss::integrator::adaptive::render_frame`] and [`run`](sss::integrator::adaptive::run)):
//! per frame of the trajectory its G-buffer, then `b_max` dispatches (one per sample index) that
//! reproject the previous frame's histories, take each pixel's count of samples and write the
//! mean, the count and the next histories.
//!
//! The per-pixel history crosses frames in two buffers that swap roles ([`GpuHistory`], valid = 0
//! where the CPU has `None`); binding 14 carries each pixel's count, sum and tallies between the
//! dispatches of one frame ([`AdaptiveState`]).

use bytemuck::{Pod, Zeroable};
use sss::integrator::adaptive::{AdaptiveParams, History};

use super::pt::{bindings, read_image};
use super::{Buffer, Context, DeviceImage, FrameInput, Kernel, Shader, VulkanError, groups_for};
use crate::contract::{AdaptiveMethodParams, AdaptiveState};

/// `method_adaptive.glsl`: scene bindings 0–8, 9 G-buffer (`GpuPixel`), 10 `vec4` out (mean,
/// `w` = samples left out), 11 the previous frame's G-buffer, 12 the previous frame's
/// [`GpuHistory`] per pixel, 13 this frame's, 14 [`AdaptiveState`] per pixel. Push constants:
/// [`AdaptiveMethodParams`].
pub const ADAPTIVE: Shader = Shader::new("method_adaptive", 15, 32);

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
    let buffers = bindings(
        frame,
        &[&output, previous_gbuffer, previous_history, &next, &state],
    )?;
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
        image: read_image(frame, &output)?,
        counts: states.iter().map(|s| s.count).collect(),
        cut: states.iter().map(|s| u64::from(s.cut)).sum(),
    };
    Ok((image, next))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::mem::offset_of;

    #[test]
    fn buffer_structs_match_std430() {
        assert_eq!((size_of::<GpuHistory>(), align_of::<GpuHistory>()), (16, 4));
        assert_eq!(offset_of!(GpuHistory, valid), 12);
        assert_eq!(
            size_of::<AdaptiveMethodParams>() as u32,
            ADAPTIVE.push_bytes
        );
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
