// BSSRDF importance sampling: the GLSL twin of sss/src/bssrdf/ (technique, probe, sample, pdf,
// eval, invert; read them side by side) [001 §2.1, §3.1, Alg. 3-4], DESIGN §9.
//
// Include after `#define SCENE_BINDING ...` (this file includes scene.glsl, which brings
// material.glsl, light.glsl, frame.glsl and bvh.glsl, and burley.glsl). Names are
// `bssrdf_<rust name>`; methods are `bssrdf_<type>_<method>`: TechniqueSelection ->
// `bssrdf_selection_*`, ExitPoint -> `bssrdf_exit_point_*`, EntryPoint -> `bssrdf_entry_point_*`,
// BssrdfSample -> `bssrdf_sample_*`, Probe -> `bssrdf_probe_sample`, `bssrdf_probe_chord`
// (Probe::ray, renamed so as not to clash with the free `probe_ray`) and `bssrdf_probe_trace`.
// `Option<T>` returns are `bool f(..., out T)`; `Result<T, InvertFail>` returns are
// `uint f(..., out T)` with BSSRDF_INVERT_OK or an InvertFail code below.
//
// Representation: a Technique is its index `axis * 3 + channel`; a Burley profile is its `d`; a
// Translucent is a GpuMaterial, and an ExitPoint carries its `d` and `r_max` per channel as the
// host computed them (never re-derived here). Hit lists are bvh.glsl's `bvh_hits` /
// `bvh_hit_count`, sorted by (t, prim) as Geometry::all_hits_on_object; the count goes on past
// BVH_MAX_HITS, which an including shader may raise with a #define before the include (the
// built-in scenes reach 8 hits per probe, engine/tests/vulkan_bssrdf.rs).
//
// Every arithmetic local is `precise` (no fused multiply-add) and glam's operation order is kept
// (frame.glsl's glam_* helpers for Vec3).

#ifndef SSS_BSSRDF_GLSL
#define SSS_BSSRDF_GLSL

#include "scene.glsl"
#include "burley.glsl"
#include "xie.glsl"
#include "dipole.glsl"
// BSSRDF_TECHNIQUE_COUNT, BSSRDF_INDEX_UNKNOWN, the axes BSSRDF_AXIS_*, the InvertFail codes
// BSSRDF_INVERT_* and the radius samplers BSSRDF_RADIUS_* (sss/src/contract.rs).
#include "contract/sss.glsl"

// std::f32::consts::TAU and FRAC_1_PI, as f32.
const float BSSRDF_TAU = 6.28318548202514648;
const float BSSRDF_FRAC_1_PI = 0.318309873342514038;
// 1.0f32 / 3.0 (Rust rounds the quotient once to f32).
const float BSSRDF_ONE_THIRD = 0.333333343267440796;

// ---------------------------------------------------------------- glam arithmetic

// Vec2::length: sqrt(x x + y y).
float bssrdf_length2(vec2 a) {
    precise float r = sqrt(a.x * a.x + a.y * a.y);
    return r;
}

// Vec3::max_element (finite inputs).
float bssrdf_max_element(vec3 v) {
    return max(max(v.x, v.y), v.z);
}

// Adding +0 turns -0 components into +0 (Ray::new's `dir + Vec3A::ZERO`).
vec3 bssrdf_plus_zero(vec3 v) {
    return vec3(v.x == 0.0 ? 0.0 : v.x, v.y == 0.0 ? 0.0 : v.y, v.z == 0.0 ? 0.0 : v.z);
}

// ---------------------------------------------------------------- technique.rs

uint bssrdf_technique_axis(uint t) {
    return t / 3u;
}

uint bssrdf_technique_channel(uint t) {
    return t % 3u;
}

// P(a) for normal, tangent, bitangent and P(c) for R, G, B.
struct TechniqueSelection {
    vec3 axis;
    vec3 channel;
};

