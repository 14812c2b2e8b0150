//! The scene BVH on the device: `geometry::Geometry`'s obvhs CWBVH uploaded as is, for
//! `geometry/glsl/bvh.glsl` (bindings `BVH_BINDING .. BVH_BINDING + 3`, in [`GpuBvh::buffers`] order).

use bytemuck::{Pod, Zeroable};
use geometry::Geometry;

use super::{Buffer, Context, VulkanError};

/// Hits per ray that `bvh.glsl`'s all-hits query keeps in the parity kernels (its default
/// `BVH_MAX_HITS`).
pub const BVH_MAX_HITS: usize = geometry::contract::bvh::DEFAULT_MAX_HITS;

/// The four BVH buffers: nodes (80-byte `CwBvhNode`s), triangles in leaf-slot order
/// (9 `f32` each), the global triangle id and the object id of each leaf slot.
pub struct GpuBvh {
    nodes: Buffer,
    triangles: Buffer,
    leaf_prims: Buffer,
    leaf_objects: Buffer,
    node_count: u32,
}

impl GpuBvh {
    /// Uploads `geometry`'s BVH.
    pub fn upload(context: &Context, geometry: &Geometry) -> Result<GpuBvh, VulkanError> {
        let bvh = geometry.bvh();
        let triangles: Vec<f32> = bvh
            .primitive_indices
            .iter()
            .flat_map(|&prim| geometry.vertices(prim))
            .flat_map(|v| v.to_array())
            .collect();
        let leaf_objects: Vec<u32> = bvh
            .primitive_indices
            .iter()
            .map(|&prim| geometry.object_of(prim))
            .collect();
        Ok(GpuBvh {
            nodes: Buffer::from_slice(context, &bvh.nodes)?,
            triangles: Buffer::from_slice(context, &triangles)?,
            leaf_prims: Buffer::from_slice(context, &bvh.primitive_indices)?,
            leaf_objects: Buffer::from_slice(context, &leaf_objects)?,
            node_count: bvh.nodes.len() as u32,
        })
    }

    /// The buffers in binding order.
    pub fn buffers(&self) -> [&Buffer; 4] {
        [
            &self.nodes,
            &self.triangles,
            &self.leaf_prims,
            &self.leaf_objects,
        ]
    }

    /// Nodes (0 for an empty scene): `BVH_NODE_COUNT` of the shader.
    pub fn node_count(&self) -> u32 {
        self.node_count
    }
}

/// `parity_bvh.glsl`'s `BvhRayInput` (std430: nine 4-byte scalars, 36 bytes); the ray of
/// `geometry::Ray` plus the object of the all-hits query.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct BvhRayInput {
    pub origin: [f32; 3],
    pub dir: [f32; 3],
    pub t_min: f32,
    pub t_max: f32,
    pub object: u32,
}

/// `parity_bvh.glsl`'s `BvhRayOutput` (std430, 88 bytes): closest hit (`u32::MAX` = none),
/// occlusion, and the first [`BVH_MAX_HITS`] hits on the input's object sorted by (t, prim)
/// with their total count.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct BvhRayOutput {
    pub closest_prim: u32,
    pub closest_t: f32,
    pub closest_bary: [f32; 2],
    pub occluded: u32,
    pub hit_count: u32,
    pub hit_prims: [u32; BVH_MAX_HITS],
    pub hit_ts: [f32; BVH_MAX_HITS],
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::mem::offset_of;

    #[test]
    fn ray_structs_match_std430() {
        assert_eq!(size_of::<BvhRayInput>(), 36);
        assert_eq!(offset_of!(BvhRayInput, t_min), 24);
        assert_eq!(offset_of!(BvhRayInput, object), 32);
        assert_eq!(size_of::<BvhRayOutput>(), 24 + 8 * BVH_MAX_HITS);
        assert_eq!(offset_of!(BvhRayOutput, hit_count), 20);
        assert_eq!(offset_of!(BvhRayOutput, hit_ts), 24 + 4 * BVH_MAX_HITS);
        // The node layout bvh.glsl reads: 80-byte obvhs nodes.
        let geometry = Geometry::new(&[geometry::shapes::icosphere(1.0, 1)]);
        assert_eq!(size_of_val(&geometry.bvh().nodes[0]), 80);
    }
}
