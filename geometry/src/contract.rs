// What the GLSL twin under `geometry/glsl/` (`bvh.glsl`) shares with this crate, as a
// `twin::contract!`; `engine/build.rs` includes this file and renders `contract/geometry.glsl`
// from `glsl_items`. This file is also compiled by the build script, so it names no item of the
// crate outside doc links.

/// Every item of the `geometry` contract (`engine/build.rs` renders `contract/geometry.glsl`).
pub fn glsl_items() -> Vec<twin::Item> {
    bvh::glsl_items()
}

/// `bvh.glsl`.
pub mod bvh {
    twin::contract! {
        glsl_prefix = BVH;

        /// Hits per ray that `bvh.glsl`'s all-hits query keeps unless the including kernel
        /// defines `BVH_MAX_HITS` first (the pass kernels keep the engine's `KEPT_HITS`); its
        /// hit count goes on past them. The CPU keeps every hit.
        pub const DEFAULT_MAX_HITS: usize = 8;
        /// The `prim` and `object` of no hit, and the `object` of a closest-hit query on any
        /// object (`Option::None` of [`crate::Hit`]).
        pub const NO_HIT: u32 = u32::MAX;

        /// The queries of [`crate::Geometry`] (`closest_hit`, `occluded`,
        /// `all_hits_on_object`) that `bvh.glsl`'s one traversal serves:
        /// `bvh_traverse(ray, BVH_<QUERY>, object)`.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        pub enum BvhQuery in BVH {
            Closest,
            Occluded,
            AllHits,
        }
    }
}
