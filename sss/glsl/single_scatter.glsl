// Paper 000's hybrid estimator per pixel: the GLSL twin of sss/src/integrator/single_scatter.rs
// (read the two side by side). Path-traced zero and single scattering on the object's own mesh
// with the material's boundary, plus diffusion with the multiple-scattering-only profile R - R1
// by BSSRDF IS (signed); Lambert pixels get the path tracer's direct lighting.
//
// The including shader enables GL_EXT_shader_explicit_arithmetic_types_int64, defines
// SCENE_BINDING (and BVH_MAX_HITS, if not BVH_DEFAULT_MAX_HITS), includes scene.glsl, pt.glsl and random_walk.glsl,
// defines the three exit_lighting_* functions random_walk.glsl declares (the ExitLighting of the
// exits, e.g. engine/glsl/include/scene_lighting.glsl, the SceneLighting twin), and then
// includes this file: the method kernel engine/glsl/method_single_scatter.glsl and the test
// kernel engine/glsl/parity_single_scatter.glsl.
//
// Per material the kernel needs, besides GpuMaterial (binding 6: ior and its Fresnel
// normalisation, the kind): the walk's RandomWalkMedium (sigma_s, sigma_t, g, boundary, eta, as
// engine::vulkan::GpuMedium uploads it) and a SingleScatterProfile (below), both computed on
// the host from Medium::from_translucent and MultipleScattering::new (they need sqrt-free
// closed forms and the transcendental r_max the device must not redo).
//
// Where the Rust code passes closures, this twin spells the instances out:
// - unscattered(.., chord) with the single-scattering chord callback is
//   single_scatter_path_traced's loop, without a callback it is single_scatter_unscattered;
// - pt::estimate_bssrdf with MultipleScattering::contribution is single_scatter_estimate_multiple
//   and single_scatter_entry (pt_estimate_translucent's and pt_entry's structure, another f).
//
// Bounds: a chain of unscattered chords has at most `max_segments` chords (the CPU's
// SingleScatterSettings::max_segments); a chain cut there, or a mesh query that skipped more than
// RANDOM_WALK_MAX_ENTRY_SKIPS entering hits (unbounded on the CPU), makes the estimate report
// `truncated`. Not bit-exact with the CPU where the path uses exp/log/sin/cos (distances,
// transmittance, phase and cosine sampling, Burley exp): parity is statistical, as for
// random_walk.glsl and pt.glsl.

#ifndef SSS_SINGLE_SCATTER_GLSL
#define SSS_SINGLE_SCATTER_GLSL

#include "pt.glsl"
#include "random_walk.glsl"

// SINGLE_SCATTER_PURPOSE_SINGLE_SCATTER, SINGLE_SCATTER_DEFAULT_MAX_SEGMENTS and the
// ChannelSelection codes SINGLE_SCATTER_CHANNEL_* (sss/src/contract.rs).
#include "contract/sss.glsl"
// 1.0f32 / 3.0.
const float SINGLE_SCATTER_ONE_THIRD = 0.333333343267440796;

// MultipleScattering as the host derives it (std430, 60 bytes; Rust twin
// engine::vulkan::GpuSingleScatterProfile): per channel the full profile's albedo A(alpha), Burley d and r_max (which
// sample x2 and truncate), and the single-scattering albedo alpha/5.108 and Burley d.
struct SingleScatterProfile {
    float full_albedo[3];
    float full_d[3];
    float full_r_max[3];
    float single_albedo[3];
    float single_d[3];
};

// Orders: the estimate by scattering order.
struct SingleScatterOrders {
    vec3 zero;
    vec3 single;
    vec3 multiple;
    bool truncated;
};

vec3 single_scatter_vec3(float v[3]) {
    return vec3(v[0], v[1], v[2]);
}

// sample_stream: the stream of sample `sample_index` of `pixel` in `frame`.
Stream single_scatter_sample_stream(uint pixel, uint frame, uint sample_index, uint64_t seed) {
    StreamKey key = StreamKey(pixel, frame, sample_index, SINGLE_SCATTER_PURPOSE_SINGLE_SCATTER);
    return stream_new(key, seed);
}

// ChannelSelection::probabilities: sigma_s / sum, or 1/3 (also when the medium does not scatter).
vec3 single_scatter_probabilities(uint selection, vec3 sigma_s) {
    precise float sum = sigma_s.x + sigma_s.y + sigma_s.z;
    if (selection == SINGLE_SCATTER_CHANNEL_SCATTERING && sum > 0.0 && !isinf(sum)) {
        precise vec3 p = sigma_s / sum;
        return p;
    }
    return vec3(SINGLE_SCATTER_ONE_THIRD);
}