// TechniqueSelection::default: axes 0.5 / 0.25 / 0.25, channels uniform (paper 001).
TechniqueSelection bssrdf_selection_default() {
    TechniqueSelection s;
    s.axis = vec3(0.5, 0.25, 0.25);
    s.channel = vec3(BSSRDF_ONE_THIRD);
    return s;
}

// TechniqueSelection::with_channel_weights: false unless every weight is finite and >= 0 and
// their sum is > 0 and finite.
bool bssrdf_selection_with_channel_weights(vec3 weights, out TechniqueSelection s) {
    s = bssrdf_selection_default();
    precise float sum = weights.x + weights.y + weights.z;
    for (int c = 0; c < 3; c++) {
        float w = weights[c];
        if (isnan(w) || isinf(w) || !(w >= 0.0)) {
            return false;
        }
    }
    if (!(sum > 0.0 && !isinf(sum))) {
        return false;
    }
    precise vec3 channel = vec3(weights.x / sum, weights.y / sum, weights.z / sum);
    s.channel = channel;
    return true;
}

// P(a) P(c).
float bssrdf_selection_probability(TechniqueSelection s, uint t) {
    precise float p = s.axis[bssrdf_technique_axis(t)] * s.channel[bssrdf_technique_channel(t)];
    return p;
}

// The technique whose cumulative interval (in index order) contains u; never one of probability 0.
uint bssrdf_selection_sample(TechniqueSelection s, float u) {
    precise float cumulative = 0.0;
    uint last = 0u;
    for (uint t = 0u; t < BSSRDF_TECHNIQUE_COUNT; t++) {
        float p = bssrdf_selection_probability(s, t);
        if (p <= 0.0) {
            continue;
        }
        cumulative = cumulative + p;
        last = t;
        if (u < cumulative) {
            return t;
        }
    }
    return last;
}

// RadiusSampling::sample_radius: the disk radius for u under the Burley profile of `d`.
float bssrdf_radius_sample_radius(uint radius, float d, float u) {
    if (radius == BSSRDF_RADIUS_XIE) {
        return xie_sample_radius(d, u);
    }
    return burley_sample_radius(d, u);
}

// RadiusSampling::pdf_disk: the disk-area density of bssrdf_radius_sample_radius at r.
float bssrdf_radius_pdf_disk(uint radius, float d, float r) {
    if (radius == BSSRDF_RADIUS_XIE) {
        return xie_pdf_disk(d, r);
    }
    return burley_pdf_disk(d, r);
}

// Inverse of bssrdf_selection_sample: the interval [lo, hi) of u that selects t, as vec2(lo, hi).
vec2 bssrdf_selection_u_interval(TechniqueSelection s, uint t) {
    precise float lo = 0.0;
    for (uint k = 0u; k < t; k++) {
        lo = lo + bssrdf_selection_probability(s, k);
    }
    precise float hi = lo + bssrdf_selection_probability(s, t);
    return vec2(lo, hi);
}

// ---------------------------------------------------------------- probe.rs

// The exit point x1: frame of the camera-facing geometric normal (t, b, n), shading normal on the
// same side, unit view direction, object, the per-channel profile `d` and `r_max`, and the
// material's Fresnel transmittance.
struct ExitPoint {
    vec3 position;
    Frame frame;
    vec3 shading_normal;
    vec3 view;
    uint object;
    vec3 d;
    vec3 r_max;
    FresnelTransmission fresnel;
};

// ExitPoint::with_profiles: x1 with explicit per-channel profiles `d` and their `r_max` (the
// host computes r_max; the CPU derives it from d) and Fresnel transmittance.
ExitPoint bssrdf_exit_point_with_profiles(vec3 position, vec3 geometric_normal,
        vec3 shading_normal, vec3 view, uint object, vec3 d, vec3 r_max,
        FresnelTransmission fresnel) {
    ExitPoint x1;
    x1.position = position;
    x1.shading_normal = glam_dot(shading_normal, geometric_normal) < 0.0 ? -shading_normal
                                                                           : shading_normal;
    x1.frame = frame_from_normal(geometric_normal);
    x1.view = view;
    x1.object = object;
    x1.d = d;
    x1.r_max = r_max;
    x1.fresnel = fresnel;
    return x1;
}

