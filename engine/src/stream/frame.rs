//! What a stream gives: one [`Frame`] at a time, and what it leaves when it ends
//! ([`Finished`]).

use crate::clock::Timing;
use crate::diagnostics::Diagnostics;
use crate::image::Image;
use shifts::PixelReservoir;

/// One rendered frame of a `Stream`.
#[derive(Clone, Debug)]
pub struct Frame {
    /// Its index on the scene's camera trajectory (0 for the first frame of the stream).
    pub index: u32,
    /// Shaded linear RGB.
    pub image: Image,
    /// Shaded values that were NaN or infinite (written as 0).
    pub nan_count: u64,
    /// The time of each step of the plan, in `Stream::labels`' order: process CPU time and
    /// wall time on the CPU backend; the device's timestamps on Vulkan (as wall time, in both
    /// fields), empty where its queue writes none.
    pub steps: Vec<Timing>,
    /// The mean confidence weight of the frame's final reservoirs (those temporal reuse takes
    /// into the next frame) over the pixels that hold one (confidence > 0); 0 where none does.
    /// It grows while temporal reuse carries history and falls back where it is rejected.
    pub confidence: f64,
}

/// What a stream leaves when it ends: the last frame's final reservoirs (its plan's
/// `final_reservoirs` buffer) and the diagnostics of its frames, when collected.
#[derive(Clone, Debug)]
pub struct Finished {
    pub diagnostics: Option<Diagnostics>,
    pub reservoirs: Vec<PixelReservoir>,
}

/// [`Frame::confidence`] of a frame whose final reservoirs are `reservoirs`.
pub(crate) fn mean_confidence(reservoirs: &[PixelReservoir]) -> f64 {
    let (sum, count) = reservoirs
        .iter()
        .filter(|r| r.confidence > 0.0)
        .fold((0.0, 0u64), |(sum, count), r| {
            (sum + f64::from(r.confidence), count + 1)
        });
    if count == 0 { 0.0 } else { sum / count as f64 }
}
