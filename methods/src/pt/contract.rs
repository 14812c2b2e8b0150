// What the path tracer's kernel `method_pt.glsl` shares with its Rust: one `twin::contract!`,
// rendered by `methods/build.rs` to `contract/pt.glsl` and `contract/pt_params.glsl`. The hit
// policy's codes (`PtHits`) stay in the engine's contract: the shade pass and the single-scatter
// kernel read them too (`sss/glsl/pt.glsl`). This file is also compiled by the build script, so it
// names no item of the crate outside doc links.

use bytemuck::{Pod, Zeroable};

twin::contract! {
    /// Push constants of `method_pt`.
    #[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
    pub struct PtParams in push_constant params {
        pub spp: u32,
        /// An `engine::contract::PtHits` code.
        pub hits: u32,
        /// The sample this dispatch adds (one dispatch per sample).
        pub sample_index: u32,
        pub pad: [u32; 5],
    }

    /// A pixel's running sum between the dispatches of `method_pt`.
    #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
    pub struct PtState {
        pub sum: [f64; 3],
        pub left_out: u32,
        /// Samples whose loops the device cut short.
        pub cut: u32,
    }
}
