// Ray queries on the obvhs CWBVH as geometry::Geometry uploads it: the GLSL twin of
// geometry/src/bvh.rs (read the two side by side; same node test, same watertight triangle
// test, same operation order, `precise` so that no multiply-add is fused).
//
// The including shader enables GL_EXT_shader_explicit_arithmetic_types_int64 (shaderInt64 and
// shaderFloat64 device features) and defines BVH_BINDING: bindings BVH_BINDING .. + 3 hold the
// nodes (CwBvhNode, 80 bytes as-is), the triangles in leaf-slot order (9 floats each), the
// global triangle id of each leaf slot (CwBvh::primitive_indices) and its object id.
// BVH_NODE_COUNT must name a uint holding the node count (0 for an empty scene).

#ifndef GEOMETRY_BVH_GLSL
#define GEOMETRY_BVH_GLSL

// BVH_DEFAULT_MAX_HITS, BVH_NO_HIT and the queries BVH_CLOSEST, BVH_OCCLUDED, BVH_ALL_HITS
// (geometry/src/contract.rs).
#include "contract/geometry.glsl"

// obvhs::cwbvh::node::CwBvhNode, repr(C): p, e[3] + imask, child_base_idx, primitive_base_idx,
// child_meta[8], then min/max quantised planes per axis (8 bytes each).
struct CwBvhNode {
    float p_x;
    float p_y;
    float p_z;
    uint e_imask;
    uint child_base_idx;
    uint primitive_base_idx;
    uint child_meta[2];
    uint child_min_x[2];
    uint child_max_x[2];
    uint child_min_y[2];
    uint child_max_y[2];
    uint child_min_z[2];
    uint child_max_z[2];
};

layout(std430, binding = BVH_BINDING) readonly buffer BvhNodes { CwBvhNode bvh_nodes[]; };
layout(std430, binding = BVH_BINDING + 1) readonly buffer BvhTriangles { float bvh_triangles[]; };
layout(std430, binding = BVH_BINDING + 2) readonly buffer BvhLeafPrims { uint bvh_leaf_prims[]; };
layout(std430, binding = BVH_BINDING + 3) readonly buffer BvhLeafObjects { uint bvh_leaf_objects[]; };

// 2 gamma_3 (Ize 2013) as computed in f32 by the CPU: box exits move out by |exit| times this.
const float BVH_BOX_EXIT_MARGIN = 3.5762793e-7; // bits 0x34C00002, the f32 the CPU computes
// Direction components below this in magnitude use +-1/BVH_MIN_DIR as their inverse.
const float BVH_MIN_DIR = 1e-20;
// obvhs's TRAVERSAL_STACK_SIZE (CwBvh::validate asserts the depth stays below it).
const int BVH_STACK_SIZE = 32;
// Hits kept by the all-hits query; bvh_hit_count still counts the ones beyond.
#ifndef BVH_MAX_HITS
#define BVH_MAX_HITS BVH_DEFAULT_MAX_HITS
#endif

// A ray prepared for traversal: slab inverses and the watertight shear [Woop et al. 2013].
struct BvhRay {
    vec3 origin;
    vec3 inv_dir;
    bvec3 negative;
    // Rows of the shear: e_kx - S_x e_kz, e_ky - S_y e_kz, S_z e_kz.
    vec3 shear0;
    vec3 shear1;
    vec3 shear2;
    float t_min;
    float t_max;
};

struct BvhHit {
    float t;
    uint prim;
    uint object;
    vec2 bary;
};

// Hits of the last bvh_all_hits_on_object, sorted by (t, prim).
BvhHit bvh_hits[BVH_MAX_HITS];
uint bvh_hit_count;

float bvh_inverse(float x) {
    return abs(x) < BVH_MIN_DIR ? 1.0 / (x < 0.0 ? -BVH_MIN_DIR : BVH_MIN_DIR) : 1.0 / x;
}

