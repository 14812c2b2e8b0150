#version 460
// Parity kernel for sss/glsl/bssrdf.glsl and shifts/glsl/domain.glsl: per query, one exit point
// x1 (a G-buffer pixel) and a set of random numbers through sampling, tracing, p_disk, eval and
// inversion (engine/tests/vulkan_bssrdf.rs computes the same on the CPU).
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require

layout(local_size_x = 64) in;

#define SCENE_BINDING 0
#include "domain.glsl"

layout(push_constant) uniform Params {
    uint count;
    uint pass;
} params;

// One query: the pixel of x1 and the random numbers of one probe, the pick of an unknown index,
// the inversion's gamma and a light sample.
struct BssrdfQuery {
    uint pixel;
    float u_technique;
    float u_radius;
    float u_angle;
    float u_pick;
    float gamma;
    float u_light[3];
};

// What the CPU compares (engine/tests/vulkan_bssrdf.rs::BssrdfResult).
struct BssrdfResult {
    uint domain;
    uint technique;
    // TechniqueSelection::with_channel_weights(u_light - 1/4) and its sample of u_technique
    // (the technique is 9 when the weights are rejected).
    uint weighted_technique;
    float u_lo;
    float u_hi;
    uint ray_ok;
    float origin[3];
    float dir[3];
    float t_max;
    uint hit_count;
    uint hit_prims[BVH_MAX_HITS];
    float hit_ts[BVH_MAX_HITS];
    uint picked;
    uint rank;
    uint prim;
    uint object;
    float p_disk;
    uint light_ok;
    uint light;
    float contribution[3];
    float target;
    uint visible;
    uint hybrid;
    float inverted_u_radius;
    float inverted_u_angle;
    uint invert_code;
    uint invert_technique;
    float invert_u_radius;
    float invert_u_angle;
    uint invert_index;
    float invert_p_disk;
};

layout(std430, binding = 9) readonly buffer GBufferIn { GPixel gbuffer[]; };
layout(std430, binding = 10) readonly buffer Queries { BssrdfQuery queries[]; };
layout(std430, binding = 11) writeonly buffer Results { BssrdfResult results[]; };

BssrdfResult parity_empty() {
    BssrdfResult r;
    r.domain = 0u;
    r.technique = 0u;
    r.weighted_technique = 0u;
    r.u_lo = 0.0;
    r.u_hi = 0.0;
    r.ray_ok = 0u;
    r.origin = float[3](0.0, 0.0, 0.0);
    r.dir = float[3](0.0, 0.0, 0.0);
    r.t_max = 0.0;
    r.hit_count = 0u;
    for (int k = 0; k < BVH_MAX_HITS; k++) {
        r.hit_prims[k] = BVH_NO_HIT;
        r.hit_ts[k] = 0.0;
    }
    r.picked = 0u;
    r.rank = 0u;
    r.prim = 0u;
    r.object = 0u;
    r.p_disk = 0.0;
    r.light_ok = 0u;
    r.light = 0u;
    r.contribution = float[3](0.0, 0.0, 0.0);
    r.target = 0.0;
    r.visible = 0u;
    r.hybrid = 0u;
    r.inverted_u_radius = 0.0;
    r.inverted_u_angle = 0.0;
    r.invert_code = 0u;
    r.invert_technique = 0u;
    r.invert_u_radius = 0.0;
    r.invert_u_angle = 0.0;
    r.invert_index = 0u;
    r.invert_p_disk = 0.0;
    return r;
}

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= params.count) {
        return;
    }
    BssrdfQuery q = queries[i];
    BssrdfResult r = parity_empty();
    SssDomain domain;
    if (!domain_new(gbuffer[q.pixel], q.pixel, frame_params.frame, params.pass, scene_seed(),
            domain)) {
        results[i] = r;
        return;
    }
    r.domain = 1u;
    Probe probe = bssrdf_probe_sample(domain.selection, q.u_technique, q.u_radius, q.u_angle);
    r.technique = probe.technique;
    TechniqueSelection weighted;
    vec3 weights = vec3(q.u_light[0], q.u_light[1], q.u_light[2]) - 0.25;
    r.weighted_technique = bssrdf_selection_with_channel_weights(weights, weighted)
        ? bssrdf_selection_sample(weighted, q.u_technique) : BSSRDF_TECHNIQUE_COUNT;
    vec2 interval = bssrdf_selection_u_interval(domain.selection, probe.technique);
    r.u_lo = interval.x;
    r.u_hi = interval.y;
    BssrdfRay ray;
    if (bssrdf_probe_chord(probe, domain.x1, ray)) {
        r.ray_ok = 1u;
        r.origin = float[3](ray.origin.x, ray.origin.y, ray.origin.z);
        r.dir = float[3](ray.dir.x, ray.dir.y, ray.dir.z);
        r.t_max = ray.t_max;
    }
    bssrdf_probe_trace(probe, domain.x1);
    r.hit_count = bvh_hit_count;
    for (uint k = 0u; k < min(bvh_hit_count, uint(BVH_MAX_HITS)); k++) {
        r.hit_prims[k] = bvh_hits[k].prim;
        r.hit_ts[k] = bvh_hits[k].t;
    }
    uint rank;
    BvhHit hit;
    if (!bssrdf_pick_hit(BSSRDF_INDEX_UNKNOWN, q.u_pick, rank, hit)) {
        results[i] = r;
        return;
    }
    r.picked = 1u;
    r.rank = rank;
    r.prim = hit.prim;
    EntryPoint x2 = bssrdf_entry_point_from_hit(hit);
    r.object = x2.object;
    float p_disk = domain_p_disk(domain, x2);
    r.p_disk = p_disk;
    Probe inverted = bssrdf_invert_technique(domain.x1, probe.technique, x2.position);
    r.inverted_u_radius = inverted.u_radius;
    r.inverted_u_angle = inverted.u_angle;
    BssrdfSample regenerated;
    r.invert_code = bssrdf_invert(domain.x1, domain.selection, x2, q.gamma, regenerated);
    r.invert_technique = regenerated.technique;
    r.invert_u_radius = regenerated.u_radius;
    r.invert_u_angle = regenerated.u_angle;
    r.invert_index = regenerated.index;
    r.invert_p_disk = regenerated.p_disk;
    LightSample light;
    if (lights_sample(x2.position, vec3(q.u_light[0], q.u_light[1], q.u_light[2]), light)) {
        r.light_ok = 1u;
        r.light = light.light;
        BssrdfSample b = bssrdf_sample_new(probe, rank, x2, p_disk);
        SssSample y = sss_sample_new(b, light.light, light.point);
        vec3 f = domain_contribution(domain, y);
        r.contribution = float[3](f.x, f.y, f.z);
        r.target = domain_target(domain, y);
        r.visible = domain_visible(domain, y) ? 1u : 0u;
        bool reconnection;
        if (hybrid_uses_reconnection(hybrid_for_material(domain.material), y, domain,
                reconnection)) {
            r.hybrid = reconnection ? 1u : 2u;
        }
    }
    results[i] = r;
}
