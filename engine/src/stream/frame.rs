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
}

/// What a stream leaves when it ends: the last frame's final reservoirs (its plan's
/// `final_reservoirs` buffer) and the diagnostics of its frames, when collected.
#[derive(Clone, Debug)]
pub struct Finished {
    pub diagnostics: Option<Diagnostics>,
    pub reservoirs: Vec<PixelReservoir>,
}
