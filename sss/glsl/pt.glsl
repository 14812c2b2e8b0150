// The path-tracing baseline per pixel: the GLSL twin of sss/src/integrator/pt.rs (read the two
// side by side). Camera ray -> G-buffer hit x1 -> BSSRDF IS -> x2 -> light sample at x2 (NEE) ->
// shadow ray, estimate f / (p_disk p_light) [001 §2.1, §3.1]; Lambert surfaces get direct
// lighting by NEE.
//
// The including shader enables GL_EXT_shader_explicit_arithmetic_types_int64 and defines
// SCENE_BINDING (and BVH_MAX_HITS, if not BVH_DEFAULT_MAX_HITS) before the first include; this file includes
// bssrdf.glsl, hence scene.glsl. Hits of a probe beyond BVH_MAX_HITS are not evaluated on the GPU
// (the CPU has no cap): pt_estimate counts such probes in pt_hit_overflow so a caller can tell a
// capped estimate from a faithful one.

#ifndef SSS_PT_GLSL
#define SSS_PT_GLSL

#include "rng.glsl"
#include "bssrdf.glsl"

// PT_PURPOSE_PT, PT_SHADOW_EPSILON and the profiles PT_PROFILE_* (PtSettings::profile; no buffer
// carries it yet) (sss/src/contract.rs).
#include "contract/sss.glsl"
// PtHits (engine/src/contract.rs): PT_HITS_UNIFORM_ONE, PT_HITS_ALL.
#include "contract/engine.glsl"
// std::f32::consts::FRAC_1_PI.
const float PT_FRAC_1_PI = 0.31830987;

// Probes of this invocation whose hit count exceeded BVH_MAX_HITS (the estimate then misses the
// hits beyond the cap).
uint pt_hit_overflow = 0u;

// The running sum of a method's samples between its dispatches (one per sample): a finite `value`
// is added to the f64 `sum` in sample order, as the CPU's DVec3 sum; a NaN or infinite one, or one
// whose probe had more than BVH_MAX_HITS hits (pt_hit_overflow above `overflow`, its count before
// the sample), is counted in `left_out` instead (the CPU leaves non-finite samples out of the sum
// but not of the divisor; on the GPU a capped sample would be biased low).
void pt_accumulate(vec3 value, uint overflow, inout double sum[3], inout uint left_out) {
    if (any(isnan(value)) || any(isinf(value)) || pt_hit_overflow != overflow) {
        left_out++;
    } else {
        precise dvec3 total = dvec3(sum[0], sum[1], sum[2]) + dvec3(value);
        sum = double[3](total.x, total.y, total.z);
    }
}

vec3 pt_vec3(float v[3]) {
    return vec3(v[0], v[1], v[2]);
}

// sample_stream: the stream of sample `sample` of `pixel` in `frame`.
Stream pt_sample_stream(uint pixel, uint frame, uint sample_index, uint64_t seed) {
    return stream_new(StreamKey(pixel, frame, sample_index, PT_PURPOSE_PT), seed);
}

// occluded: whether the segment from x (offset to the side of `normal` that wi leaves through)
// to the light at `distance` along wi is blocked.
bool pt_occluded(vec3 x, vec3 normal, vec3 wi, float distance) {
    precise float side = glam_dot(normal, wi) >= 0.0 ? 1.0 : -1.0;
    precise vec3 origin = x + normal * (side * PT_SHADOW_EPSILON);
    precise float t_max = distance - 2.0 * PT_SHADOW_EPSILON;
    BvhRay ray;
    if (!bvh_prepare(origin, wi, 0.0, t_max, ray)) {
        return false;
    }
    return bvh_traverse(ray, BVH_OCCLUDED, BVH_NO_HIT).prim != BVH_NO_HIT;
}

// PtSettings::radius and ::profile, with the material's dipoles (used under PT_PROFILE_DIPOLE; the
// Rust Profile enum of estimate).
struct PtOptions {
    uint radius;
    uint profile;
    GpuDipoleProfiles dipoles;
};

