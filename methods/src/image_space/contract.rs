// What the image-space method's GLSL (`image_space.glsl`, the CPU's twin, and its kernel
// `method_image_space.glsl`) shares with its Rust: one `twin::contract!`, rendered by
// `methods/build.rs` to `contract/image_space.glsl` and `contract/image_space_params.glsl`. This
// file is also compiled by the build script, so it names no item of the crate outside doc links.

use bytemuck::{Pod, Zeroable};

twin::contract! {
    glsl_prefix = IMAGE_SPACE;

    /// `purpose` of the irradiance streams (ASCII "ISIR").
    pub const PURPOSE_IRRADIANCE: u32 = 0x4953_4952;
    /// `purpose` of the gather streams (ASCII "ISGA").
    pub const PURPOSE_GATHER: u32 = 0x4953_4741;

    /// What the image shows under a tangent-plane point
    /// ([`crate::image_space::cpu::Lookup::kind`]); on the GPU the lookup returns its code.
    #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
    pub enum LookupKind in IMAGE_SPACE {
        /// An entry point with its normal and irradiance.
        Entry,
        OffScreen,
        /// Another object or no hit.
        Occluded,
    }

    /// `ImageSpaceParams::stage`: which half of a pass of `method_image_space` a dispatch runs.
    #[derive(Clone, Copy, Debug, PartialEq, Eq)]
    pub enum ImageSpaceStage in IMAGE_SPACE_STAGE {
        /// `E` of every translucent pixel into the irradiance buffer [002 Eq. 5].
        Irradiance,
        /// The gather of every translucent pixel, the path tracer's sample elsewhere [002 Eq. 4].
        Gather,
    }

    /// Push constants of `method_image_space`: the pass (the stream key `pass` of
    /// [`render`](crate::image_space::cpu::render)), its stage and `ImageSpaceSettings`' sample counts (its `P(c)` is folded into
    /// the uploaded gather profiles).
    #[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
    pub struct ImageSpaceParams in push_constant params {
        pub spp: u32,
        pub pass: u32,
        /// An `ImageSpaceStage` code.
        pub stage: u32,
        pub irradiance_samples: u32,
        pub importance_samples: u32,
        pub uniform_samples: u32,
        pub pad: [u32; 2],
    }

    /// A pixel of `method_image_space` between its dispatches: the f64 sum of its finite pass
    /// values, the pass values left out, the dispatches whose loops the device cut short, and its
    /// gather's `EntryCounts` over the passes.
    #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
    pub struct ImageSpaceState {
        pub sum: [f64; 3],
        pub left_out: u32,
        pub cut: u32,
        pub samples: u32,
        pub off_screen: u32,
        pub occluded: u32,
        pub outside: u32,
        pub edge_on: u32,
        pub pad: u32,
    }
}