// PreparedRay::new: false for a zero or non-finite direction or an empty/non-finite interval.
bool bvh_prepare(vec3 origin, vec3 dir, float t_min, float t_max, out BvhRay ray) {
    // dir + 0 turns -0 into +0, as on the CPU.
    vec3 d = vec3(dir.x == 0.0 ? 0.0 : dir.x, dir.y == 0.0 ? 0.0 : dir.y, dir.z == 0.0 ? 0.0 : dir.z);
    bool finite = !any(isinf(d)) && !any(isnan(d)) && !any(isinf(origin)) && !any(isnan(origin));
    if (!finite || all(equal(d, vec3(0.0))) || isnan(t_min) || isnan(t_max) || !(t_min < t_max)) {
        return false;
    }
    vec3 a = abs(d);
    int kz = (a.x >= a.y && a.x >= a.z) ? 0 : (a.y >= a.z ? 1 : 2);
    int kx = (kz + 1) % 3;
    int ky = (kz + 2) % 3;
    if (d[kz] < 0.0) {
        int swap = kx;
        kx = ky;
        ky = swap;
    }
    precise float sx = d[kx] / d[kz];
    precise float sy = d[ky] / d[kz];
    precise float sz = 1.0 / d[kz];
    ray.shear0 = vec3(0.0);
    ray.shear1 = vec3(0.0);
    ray.shear2 = vec3(0.0);
    ray.shear0[kx] = 1.0;
    ray.shear0[kz] = -sx;
    ray.shear1[ky] = 1.0;
    ray.shear1[kz] = -sy;
    ray.shear2[kz] = sz;
    ray.origin = origin;
    ray.inv_dir = vec3(bvh_inverse(d.x), bvh_inverse(d.y), bvh_inverse(d.z));
    ray.negative = lessThan(d, vec3(0.0));
    ray.t_min = t_min;
    ray.t_max = t_max;
    return true;
}

// Mat3A * Vec3A as glam computes it: column 0 * x + column 1 * y + column 2 * z.
vec3 bvh_shear(BvhRay ray, vec3 v) {
    precise vec3 r = vec3(ray.shear0.x, ray.shear1.x, ray.shear2.x) * v.x;
    r = r + vec3(ray.shear0.y, ray.shear1.y, ray.shear2.y) * v.y;
    r = r + vec3(ray.shear0.z, ray.shear1.z, ray.shear2.z) * v.z;
    return r;
}

vec3 bvh_vertex(uint slot, uint k) {
    uint base = 9u * slot + 3u * k;
    return vec3(bvh_triangles[base], bvh_triangles[base + 1u], bvh_triangles[base + 2u]);
}

// Watertight ray-triangle test [Woop et al. 2013]: t_min < t < t_max; edge functions that are
// exactly zero are recomputed in double precision (paper section 4).
bool bvh_intersect_triangle(uint slot, BvhRay ray, float t_max, out float t, out vec2 bary) {
    precise vec3 a = bvh_shear(ray, bvh_vertex(slot, 0u) - ray.origin);
    precise vec3 b = bvh_shear(ray, bvh_vertex(slot, 1u) - ray.origin);
    precise vec3 c = bvh_shear(ray, bvh_vertex(slot, 2u) - ray.origin);
    precise float u = c.x * b.y - c.y * b.x;
    precise float v = a.x * c.y - a.y * c.x;
    precise float w = b.x * a.y - b.y * a.x;
    if (u == 0.0 || v == 0.0 || w == 0.0) {
        precise double u64 = double(c.x) * double(b.y) - double(c.y) * double(b.x);
        precise double v64 = double(a.x) * double(c.y) - double(a.y) * double(c.x);
        precise double w64 = double(b.x) * double(a.y) - double(b.y) * double(a.x);
        u = float(u64);
        v = float(v64);
        w = float(w64);
    }
    if ((u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0)) {
        return false;
    }
    precise float det = u + v + w;
    if (det == 0.0) {
        return false;
    }
    precise float tt = (u * a.z + v * b.z + w * c.z) / det;
    t = tt;
    precise float bu = v / det;
    precise float bv = w / det;
    bary = vec2(bu, bv);
    return tt > ray.t_min && tt < t_max;
}

uint bvh_byte(uint words[2], uint i) {
    return (words[i >> 2] >> ((i & 3u) * 8u)) & 0xFFu;
}