// ExitPoint::new: `geometric_normal` must already face the camera; the shading normal is flipped
// to its side. The profiles are the material's host-computed `d` and `r_max`.
ExitPoint bssrdf_exit_point_new(vec3 position, vec3 geometric_normal, vec3 shading_normal,
        vec3 view, uint object, GpuMaterial material) {
    return bssrdf_exit_point_with_profiles(position, geometric_normal, shading_normal, view,
        object, material_d(material), material_r_max(material), material_fresnel(material));
}

// ExitPoint::disk_basis: normal (t, b, n), tangent (b, n, t), bitangent (n, t, b).
void bssrdf_exit_point_disk_basis(ExitPoint x1, uint axis, out vec3 px, out vec3 py, out vec3 pz) {
    if (axis == BSSRDF_AXIS_NORMAL) {
        px = x1.frame.t;
        py = x1.frame.b;
        pz = x1.frame.n;
    } else if (axis == BSSRDF_AXIS_TANGENT) {
        px = x1.frame.b;
        py = x1.frame.n;
        pz = x1.frame.t;
    } else {
        px = x1.frame.n;
        py = x1.frame.t;
        pz = x1.frame.b;
    }
}

// ExitPoint::disk_coordinates: (l.p_x, l.p_y), l = x2 - x1.
vec2 bssrdf_exit_point_disk_coordinates(ExitPoint x1, uint axis, vec3 x2) {
    vec3 px, py, pz;
    bssrdf_exit_point_disk_basis(x1, axis, px, py, pz);
    precise vec3 l = x2 - x1.position;
    return vec2(glam_dot(l, px), glam_dot(l, py));
}

// The entry point x2: triangle, barycentrics, position, geometric normal (winding), shading normal.
struct EntryPoint {
    uint object;
    uint prim;
    vec2 bary;
    vec3 position;
    vec3 geometric_normal;
    vec3 shading_normal;
};

// EntryPoint::new.
EntryPoint bssrdf_entry_point_new(uint prim, vec2 bary) {
    EntryPoint x2;
    x2.object = scene_object_of(prim);
    x2.prim = prim;
    x2.bary = bary;
    x2.position = scene_position(prim, bary);
    x2.geometric_normal = scene_geometric_normal(prim);
    x2.shading_normal = scene_shading_normal(prim, bary);
    return x2;
}

// EntryPoint::from_hit.
EntryPoint bssrdf_entry_point_from_hit(BvhHit hit) {
    return bssrdf_entry_point_new(hit.prim, hit.bary);
}

// geometry::Ray: points origin + t dir, t_min < t < t_max.
struct BssrdfRay {
    vec3 origin;
    vec3 dir;
    float t_min;
    float t_max;
};

// chord: the chord of the r_max,c sphere along -axis through the disk point `disk`;
// false when r >= r_max,c.
bool bssrdf_chord(ExitPoint x1, uint t, vec2 disk, out BssrdfRay ray) {
    ray.origin = vec3(0.0);
    ray.dir = vec3(0.0);
    ray.t_min = 0.0;
    ray.t_max = 0.0;
    float r_max = x1.r_max[bssrdf_technique_channel(t)];
    precise float h2 = r_max * r_max - (disk.x * disk.x + disk.y * disk.y);
    if (isnan(h2) || h2 <= 0.0) {
        return false;
    }
    precise float h = sqrt(h2);
    vec3 px, py, axis;
    bssrdf_exit_point_disk_basis(x1, bssrdf_technique_axis(t), px, py, axis);
    precise vec3 q = x1.position + disk.x * px + disk.y * py;
    precise vec3 origin = q + h * axis;
    precise float t_max = 2.0 * h;
    ray.origin = origin;
    ray.dir = bssrdf_plus_zero(-axis);
    ray.t_max = t_max;
    return true;
}