// pick_channel: the channel whose cumulative interval contains u; zero-probability channels are
// never returned.
uint single_scatter_pick_channel(vec3 probabilities, float u) {
    precise float cumulative = 0.0;
    uint last = 0u;
    for (uint c = 0u; c < 3u; c++) {
        if (probabilities[c] <= 0.0) {
            continue;
        }
        cumulative += probabilities[c];
        last = c;
        if (u < cumulative) {
            return c;
        }
    }
    return last;
}

// sampling::sample_truncated_exponential: t = -ln(1 - u (1 - e^{-sigma_t d})) / sigma_t [000 slide 56] (d = inf: the
// plain exponential).
float single_scatter_sample_distance(float sigma_t, float d, float u) {
    precise float t = -burley_log1p(u * burley_expm1(-sigma_t * d)) / sigma_t;
    return t;
}

// distance_pdf: sum_c P_c sigma_t,c e^{-sigma_t,c t} / (1 - e^{-sigma_t,c d}).
float single_scatter_distance_pdf(vec3 sigma_t, vec3 probabilities, float d, float t) {
    precise float sum = 0.0;
    for (uint c = 0u; c < 3u; c++) {
        if (probabilities[c] > 0.0) {
            precise float term = probabilities[c] * sigma_t[c] * exp(-sigma_t[c] * t)
                / -burley_expm1(-sigma_t[c] * d);
            sum = sum + term;
        }
    }
    return sum;
}

// The boundary query of MeshBoundary with t_max = inf: 1 with t and the outward normal, 0 when
// the boundary is not reached, 2 when the entry-skip cap was hit (truncated).
uint single_scatter_intersect(uint object, bool inward_winding, vec3 pos, vec3 dir, out float t,
                              out vec3 normal) {
    return random_walk_mesh_intersect(object, inward_winding, pos, dir, burley_infinity(), t,
                                      normal);
}

// unscattered without a chord callback: the light arriving through the exit of the unscattered
// path from `pos` along `dir` with weight `beta`, attenuated by e^{-sigma_t d} per chord, through
// internal reflections under Russian roulette. False when the chain was cut.
bool single_scatter_unscattered(uint object, bool inward_winding, RandomWalkMedium medium,
                                vec3 pos_in, vec3 dir_in, vec3 beta_in, uint max_segments,
                                inout Stream stream, out vec3 light) {
    light = vec3(0.0);
    vec3 sigma_t = single_scatter_vec3(medium.sigma_t);
    precise vec3 pos = pos_in;
    vec3 dir = dir_in;
    precise vec3 beta = beta_in;
    for (uint segment = 0u; segment < max_segments; segment++) {
        float t;
        vec3 normal;
        uint found = single_scatter_intersect(object, inward_winding, pos, dir, t, normal);
        if (found == 2u) {
            return false;
        }
        if (found == 0u) {
            return true;
        }
        beta = beta * exp(-sigma_t * t);
        pos += t * dir;
        vec3 out_dir;
        uint crossing =
            random_walk_cross(medium.interface_kind, medium.eta, dir, normal, stream, out_dir);
        if (crossing != RANDOM_WALK_CROSSING_REFLECTED) {
            precise vec3 l = beta * random_walk_incident(pos, normal,
                crossing == RANDOM_WALK_CROSSING_LEAVES_DIFFUSE, out_dir, stream);
            light = l;
            return true;
        }
        dir = out_dir;
        vec3 survivor;
        if (!random_walk_roulette(beta, stream_next_f32(stream), survivor)) {
            return true;
        }
        beta = survivor;
    }
    return false;
}