// Bit i set when child slot i's box overlaps the ray within [t_min, t_max]
// (overlap_mask_scalar: planes p + q 2^e, the ray moved into that grid).
uint bvh_overlap_mask(CwBvhNode node, BvhRay ray, float t_max) {
    vec3 extent = vec3(
        uintBitsToFloat((node.e_imask & 0xFFu) << 23),
        uintBitsToFloat(((node.e_imask >> 8) & 0xFFu) << 23),
        uintBitsToFloat(((node.e_imask >> 16) & 0xFFu) << 23));
    precise vec3 scale = extent * ray.inv_dir;
    precise vec3 offset = (vec3(node.p_x, node.p_y, node.p_z) - ray.origin) * ray.inv_dir;
    uint mask = 0u;
    for (uint child = 0u; child < 8u; child++) {
        float lo_x = float(bvh_byte(node.child_min_x, child));
        float hi_x = float(bvh_byte(node.child_max_x, child));
        float lo_y = float(bvh_byte(node.child_min_y, child));
        float hi_y = float(bvh_byte(node.child_max_y, child));
        float lo_z = float(bvh_byte(node.child_min_z, child));
        float hi_z = float(bvh_byte(node.child_max_z, child));
        precise float near_x = (ray.negative.x ? hi_x : lo_x) * scale.x + offset.x;
        precise float near_y = (ray.negative.y ? hi_y : lo_y) * scale.y + offset.y;
        precise float near_z = (ray.negative.z ? hi_z : lo_z) * scale.z + offset.z;
        precise float far_x = (ray.negative.x ? lo_x : hi_x) * scale.x + offset.x;
        precise float far_y = (ray.negative.y ? lo_y : hi_y) * scale.y + offset.y;
        precise float far_z = (ray.negative.z ? lo_z : hi_z) * scale.z + offset.z;
        float entry = max(max(max(near_x, near_y), near_z), ray.t_min);
        float exit_raw = min(min(far_x, far_y), far_z);
        precise float exit_pushed = exit_raw + abs(exit_raw) * BVH_BOX_EXIT_MARGIN;
        float exit = min(exit_pushed, t_max);
        mask |= uint(entry <= exit) << child;
    }
    return mask;
}

// The hit mask obvhs's traversal expects: inner children in the top byte, leaf triangles below
// (CwBvhNode::get_child_and_index_bits applied to the overlapped children).
uint bvh_intersect_node(CwBvhNode node, BvhRay ray, uint oct_inv4, float t_max) {
    uint overlap = bvh_overlap_mask(node, ray, t_max);
    uint64_t oct_inv8 = uint64_t(oct_inv4);
    oct_inv8 |= oct_inv8 << 32;
    uint64_t meta8 = uint64_t(node.child_meta[0]) | (uint64_t(node.child_meta[1]) << 32);
    uint64_t is_inner8 = (meta8 & (meta8 << 1)) & 0x1010101010101010UL;
    uint64_t inner_mask8 = (is_inner8 >> 4) * 0xFFUL;
    uint64_t bit_index8 = (meta8 ^ (oct_inv8 & inner_mask8)) & 0x1F1F1F1F1F1F1F1FUL;
    uint64_t child_bits8 = (meta8 >> 5) & 0x0707070707070707UL;
    uint hit_mask = 0u;
    for (uint child = 0u; child < 8u; child++) {
        if ((overlap & (1u << child)) != 0u) {
            uint child_bits = uint(child_bits8 >> (child * 8u)) & 0xFFu;
            uint bit_index = uint(bit_index8 >> (child * 8u)) & 0xFFu;
            hit_mask |= child_bits << bit_index;
        }
    }
    return hit_mask;
}

// The smallest float above x (f32::next_up), for finite x.
float bvh_next_up(float x) {
    if (x == 0.0) {
        return uintBitsToFloat(1u);
    }
    uint bits = floatBitsToUint(x);
    return uintBitsToFloat(x > 0.0 ? bits + 1u : bits - 1u);
}