// probe_ray_with: probe_ray with the radius drawn by `radius` (RadiusSampling).
bool bssrdf_probe_ray_with(ExitPoint x1, uint t, uint radius, float u_radius, float u_angle,
        out BssrdfRay ray) {
    float r = bssrdf_radius_sample_radius(radius, x1.d[bssrdf_technique_channel(t)], u_radius);
    precise float phi = BSSRDF_TAU * u_angle;
    float c = cos(phi);
    float s = sin(phi);
    precise vec2 disk = vec2(r * c, r * s);
    return bssrdf_chord(x1, t, disk, ray);
}

// probe_ray: radius by the exact inverse CDF of channel c, angle 2 pi u_angle [001 Eq. 4, Fig. 2b].
bool bssrdf_probe_ray(ExitPoint x1, uint t, float u_radius, float u_angle, out BssrdfRay ray) {
    return bssrdf_probe_ray_with(x1, t, BSSRDF_RADIUS_EXACT, u_radius, u_angle, ray);
}

// trace_probe: every hit of `ray` on x1's object into bvh_hits, sorted by (t, prim);
// bvh_hit_count counts them all (also those beyond BVH_MAX_HITS).
void bssrdf_trace_probe(ExitPoint x1, BssrdfRay ray) {
    BvhRay prepared;
    bvh_hit_count = 0u;
    if (bvh_prepare(ray.origin, ray.dir, ray.t_min, ray.t_max, prepared)) {
        bvh_traverse(prepared, BVH_ALL_HITS, x1.object);
    }
}

// ---------------------------------------------------------------- sample.rs

// One BSSRDF IS draw before tracing: technique index and its two random numbers.
struct Probe {
    uint technique;
    float u_radius;
    float u_angle;
};

// Probe::sample.
Probe bssrdf_probe_sample(TechniqueSelection selection, float u_technique, float u_radius,
        float u_angle) {
    return Probe(bssrdf_selection_sample(selection, u_technique), u_radius, u_angle);
}

// Probe::ray_with: the chord with the radius drawn by `radius`.
bool bssrdf_probe_chord_with(Probe probe, ExitPoint x1, uint radius, out BssrdfRay ray) {
    return bssrdf_probe_ray_with(x1, probe.technique, radius, probe.u_radius, probe.u_angle, ray);
}

// Probe::ray.
bool bssrdf_probe_chord(Probe probe, ExitPoint x1, out BssrdfRay ray) {
    return bssrdf_probe_chord_with(probe, x1, BSSRDF_RADIUS_EXACT, ray);
}

// Probe::trace_with: the chord's hits on x1's object (none for an empty chord), radius by `radius`.
void bssrdf_probe_trace_with(Probe probe, ExitPoint x1, uint radius) {
    BssrdfRay ray;
    if (bssrdf_probe_chord_with(probe, x1, radius, ray)) {
        bssrdf_trace_probe(x1, ray);
    } else {
        bvh_hit_count = 0u;
    }
}

// Probe::trace.
void bssrdf_probe_trace(Probe probe, ExitPoint x1) {
    bssrdf_probe_trace_with(probe, x1, BSSRDF_RADIUS_EXACT);
}

// pick_hit over bvh_hits: rank `index`, or with index == BSSRDF_INDEX_UNKNOWN one picked uniformly
// with u_pick. False if there is no such hit, or (counted by the caller through bvh_hit_count)
// when the rank lies beyond the BVH_MAX_HITS stored hits.
bool bssrdf_pick_hit(uint index, float u_pick, out uint rank, out BvhHit hit) {
    rank = 0u;
    hit = BvhHit(0.0, BVH_NO_HIT, BVH_NO_HIT, vec2(0.0));
    uint count = bvh_hit_count;
    if (index != BSSRDF_INDEX_UNKNOWN) {
        rank = index;
    } else if (count == 0u) {
        return false;
    } else {
        precise float scaled = u_pick * float(count);
        rank = min(uint(scaled), count - 1u);
    }
    if (rank >= min(count, uint(BVH_MAX_HITS))) {
        return false;
    }
    hit = bvh_hits[rank];
    return true;
}