// The default settings: exact radii, Burley profile.
PtOptions pt_options_default() {
    PtOptions o;
    o.radius = BSSRDF_RADIUS_EXACT;
    o.profile = PT_PROFILE_BURLEY;
    o.dipoles.r_max_all = 0.0;
    for (int c = 0; c < 3; c++) {
        o.dipoles.channels[c] = GpuDipole(0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    }
    return o;
}

// The value of one entry point x2 (the `entry` closure of estimate_translucent): 3 light numbers
// from rng, f / (p_disk p_light), 0 when unlit, outside the support or shadowed.
vec3 pt_entry(GpuMaterial material, ExitPoint x1, TechniqueSelection selection, PtOptions options,
              BvhHit hit, inout Stream rng) {
    EntryPoint x2 = bssrdf_entry_point_from_hit(hit);
    precise float p = bssrdf_p_disk_with(x1, selection, options.radius, x2.position,
        x2.geometric_normal);
    float u0 = stream_next_f32(rng);
    float u1 = stream_next_f32(rng);
    float u2 = stream_next_f32(rng);
    LightSample light;
    if (!lights_sample(x2.position, vec3(u0, u1, u2), light)) {
        return vec3(0.0);
    }
    precise vec3 f = options.profile == PT_PROFILE_DIPOLE
        ? bssrdf_contribution_dipole(options.dipoles, x1, x2, light.wi, light.radiance)
        : bssrdf_contribution(material, x1, x2, light.wi, light.radiance);
    if (!(p > 0.0 && light.pdf > 0.0) || all(equal(f, vec3(0.0)))) {
        return vec3(0.0);
    }
    if (pt_occluded(x2.position, x2.geometric_normal, light.wi, light.distance)) {
        return vec3(0.0);
    }
    precise float pdf = p * light.pdf;
    precise vec3 value = f / pdf;
    return value;
}

// estimate_translucent: one probe, then every hit (All, summed in rank order [001 Eq. 10]) or
// one hit picked uniformly and weighted by the hit count (UniformOne [001 Eq. 9]).
vec3 pt_estimate_translucent(GpuMaterial material, ExitPoint x1, uint hits_policy,
        PtOptions options, inout Stream rng) {
    TechniqueSelection selection = bssrdf_selection_default();
    float u_technique = stream_next_f32(rng);
    float u_radius = stream_next_f32(rng);
    float u_angle = stream_next_f32(rng);
    Probe probe = bssrdf_probe_sample(selection, u_technique, u_radius, u_angle);
    bssrdf_probe_trace_with(probe, x1, options.radius);
    // Shadow rays reset bvh_hit_count (bvh_hits stays): keep the probe's count.
    uint count = bvh_hit_count;
    if (count > uint(BVH_MAX_HITS)) {
        pt_hit_overflow++;
    }
    uint kept = min(count, uint(BVH_MAX_HITS));
    if (hits_policy == PT_HITS_ALL) {
        precise vec3 sum = vec3(0.0);
        for (uint k = 0u; k < kept; k++) {
            sum = sum + pt_entry(material, x1, selection, options, bvh_hits[k], rng);
        }
        return sum;
    }
    float u_pick = stream_next_f32(rng);
    uint rank;
    BvhHit hit;
    if (!bssrdf_pick_hit(BSSRDF_INDEX_UNKNOWN, u_pick, rank, hit)) {
        return vec3(0.0);
    }
    precise vec3 value = pt_entry(material, x1, selection, options, hit, rng) * float(count);
    return value;
}

// direct_lambert: (albedo/π) L_e max(0, n·ωi) / p_light, visibility tested.
vec3 pt_direct_lambert(vec3 albedo, GPixel x1, inout Stream rng) {
    vec3 position = pt_vec3(x1.position);
    vec3 geometric_normal = pt_vec3(x1.geometric_normal);
    float u0 = stream_next_f32(rng);
    float u1 = stream_next_f32(rng);
    float u2 = stream_next_f32(rng);
    LightSample light;
    if (!lights_sample(position, vec3(u0, u1, u2), light)) {
        return vec3(0.0);
    }
    precise float cos_i = glam_dot(pt_vec3(x1.shading_normal), light.wi);
    if (!(cos_i > 0.0 && glam_dot(geometric_normal, light.wi) > 0.0 && light.pdf > 0.0)) {
        return vec3(0.0);
    }
    if (pt_occluded(position, geometric_normal, light.wi, light.distance)) {
        return vec3(0.0);
    }
    precise float scale = PT_FRAC_1_PI * cos_i / light.pdf;
    precise vec3 value = albedo * scale * light.radiance;
    return value;
}

// estimate_lambert: the emission toward the camera on the side of x1's winding normal it sees,
// plus the direct lighting.
vec3 pt_estimate_lambert(GpuMaterial material, GPixel x1, inout Stream rng) {
    bool front = glam_dot(scene_geometric_normal(x1.prim), pt_vec3(x1.view)) > 0.0;
    vec3 emitted = material_emitted(material, front);
    precise vec3 value = emitted + pt_direct_lambert(material_albedo(material), x1, rng);
    return value;
}

// estimate with the radius sampling, profile (and, under the dipole profile, the dipoles of x1's
// material) of `options`: one f32 estimate of the radiance leaving x1 toward the camera
// (Shading::prepare picks the branch by x1's material).
vec3 pt_estimate_with(GPixel x1, uint hits_policy, PtOptions options, inout Stream rng) {
    GpuMaterial material = scene_material(x1.object);
    if (material_is_translucent(material)) {
        ExitPoint exit_point = bssrdf_exit_point_new(pt_vec3(x1.position),
            pt_vec3(x1.geometric_normal), pt_vec3(x1.shading_normal), pt_vec3(x1.view), x1.object,
            material);
        return pt_estimate_translucent(material, exit_point, hits_policy, options, rng);
    }
    return pt_estimate_lambert(material, x1, rng);
}

// estimate with the default settings (exact radii, Burley profile).
vec3 pt_estimate(GPixel x1, uint hits_policy, inout Stream rng) {
    return pt_estimate_with(x1, hits_policy, pt_options_default(), rng);
}

#endif
