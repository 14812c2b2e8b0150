#version 460
// Parity kernel for geometry/glsl/bvh.glsl: per ray, the closest hit, occlusion and all hits on one
// object (engine/tests/vulkan_parity.rs).
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require

layout(local_size_x = 64) in;

layout(push_constant) uniform Params {
    uint count;
    uint node_count;
} params;

#define BVH_BINDING 2
#define BVH_NODE_COUNT params.node_count
#include "bvh.glsl"

struct BvhRayInput {
    float origin[3];
    float dir[3];
    float t_min;
    float t_max;
    uint object;
};

struct BvhRayOutput {
    uint closest_prim;
    float closest_t;
    float closest_u;
    float closest_v;
    uint occluded;
    uint hit_count;
    uint hit_prims[BVH_MAX_HITS];
    float hit_ts[BVH_MAX_HITS];
};

layout(std430, binding = 0) readonly buffer Rays { BvhRayInput rays[]; };
layout(std430, binding = 1) writeonly buffer Results { BvhRayOutput results[]; };

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= params.count) {
        return;
    }
    BvhRayInput input_ray = rays[i];
    BvhRayOutput out_ray;
    out_ray.closest_prim = BVH_NO_HIT;
    out_ray.closest_t = 0.0;
    out_ray.closest_u = 0.0;
    out_ray.closest_v = 0.0;
    out_ray.occluded = 0u;
    out_ray.hit_count = 0u;
    for (int k = 0; k < BVH_MAX_HITS; k++) {
        out_ray.hit_prims[k] = BVH_NO_HIT;
        out_ray.hit_ts[k] = 0.0;
    }
    BvhRay ray;
    vec3 origin = vec3(input_ray.origin[0], input_ray.origin[1], input_ray.origin[2]);
    vec3 dir = vec3(input_ray.dir[0], input_ray.dir[1], input_ray.dir[2]);
    if (bvh_prepare(origin, dir, input_ray.t_min, input_ray.t_max, ray)) {
        BvhHit closest = bvh_traverse(ray, BVH_CLOSEST, BVH_NO_HIT);
        out_ray.closest_prim = closest.prim;
        if (closest.prim != BVH_NO_HIT) {
            out_ray.closest_t = closest.t;
            out_ray.closest_u = closest.bary.x;
            out_ray.closest_v = closest.bary.y;
        }
        out_ray.occluded = bvh_traverse(ray, BVH_OCCLUDED, BVH_NO_HIT).prim != BVH_NO_HIT ? 1u : 0u;
        bvh_traverse(ray, BVH_ALL_HITS, input_ray.object);
        out_ray.hit_count = bvh_hit_count;
        for (uint k = 0u; k < min(bvh_hit_count, uint(BVH_MAX_HITS)); k++) {
            out_ray.hit_prims[k] = bvh_hits[k].prim;
            out_ray.hit_ts[k] = bvh_hits[k].t;
        }
    }
    results[i] = out_ray;
}