// The part of a reservoir sample that BSSRDF IS owns [001 Alg. 3]; `index` is
// BSSRDF_INDEX_UNKNOWN for None.
struct BssrdfSample {
    uint object;
    uint prim;
    vec2 bary;
    uint technique;
    float u_radius;
    float u_angle;
    uint index;
    float p_disk;
};

// BssrdfSample::new.
BssrdfSample bssrdf_sample_new(Probe probe, uint index, EntryPoint x2, float p_disk) {
    return BssrdfSample(x2.object, x2.prim, x2.bary, probe.technique, probe.u_radius,
        probe.u_angle, index, p_disk);
}

// BssrdfSample::probe.
Probe bssrdf_sample_probe(BssrdfSample s) {
    return Probe(s.technique, s.u_radius, s.u_angle);
}

// ---------------------------------------------------------------- pdf.rs

// technique_terms_with: P(a) P(c) p_{d_c}(r_a) |n2.axis_a| 1[|x2 - x1| <= r_max,c] per technique,
// p_{d_c} the density of the radius sampler `radius`.
void bssrdf_technique_terms_with(ExitPoint x1, TechniqueSelection selection, uint radius, vec3 x2,
        vec3 n2, out float terms[9]) {
    precise vec3 l = x2 - x1.position;
    precise float distance2 = glam_dot(l, l);
    for (uint t = 0u; t < BSSRDF_TECHNIQUE_COUNT; t++) {
        float p = bssrdf_selection_probability(selection, t);
        uint c = bssrdf_technique_channel(t);
        float r_max = x1.r_max[c];
        precise float r_max2 = r_max * r_max;
        if (p <= 0.0 || distance2 > r_max2) {
            terms[t] = 0.0;
            continue;
        }
        uint a = bssrdf_technique_axis(t);
        float r_a = bssrdf_length2(bssrdf_exit_point_disk_coordinates(x1, a, x2));
        vec3 px, py, axis;
        bssrdf_exit_point_disk_basis(x1, a, px, py, axis);
        precise float term = p * bssrdf_radius_pdf_disk(radius, x1.d[c], r_a)
            * abs(glam_dot(n2, axis));
        terms[t] = term;
    }
}

// technique_terms: the terms of the exact radius sampler.
void bssrdf_technique_terms(ExitPoint x1, TechniqueSelection selection, vec3 x2, vec3 n2,
        out float terms[9]) {
    bssrdf_technique_terms_with(x1, selection, BSSRDF_RADIUS_EXACT, x2, n2, terms);
}

// p_disk_with: the sum of the technique terms of the radius sampler `radius`.
float bssrdf_p_disk_with(ExitPoint x1, TechniqueSelection selection, uint radius, vec3 x2,
        vec3 n2) {
    float terms[9];
    bssrdf_technique_terms_with(x1, selection, radius, x2, n2, terms);
    precise float sum = 0.0;
    for (uint t = 0u; t < BSSRDF_TECHNIQUE_COUNT; t++) {
        sum = sum + terms[t];
    }
    return sum;
}

// p_disk(x2 | x1): the sum of the technique terms (DESIGN §9).
float bssrdf_p_disk(ExitPoint x1, TechniqueSelection selection, vec3 x2, vec3 n2) {
    return bssrdf_p_disk_with(x1, selection, BSSRDF_RADIUS_EXACT, x2, n2);
}

// ---------------------------------------------------------------- eval.rs

