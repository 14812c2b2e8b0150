// One integration domain of ReSTIR SSS, a pixel at a frame with its exit point x1: the GLSL twin
// of shifts/src/domain.rs (SssDomain; read the two side by side) and of the hybrid criterion of
// shifts/src/hybrid.rs (Hybrid::{for_material, connectable, uses_reconnection}), DESIGN §4, §9.
//
// Include after `#define SCENE_BINDING ...`; the including shader enables
// GL_EXT_shader_explicit_arithmetic_types_int64. Names are `domain_<rust name>` and
// `hybrid_<rust name>`; `Option<T>` returns are `bool f(..., out T)`.

#ifndef SHIFTS_DOMAIN_GLSL
#define SHIFTS_DOMAIN_GLSL

#include "rng.glsl"
#include "sample.glsl"
#include "bssrdf.glsl"

// SHADOW_EPSILON and the shifts' stream purposes PURPOSE_INVERSION, PURPOSE_PICK and
// PARTNER_PIXEL_MASK come from the contract (shifts/src/contract.rs, via sample.glsl).

// The domain of one pixel: its translucent material, x1, the technique selection, the target
// function (a TARGET_* code; the pass kernels set the preset's, as SssDomain::with_target) and
// the stream key fields.
struct SssDomain {
    GpuMaterial material;
    ExitPoint x1;
    TechniqueSelection selection;
    uint target;
    uint pixel;
    uint frame;
    uint pass;
    uint64_t seed;
};

// Direction toward the light vertex seen from x2, what the light sends along it, and the end of
// the shadow segment (LightPath).
struct LightPath {
    vec3 wi;
    vec3 radiance;
    vec3 shadow_target;
};

vec3 domain_gpixel_vec3(float v[3]) {
    return vec3(v[0], v[1], v[2]);
}

// SssSample::new (shifts/src/sample.rs): the BSSRDF part `b` and the light vertex x3 on `light`.
SssSample sss_sample_new(BssrdfSample b, uint light, vec3 x3) {
    SssSample s;
    s.x3 = float[3](x3.x, x3.y, x3.z);
    s.light = light;
    s.bary = float[2](b.bary.x, b.bary.y);
    s.object = b.object;
    s.prim = b.prim;
    s.technique = b.technique;
    s.u_radius = b.u_radius;
    s.u_angle = b.u_angle;
    s.index = b.index;
    s.p_disk = b.p_disk;
    return s;
}

// SssDomain::new for G-buffer pixel `gpixel`: false if x1 is not on a translucent object (or, as
// the caller's `Option<GPixel>` is folded into `valid`, if the pixel has no primary hit).
// BSSRDF IS uses paper 001's technique selection.
bool domain_new(GPixel gpixel, uint pixel, uint frame, uint pass, uint64_t seed,
        out SssDomain domain) {
    domain.pixel = pixel;
    domain.frame = frame;
    domain.pass = pass;
    domain.seed = seed;
    domain.selection = bssrdf_selection_default();
    domain.target = TARGET_LUMINANCE;
    if (gpixel.valid == 0u || gpixel.object >= uint(scene_objects.length())) {
        return false;
    }
    uint material = scene_material_of_object(gpixel.object);
    if (material >= uint(scene_materials.length())) {
        return false;
    }
    domain.material = scene_materials[material];
    if (domain.material.kind != MATERIAL_TRANSLUCENT) {
        return false;
    }
    domain.x1 = bssrdf_exit_point_new(domain_gpixel_vec3(gpixel.position),
        domain_gpixel_vec3(gpixel.geometric_normal), domain_gpixel_vec3(gpixel.shading_normal),
        domain_gpixel_vec3(gpixel.view), gpixel.object, domain.material);
    return true;
}

// SssDomain::entry_point: x2 of `y`; false if its triangle does not exist or lies on another
// object than x1.
bool domain_entry_point(SssDomain domain, SssSample y, out EntryPoint x2) {
    x2 = EntryPoint(0u, 0u, vec2(0.0), vec3(0.0), vec3(0.0), vec3(0.0));
    if (y.prim >= uint(scene_triangles.length()) || scene_object_of(y.prim) != y.object) {
        return false;
    }
    if (y.object != domain.x1.object) {
        return false;
    }
    x2 = bssrdf_entry_point_new(y.prim, sample_bary(y));
    return true;
}

// SssDomain::p_disk: p_disk(x2 | x1) of this domain's x1.
float domain_p_disk(SssDomain domain, EntryPoint x2) {
    return bssrdf_p_disk(domain.x1, domain.selection, x2.position, x2.geometric_normal);
}