// obvhs's traverse! macro with the three visitors of Geometry (`mode`, a BvhQuery code): closest
// hit (on `object`, or on any object when it is BVH_NO_HIT), occlusion, and all hits on `object`
// into bvh_hits.
// Returns the closest hit (closest mode) or whether anything was hit (other modes, in .prim).
BvhHit bvh_traverse(BvhRay ray, uint mode, uint object) {
    BvhHit best;
    best.t = ray.t_max;
    best.prim = BVH_NO_HIT;
    best.object = BVH_NO_HIT;
    best.bary = vec2(0.0);
    bvh_hit_count = 0u;
    float t_max = ray.t_max;
    uint oct_inv4 = (ray.inv_dir.x < 0.0 ? 0u : 0x04040404u)
        | (ray.inv_dir.y < 0.0 ? 0u : 0x02020202u)
        | (ray.inv_dir.z < 0.0 ? 0u : 0x01010101u);
    uvec2 stack[BVH_STACK_SIZE];
    int depth = 0;
    uvec2 current_group = BVH_NODE_COUNT > 0u ? uvec2(0u, 0x80000000u) : uvec2(0u);
    uvec2 primitive_group = uvec2(0u);
    bool done = BVH_NODE_COUNT == 0u;
    while (!done) {
        while (primitive_group.y != 0u) {
            uint local = uint(findMSB(primitive_group.y));
            primitive_group.y &= ~(1u << local);
            uint slot = primitive_group.x + local;
            uint slot_object = bvh_leaf_objects[slot];
            float t;
            vec2 bary;
            if (mode == BVH_OCCLUDED) {
                if (bvh_intersect_triangle(slot, ray, t_max, t, bary)) {
                    best.prim = bvh_leaf_prims[slot];
                    return best;
                }
            } else if (mode == BVH_CLOSEST) {
                if (object != BVH_NO_HIT && slot_object != object) {
                    continue;
                }
                // Ties in t are accepted here and go to the lower triangle id below.
                float limit = best.prim == BVH_NO_HIT ? ray.t_max : bvh_next_up(best.t);
                if (bvh_intersect_triangle(slot, ray, limit, t, bary)) {
                    uint prim = bvh_leaf_prims[slot];
                    if (best.prim == BVH_NO_HIT || t < best.t || (t == best.t && prim < best.prim)) {
                        best = BvhHit(t, prim, slot_object, bary);
                        t_max = t;
                    }
                }
            } else if (slot_object == object && bvh_intersect_triangle(slot, ray, t_max, t, bary)) {
                BvhHit hit = BvhHit(t, bvh_leaf_prims[slot], slot_object, bary);
                // Insertion into the (t, prim)-sorted list; the count goes on past the capacity.
                uint k = min(bvh_hit_count, uint(BVH_MAX_HITS));
                while (k > 0u && (bvh_hits[k - 1u].t > hit.t
                        || (bvh_hits[k - 1u].t == hit.t && bvh_hits[k - 1u].prim > hit.prim))) {
                    if (k < uint(BVH_MAX_HITS)) {
                        bvh_hits[k] = bvh_hits[k - 1u];
                    }
                    k--;
                }
                if (k < uint(BVH_MAX_HITS)) {
                    bvh_hits[k] = hit;
                }
                bvh_hit_count++;
                best.prim = 0u;
            }
        }
        primitive_group = uvec2(0u);
        if ((current_group.y & 0xFF000000u) != 0u) {
            uint hits_imask = current_group.y;
            uint child_index_offset = uint(findMSB(hits_imask));
            uint child_index_base = current_group.x;
            current_group.y &= ~(1u << child_index_offset);
            if ((current_group.y & 0xFF000000u) != 0u && depth < BVH_STACK_SIZE) {
                stack[depth++] = current_group;
            }
            uint slot_index = (child_index_offset - 24u) ^ (oct_inv4 & 0xFFu);
            uint relative_index = uint(bitCount(hits_imask & ~(0xFFFFFFFFu << slot_index)));
            CwBvhNode node = bvh_nodes[child_index_base + relative_index];
            uint hitmask = bvh_intersect_node(node, ray, oct_inv4, t_max);
            current_group = uvec2(node.child_base_idx, (hitmask & 0xFF000000u) | (node.e_imask >> 24));
            primitive_group = uvec2(node.primitive_base_idx, hitmask & 0x00FFFFFFu);
        } else {
            current_group = uvec2(0u);
        }
        if (primitive_group.y == 0u && (current_group.y & 0xFF000000u) == 0u) {
            if (depth == 0) {
                done = true;
            } else {
                current_group = stack[--depth];
            }
        }
    }
    return best;
}

#endif
