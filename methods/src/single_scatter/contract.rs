// What the single-scatter method's kernel `method_single_scatter.glsl` shares with its Rust host
// code (`vulkan.rs`): one `twin::contract!`, rendered by `methods/build.rs` to
// `contract/single_scatter.glsl` and `contract/single_scatter_params.glsl`. This file is also
// compiled by the build script, so it names no item of the crate outside doc links.

use bytemuck::{Pod, Zeroable};

twin::contract! {
    /// Push constants of `method_single_scatter`: `spp`, the sample this dispatch runs (one
    /// dispatch per sample) and `SingleScatterSettings`' knobs the kernel takes (the
    /// `ChannelSelection` code, the `PtHits` code of the diffusion's probe, `max_segments`).
    #[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
    pub struct SingleScatterParams in push_constant params {
        pub spp: u32,
        pub sample_index: u32,
        pub channel_selection: u32,
        pub hits: u32,
        pub max_segments: u32,
        pub pad: [u32; 3],
    }
}