// SssDomain::light_path: false for an unknown light or x3 = x2. A directional light sends its
// irradiance along -direction, its segment ends DIRECTIONAL_DISTANCE away.
bool domain_light_path(SssDomain domain, vec3 x2, SssSample y, out LightPath path) {
    path = LightPath(vec3(0.0), vec3(0.0), vec3(0.0));
    if (y.light >= LIGHT_COUNT) {
        return false;
    }
    if (scene_lights[y.light].kind == LIGHT_DIRECTIONAL) {
        vec3 wi = -light_p0(y.light);
        precise vec3 shadow_target = x2 + LIGHT_DIRECTIONAL_DISTANCE * wi;
        path = LightPath(wi, light_emission(y.light), shadow_target);
        return true;
    }
    vec3 x3 = sample_x3(y);
    vec3 wi;
    if (!glam_try_normalize(x3 - x2, wi)) {
        return false;
    }
    path = LightPath(wi, lights_radiance(y.light, x3, x2), x3);
    return true;
}

// SssDomain::contribution: f(y) = S max(0, n2.wi) L_e, unshadowed, RGB; 0 outside the support
// and where not finite.
vec3 domain_contribution(SssDomain domain, SssSample y) {
    EntryPoint x2;
    if (!domain_entry_point(domain, y, x2)) {
        return vec3(0.0);
    }
    LightPath light;
    if (!domain_light_path(domain, x2.position, y, light)) {
        return vec3(0.0);
    }
    vec3 f = bssrdf_contribution(domain.material, domain.x1, x2, light.wi, light.radiance);
    bool finite = !any(isnan(f)) && !any(isinf(f));
    return finite ? f : vec3(0.0);
}

// SssDomain::visible: whether the segment x2-x3 of `y` is unoccluded; false outside the support.
bool domain_visible(SssDomain domain, SssSample y) {
    EntryPoint x2;
    if (!domain_entry_point(domain, y, x2)) {
        return false;
    }
    LightPath light;
    if (!domain_light_path(domain, x2.position, y, light)) {
        return false;
    }
    vec3 n = x2.geometric_normal;
    float side = glam_dot(n, light.wi) < 0.0 ? -1.0 : 1.0;
    precise vec3 from = x2.position + side * SHADOW_EPSILON * n;
    precise vec3 to = light.shadow_target - SHADOW_EPSILON * light.wi;
    // Ray::segment(from, to): dir = to - from, t in (0, 1).
    precise vec3 dir = to - from;
    BvhRay ray;
    if (!bvh_prepare(from, dir, 0.0, 1.0, ray)) {
        return true;
    }
    return bvh_traverse(ray, BVH_OCCLUDED, BVH_NO_HIT).prim == BVH_NO_HIT;
}

// Target::of (shifts/src/target.rs) for the targets with a kernel: the luminance and the channels
// (channel selection is exact, so it matches the CPU bit for bit). TARGET_MEAN and TARGET_L2 are
// CPU-only; the renderer refuses them.
float domain_target_of(uint target, vec3 f) {
    switch (target) {
    case TARGET_RED:
        return f.x;
    case TARGET_GREEN:
        return f.y;
    case TARGET_BLUE:
        return f.z;
    default:
        return bssrdf_target(f);
    }
}

// Domain::target: p-hat of the domain's target of f, unshadowed, clamped below at 0 (f32::max).
float domain_target(SssDomain domain, SssSample y) {
    return rust_max(domain_target_of(domain.target, domain_contribution(domain, y)), 0.0);
}

// SssDomain::shift_stream: the stream of a shift's random numbers used at `domain` when it is
// paired with `partner`, keyed (pixel, frame, pass, purpose | partner pixel & 0x3FFF_FFFF) under
// the run seed.
Stream domain_shift_stream(SssDomain domain, uint purpose, SssDomain partner) {
    uint tagged = purpose | (partner.pixel & PARTNER_PIXEL_MASK);
    return stream_new(StreamKey(domain.pixel, domain.frame, domain.pass, tagged), domain.seed);
}

// ---------------------------------------------------------------- hybrid.rs (criterion only)

// Thresholds of the hybrid shift: kappa_dist (scene units) and kappa_orient (cosine).
struct Hybrid {
    float kappa_dist;
    float kappa_orient;
};

// Hybrid::for_material: paper 001's defaults [001 §5.1], kappa_dist = 2 max_c d_c (host value
// GpuMaterial::kappa_dist), kappa_orient = 0.5.
Hybrid hybrid_for_material(GpuMaterial material) {
    return Hybrid(material.kappa_dist, 0.5);
}

// Hybrid::connectable: |x2 - x1| >= kappa_dist or n1.n2 <= kappa_orient (geometric normals)
// [001 §4.1].
bool hybrid_connectable(Hybrid hybrid, ExitPoint x1, EntryPoint x2) {
    return glam_length(x2.position - x1.position) >= hybrid.kappa_dist
        || glam_dot(x1.frame.n, x2.geometric_normal) <= hybrid.kappa_orient;
}

// Hybrid::uses_reconnection: whether the shift of `x` out of `src` uses reconnection; false
// (None) if x2 is not on src's object.
bool hybrid_uses_reconnection(Hybrid hybrid, SssSample x, SssDomain src, out bool reconnection) {
    reconnection = false;
    EntryPoint x2;
    if (!domain_entry_point(src, x, x2)) {
        return false;
    }
    reconnection = hybrid_connectable(hybrid, src.x1, x2);
    return true;
}

#endif
