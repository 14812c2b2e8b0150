// What the adaptive method's kernel `method_adaptive.glsl` shares with its Rust: one
// `twin::contract!`, rendered by `methods/build.rs` to `contract/adaptive.glsl` and
// `contract/adaptive_method_params.glsl`. This file is also compiled by the build script, so it
// names no item of the crate outside doc links.

use bytemuck::{Pod, Zeroable};

twin::contract! {
    /// Push constants of `method_adaptive`: [`AdaptiveParams`](crate::adaptive::cpu::AdaptiveParams) (the
    /// radius sampling as its `RadiusSampling` code) and the sample this dispatch adds (one
    /// dispatch per sample index `0..b_max`).
    #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
    pub struct AdaptiveMethodParams in push_constant params {
        pub alpha: f32,
        pub target_variance: f32,
        pub kappa: f32,
        pub b_min: u32,
        pub b_max: u32,
        pub radius: u32,
        pub sample_index: u32,
        pub pad: u32,
    }

    /// A pixel of `method_adaptive` within one frame: the f64 sum of its finite samples, its
    /// count `n`, the samples left out, the dispatches whose loops the device cut short, and the
    /// reprojected history it started from (`valid = 0`: none).
    #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
    pub struct AdaptiveState {
        pub sum: [f64; 3],
        pub count: u32,
        pub left_out: u32,
        pub cut: u32,
        pub history_mean_count: f32,
        pub history_mean: f32,
        pub history_variance: f32,
        pub history_valid: u32,
        pub pad: u32,
    }
}