// bssrdf_of_profile: S = R(|x1 - x2|)/pi F_t(n1.wo) F_t(n2.wi) for a profile value per channel
// (any sign; the caller truncates), with x1's Fresnel transmittance [001 Eq. 2].
vec3 bssrdf_bssrdf_of_profile(vec3 profile, ExitPoint x1, EntryPoint x2, vec3 wi) {
    precise float fresnel = fresnel_transmission_eval(x1.fresnel, glam_dot(x1.shading_normal, x1.view))
        * fresnel_transmission_eval(x1.fresnel, glam_dot(x2.shading_normal, wi));
    precise vec3 s = profile * (BSSRDF_FRAC_1_PI * fresnel);
    return s;
}

// bssrdf: S = (A/pi) R_d(|x1 - x2|) F_t(n1.wo) F_t(n2.wi) per channel [001 Eq. 2-3], truncated at
// the widest r_max of x1's cached profiles; F_t is x1's cached FresnelTransmission.
vec3 bssrdf_bssrdf(GpuMaterial material, ExitPoint x1, EntryPoint x2, vec3 wi) {
    float r = glam_length(x2.position - x1.position);
    if (r > bssrdf_max_element(x1.r_max)) {
        return vec3(0.0);
    }
    vec3 profile = vec3(burley_pdf_disk(x1.d.x, r), burley_pdf_disk(x1.d.y, r),
        burley_pdf_disk(x1.d.z, r));
    return bssrdf_bssrdf_of_profile(material_albedo(material) * profile, x1, x2, wi);
}

// contribution: f = S max(0, n2.wi) L_e, unshadowed (eval.rs's `lit` inlined).
vec3 bssrdf_contribution(GpuMaterial material, ExitPoint x1, EntryPoint x2, vec3 wi,
        vec3 radiance) {
    float cos_i = glam_dot(x2.shading_normal, wi);
    if (isnan(cos_i) || cos_i <= 0.0) {
        return vec3(0.0);
    }
    precise vec3 f = bssrdf_bssrdf(material, x1, x2, wi) * cos_i * radiance;
    return f;
}

// target: p-hat = luminance(f), unshadowed.
float bssrdf_target(vec3 f) {
    return luminance(f);
}

// ---------------------------------------------------------------- invert.rs

// invert_technique: u_radius = CDF_{d_c}(r_a), u_angle = atan2(l_y, l_x) / 2 pi wrapped to [0, 1)
// [001 Alg. 4, lines 2-9].
Probe bssrdf_invert_technique(ExitPoint x1, uint t, vec3 x2) {
    vec2 disk = bssrdf_exit_point_disk_coordinates(x1, bssrdf_technique_axis(t), x2);
    float u_radius = burley_cdf(x1.d[bssrdf_technique_channel(t)], bssrdf_length2(disk));
    float angle = atan(disk.y, disk.x);
    precise float u = angle / BSSRDF_TAU;
    precise float wrapped = u < 0.0 ? u + 1.0 : u;
    float u_angle = wrapped < 1.0 ? wrapped : 0.0;
    return Probe(t, u_radius, u_angle);
}

// invert_random_numbers: the technique drawn from its posterior with gamma [001 Alg. 4, line 1],
// inverted; also p_disk(x2 | x1). Traces no ray.
uint bssrdf_invert_random_numbers(ExitPoint x1, TechniqueSelection selection, EntryPoint x2,
        float gamma, out Probe probe, out float p_disk) {
    probe = Probe(0u, 0.0, 0.0);
    float terms[9];
    bssrdf_technique_terms(x1, selection, x2.position, x2.geometric_normal, terms);
    precise float sum = 0.0;
    for (uint t = 0u; t < BSSRDF_TECHNIQUE_COUNT; t++) {
        sum = sum + terms[t];
    }
    p_disk = sum;
    if (!(sum > 0.0 && !isinf(sum))) {
        return BSSRDF_INVERT_OUT_OF_SUPPORT;
    }
    precise float threshold = gamma * sum;
    precise float cumulative = 0.0;
    uint chosen = BSSRDF_TECHNIQUE_COUNT;
    for (uint t = 0u; t < BSSRDF_TECHNIQUE_COUNT; t++) {
        if (terms[t] <= 0.0) {
            continue;
        }
        cumulative = cumulative + terms[t];
        chosen = t;
        if (threshold < cumulative) {
            break;
        }
    }
    if (chosen == BSSRDF_TECHNIQUE_COUNT) {
        return BSSRDF_INVERT_OUT_OF_SUPPORT;
    }
    probe = bssrdf_invert_technique(x1, chosen, x2.position);
    return BSSRDF_INVERT_OK;
}