// scatter_on_chord: single scattering from the chord pos + t dir, t in (0, d): channel, distance,
// Henyey-Greenstein direction, then the unscattered escape. False when the escape was cut.
bool single_scatter_scatter_on_chord(uint object, bool inward_winding, RandomWalkMedium medium,
                                     vec3 probabilities, vec3 pos, vec3 dir, float d,
                                     uint max_segments, inout Stream stream, out vec3 light) {
    light = vec3(0.0);
    vec3 sigma_t = single_scatter_vec3(medium.sigma_t);
    uint channel = single_scatter_pick_channel(probabilities, stream_next_f32(stream));
    float t = single_scatter_sample_distance(sigma_t[channel], d, stream_next_f32(stream));
    float pdf = single_scatter_distance_pdf(sigma_t, probabilities, d, t);
    vec2 u;
    u.x = stream_next_f32(stream);
    u.y = stream_next_f32(stream);
    vec3 scattered;
    float value;
    float phase_pdf;
    henyey_greenstein_sample(medium.g, dir, u, scattered, value, phase_pdf);
    if (!(d > 0.0 && pdf > 0.0 && phase_pdf > 0.0)) {
        return true;
    }
    // [000 slide 68]: sigma_s e^{-sigma_t t} / p(t), the phase weight, then the exact escape.
    precise vec3 weight = single_scatter_vec3(medium.sigma_s) * exp(-sigma_t * t)
        * (value / phase_pdf) / pdf;
    precise vec3 start = pos + t * dir;
    return single_scatter_unscattered(object, inward_winding, medium, start, scattered, weight,
                                      max_segments, stream, light);
}

// path_traced: zero and single scattering of the radiance leaving x1 (outward n1) toward wo;
// `multiple` is 0. The loop is unscattered's with the single-scattering chord callback.
SingleScatterOrders single_scatter_path_traced(uint object, bool inward_winding,
                                               RandomWalkMedium medium, vec3 x1, vec3 n1, vec3 wo,
                                               uint channel_selection, uint max_segments,
                                               inout Stream stream) {
    SingleScatterOrders orders = SingleScatterOrders(vec3(0.0), vec3(0.0), vec3(0.0), false);
    vec3 dir;
    float entry;
    if (!random_walk_enter(medium.interface_kind, medium.eta, n1, wo, stream, dir, entry)) {
        return orders;
    }
    vec3 probabilities =
        single_scatter_probabilities(channel_selection, single_scatter_vec3(medium.sigma_s));
    vec3 sigma_t = single_scatter_vec3(medium.sigma_t);
    precise vec3 single = vec3(0.0);
    bool truncated = false;
    precise vec3 pos = x1;
    precise vec3 beta = vec3(entry);
    bool done = false;
    for (uint segment = 0u; segment < max_segments && !done; segment++) {
        float t;
        vec3 normal;
        uint found = single_scatter_intersect(object, inward_winding, pos, dir, t, normal);
        if (found == 2u) {
            break;
        }
        float d = found == 1u ? t : burley_infinity();
        vec3 light;
        if (single_scatter_scatter_on_chord(object, inward_winding, medium, probabilities, pos,
                                            dir, d, max_segments, stream, light)) {
            single = single + beta * light;
        } else {
            truncated = true;
        }
        if (found == 0u) {
            done = true;
            break;
        }
        beta = beta * exp(-sigma_t * t);
        pos += t * dir;
        vec3 out_dir;
        uint crossing =
            random_walk_cross(medium.interface_kind, medium.eta, dir, normal, stream, out_dir);
        if (crossing != RANDOM_WALK_CROSSING_REFLECTED) {
            precise vec3 zero = beta * random_walk_incident(pos, normal,
                crossing == RANDOM_WALK_CROSSING_LEAVES_DIFFUSE, out_dir, stream);
            orders.zero = zero;
            done = true;
            break;
        }
        dir = out_dir;
        vec3 survivor;
        if (!random_walk_roulette(beta, stream_next_f32(stream), survivor)) {
            done = true;
            break;
        }
        beta = survivor;
    }
    orders.single = single;
    orders.truncated = truncated || !done;
    return orders;
}

// MultipleScattering::profile_rgb: A R_full(r) - (alpha/5.108) R_1(r) per channel (signed).
vec3 single_scatter_profile_rgb(SingleScatterProfile m, float r) {
    vec3 p;
    for (uint c = 0u; c < 3u; c++) {
        precise float v = m.full_albedo[c] * burley_pdf_disk(m.full_d[c], r)
            - m.single_albedo[c] * burley_pdf_disk(m.single_d[c], r);
        p[c] = v;
    }
    return p;
}

// MultipleScattering::bssrdf: S = Rn(|x1 - x2|)/pi F_t F_t, 0 beyond x1's widest r_max.
vec3 single_scatter_bssrdf(SingleScatterProfile m, ExitPoint x1, EntryPoint x2, vec3 wi) {
    float r = glam_length(x2.position - x1.position);
    if (r > bssrdf_max_element(x1.r_max)) {
        return vec3(0.0);
    }
    return bssrdf_bssrdf_of_profile(single_scatter_profile_rgb(m, r), x1, x2, wi);
}

