//! `purpose` tags of the pipeline's random streams. Every random number of a pass comes from
//! `StreamKey { pixel, frame, pass, purpose }.stream(seed)`, with `pixel` the receiving pixel's
//! linear index, `pass` the pass's index in the preset (0 = candidates) and `purpose` one of
//! these. They stay below 2³⁰: the `shifts` crate keys its own streams (probabilistic
//! inversion's γ, the deferred uniform pick) with the top two bits set, and the path tracer uses
//! `sss::integrator::pt::PURPOSE_PT`.

/// BSSRDF probe numbers of candidate generation: per BSSRDF sample, `u_technique, u_radius,
/// u_angle`.
pub const PROBE: u32 = 0x100;
/// Light-sample numbers of candidate generation: 3 per probe (shared light) or per hit.
pub const LIGHT: u32 = 0x101;
/// Weighted-reservoir selection numbers (`u` of [001 Alg. 1]), one per streamed candidate or
/// input reservoir, in candidate generation and in reuse passes.
pub const SELECT: u32 = 0x102;
/// Spatial neighbour positions: 2 numbers (radius, angle) per neighbour slot.
pub const NEIGHBOURS: u32 = 0x103;
/// The path-tracing estimate that shades pixels whose x1 is not translucent.
pub const OPAQUE: u32 = 0x104;