// find_index: re-traces the chord of `probe` at x1 and returns the rank of the hit on x2's triangle
// whose t matches x2 within 1e-3 r_max,c; false if there is none among the stored hits.
bool bssrdf_find_index(ExitPoint x1, Probe probe, EntryPoint x2, out uint index) {
    index = BSSRDF_INDEX_UNKNOWN;
    BssrdfRay ray;
    if (!bssrdf_probe_chord(probe, x1, ray)) {
        return false;
    }
    bssrdf_trace_probe(x1, ray);
    float t_x2 = glam_dot(x2.position - ray.origin, ray.dir);
    precise float tolerance = 1e-3 * x1.r_max[bssrdf_technique_channel(probe.technique)];
    uint stored = min(bvh_hit_count, uint(BVH_MAX_HITS));
    for (uint i = 0u; i < stored; i++) {
        precise float dt = bvh_hits[i].t - t_x2;
        if (bvh_hits[i].prim == x2.prim && abs(dt) <= tolerance) {
            index = i;
            return true;
        }
    }
    return false;
}

// invert: probabilistic inversion with the exact index policy.
uint bssrdf_invert(ExitPoint x1, TechniqueSelection selection, EntryPoint x2, float gamma,
        out BssrdfSample result) {
    Probe probe;
    float p_disk;
    result = BssrdfSample(0u, 0u, vec2(0.0), 0u, 0.0, 0.0, BSSRDF_INDEX_UNKNOWN, 0.0);
    uint fail = bssrdf_invert_random_numbers(x1, selection, x2, gamma, probe, p_disk);
    if (fail != BSSRDF_INVERT_OK) {
        return fail;
    }
    uint index;
    if (!bssrdf_find_index(x1, probe, x2, index)) {
        return BSSRDF_INVERT_INDEX_NOT_FOUND;
    }
    result = bssrdf_sample_new(probe, index, x2, p_disk);
    return BSSRDF_INVERT_OK;
}

// ---------------------------------------------------------------- dipole.rs

// bssrdf_dipole: S = R_d(|x1 - x2|)/pi F_t(n1.wo) F_t(n2.wi) with the dipole profile, truncated at
// r_max_all, and x1's Fresnel transmittance (bssrdf_of_profile).
vec3 bssrdf_bssrdf_dipole(GpuDipoleProfiles dipoles, ExitPoint x1, EntryPoint x2, vec3 wi) {
    float r = glam_length(x2.position - x1.position);
    return bssrdf_bssrdf_of_profile(dipole_profiles_profile_rgb(dipoles, r), x1, x2, wi);
}

// contribution_dipole: f = S max(0, n2.wi) L_e with the dipole profile, unshadowed (eval.rs's
// `lit` inlined, as in bssrdf_contribution).
vec3 bssrdf_contribution_dipole(GpuDipoleProfiles dipoles, ExitPoint x1, EntryPoint x2, vec3 wi,
        vec3 radiance) {
    float cos_i = glam_dot(x2.shading_normal, wi);
    if (isnan(cos_i) || cos_i <= 0.0) {
        return vec3(0.0);
    }
    precise vec3 f = bssrdf_bssrdf_dipole(dipoles, x1, x2, wi) * cos_i * radiance;
    return f;
}

#endif