// MultipleScattering::contribution: f = S max(0, n2.wi) L_e, unshadowed.
vec3 single_scatter_contribution(SingleScatterProfile m, ExitPoint x1, EntryPoint x2, vec3 wi,
                                 vec3 radiance) {
    float cos_i = glam_dot(x2.shading_normal, wi);
    if (isnan(cos_i) || cos_i <= 0.0) {
        return vec3(0.0);
    }
    precise vec3 f = single_scatter_bssrdf(m, x1, x2, wi) * cos_i * radiance;
    return f;
}

// pt::estimate_bssrdf's `entry` with MultipleScattering::contribution: 3 light numbers,
// f / (p_disk p_light), 0 when unlit, outside the support or shadowed.
vec3 single_scatter_entry(SingleScatterProfile m, ExitPoint x1, TechniqueSelection selection,
                          BvhHit hit, inout Stream rng) {
    EntryPoint x2 = bssrdf_entry_point_from_hit(hit);
    precise float p = bssrdf_p_disk(x1, selection, x2.position, x2.geometric_normal);
    float u0 = stream_next_f32(rng);
    float u1 = stream_next_f32(rng);
    float u2 = stream_next_f32(rng);
    LightSample light;
    if (!lights_sample(x2.position, vec3(u0, u1, u2), light)) {
        return vec3(0.0);
    }
    precise vec3 f = single_scatter_contribution(m, x1, x2, light.wi, light.radiance);
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

// pt::estimate_bssrdf with MultipleScattering::contribution: one probe (default technique
// selection), then every hit (All) or one picked uniformly (UniformOne).
vec3 single_scatter_estimate_multiple(SingleScatterProfile m, ExitPoint x1, uint hits_policy,
                                      inout Stream rng) {
    TechniqueSelection selection = bssrdf_selection_default();
    float u_technique = stream_next_f32(rng);
    float u_radius = stream_next_f32(rng);
    float u_angle = stream_next_f32(rng);
    Probe probe = bssrdf_probe_sample(selection, u_technique, u_radius, u_angle);
    bssrdf_probe_trace(probe, x1);
    // Shadow rays reset bvh_hit_count (bvh_hits stays): keep the probe's count.
    uint count = bvh_hit_count;
    if (count > uint(BVH_MAX_HITS)) {
        pt_hit_overflow++;
    }
    uint kept = min(count, uint(BVH_MAX_HITS));
    if (hits_policy == PT_HITS_ALL) {
        precise vec3 sum = vec3(0.0);
        for (uint k = 0u; k < kept; k++) {
            sum = sum + single_scatter_entry(m, x1, selection, bvh_hits[k], rng);
        }
        return sum;
    }
    float u_pick = stream_next_f32(rng);
    uint rank;
    BvhHit hit;
    if (!bssrdf_pick_hit(BSSRDF_INDEX_UNKNOWN, u_pick, rank, hit)) {
        return vec3(0.0);
    }
    precise vec3 value = single_scatter_entry(m, x1, selection, hit, rng) * float(count);
    return value;
}

// estimate: one estimate of the radiance leaving x1 toward the camera by scattering order
// (Lambert pixels: pt_estimate_lambert, all of it in `zero`). `medium` and `m` are x1's
// material's; stream order as on the CPU: the path-traced part, then the probe.
SingleScatterOrders single_scatter_estimate(GPixel x1, RandomWalkMedium medium,
                                            SingleScatterProfile m, uint channel_selection,
                                            uint hits_policy, uint max_segments,
                                            inout Stream rng) {
    GpuMaterial material = scene_material(x1.object);
    if (!material_is_translucent(material)) {
        SingleScatterOrders lambert = SingleScatterOrders(vec3(0.0), vec3(0.0), vec3(0.0), false);
        lambert.zero = pt_estimate_lambert(material, x1, rng);
        return lambert;
    }
    vec3 view = pt_vec3(x1.view);
    vec3 n1 = pt_vec3(x1.geometric_normal);
    bool inward_winding = glam_dot(scene_geometric_normal(x1.prim), view) < 0.0;
    ExitPoint exit_point = bssrdf_exit_point_with_profiles(pt_vec3(x1.position), n1,
        pt_vec3(x1.shading_normal), view, x1.object, single_scatter_vec3(m.full_d),
        single_scatter_vec3(m.full_r_max), material_fresnel(material));
    SingleScatterOrders orders = single_scatter_path_traced(x1.object, inward_winding, medium,
        exit_point.position, n1, view, channel_selection, max_segments, rng);
    orders.multiple = single_scatter_estimate_multiple(m, exit_point, hits_policy, rng);
    return orders;
}

#endif
