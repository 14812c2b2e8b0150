// Twin of sss::scene::{Light, Lights, LightSample, luminance} (sss/src/scene/light.rs), read it
// side by side. The selection CDF and pmf are the CPU's own values, uploaded per light.
//
// Included by scene.glsl (which declares FrameParams first): the lights live at binding
// SCENE_BINDING + 7 and LIGHT_COUNT names the light count. Per-light functions take the light's
// index, as Lights' methods do.

#ifndef SSS_LIGHT_GLSL
#define SSS_LIGHT_GLSL

#include "frame.glsl"
// GpuLight and its kinds LIGHT_<KIND> (engine/src/contract.rs).
#include "contract/engine.glsl"
// LIGHT_DIRECTIONAL_DISTANCE (sss/src/contract.rs).
#include "contract/sss.glsl"

const float LIGHT_PI = 3.14159265358979323846;


// A point sampled on a light as seen from x2 (LightSample).
struct LightSample {
    uint light;
    vec3 point;
    vec3 normal;
    vec3 wi;
    float distance;
    vec3 radiance;
    float pdf;
    bool is_delta;
};

layout(std430, binding = SCENE_BINDING + 7) readonly buffer SceneLights { GpuLight scene_lights[]; };

// Rec. 709 luminance.
float luminance(vec3 c) {
    return glam_dot(c, vec3(0.2126, 0.7152, 0.0722));
}

vec3 light_p0(uint light) {
    return vec3(scene_lights[light].p0[0], scene_lights[light].p0[1], scene_lights[light].p0[2]);
}

vec3 light_p1(uint light) {
    return vec3(scene_lights[light].p1[0], scene_lights[light].p1[1], scene_lights[light].p1[2]);
}

vec3 light_p2(uint light) {
    return vec3(scene_lights[light].p2[0], scene_lights[light].p2[1], scene_lights[light].p2[2]);
}

vec3 light_emission(uint light) {
    GpuLight l = scene_lights[light];
    return vec3(l.emission[0], l.emission[1], l.emission[2]);
}

// Light::Triangle's two_sided (quads and other kinds: false).
bool light_two_sided(uint light) {
    return scene_lights[light].two_sided != 0u;
}

// Light::is_delta.
bool light_is_delta(uint light) {
    uint kind = scene_lights[light].kind;
    return kind == LIGHT_POINT || kind == LIGHT_DIRECTIONAL;
}

// Unnormalised normal of a quad (edge_u x edge_v) or a triangle ((v1 - v0) x (v2 - v0)).
vec3 light_face_normal(uint light) {
    if (scene_lights[light].kind == LIGHT_QUAD) {
        return glam_cross(light_p1(light), light_p2(light));
    }
    precise vec3 e1 = light_p1(light) - light_p0(light);
    precise vec3 e2 = light_p2(light) - light_p0(light);
    return glam_cross(e1, e2);
}

// Light::radiance: L_e leaving `point` toward `toward`.
vec3 light_radiance(uint light, vec3 point, vec3 toward) {
    uint kind = scene_lights[light].kind;
    precise vec3 out_dir = toward - point;
    if (kind == LIGHT_QUAD || kind == LIGHT_TRIANGLE) {
        bool emits = light_two_sided(light) || glam_dot(light_face_normal(light), out_dir) > 0.0;
        return emits ? light_emission(light) : vec3(0.0);
    }
    if (kind == LIGHT_SPHERE) {
        precise vec3 outward = point - light_p0(light);
        return glam_dot(outward, out_dir) > 0.0 ? light_emission(light) : vec3(0.0);
    }
    if (kind == LIGHT_POINT) {
        float d2 = glam_distance_squared(point, toward);
        precise vec3 e = light_emission(light) / d2;
        return d2 > 0.0 ? e : vec3(0.0);
    }
    return light_emission(light);
}

// area_to_solid_angle: ‖p − x‖² / (area · cos θ_l), 0 from behind unless two-sided (|cos θ_l|).
float light_area_to_solid_angle(vec3 x, vec3 p, vec3 n, float area, bool two_sided) {
    precise vec3 to_x = x - p;
    float d2 = glam_length_squared(to_x);
    precise float cos_facing = glam_dot(n, to_x) / sqrt(d2);
    precise float cos_l = two_sided ? abs(cos_facing) : cos_facing;
    if (cos_l > 0.0 && area > 0.0 && d2 > 0.0) {
        precise float pdf = d2 / (area * cos_l);
        return pdf;
    }
    return 0.0;
}

// one_minus_cos_max: sin²θ_max / (1 + cos θ_max).
float light_one_minus_cos_max(float sin2_max) {
    precise float v = sin2_max / (1.0 + sqrt(rust_max(1.0 - sin2_max, 0.0)));
    return v;
}

// sphere_pdf: the cone pdf 1 / (2π (1 − cos θ_max)) on the cap visible from x, else 0.
float light_sphere_pdf(vec3 center, float radius, vec3 x, vec3 point) {
    float dc2 = glam_distance_squared(center, x);
    precise vec3 normal = (point - center) / radius;
    precise vec3 to_x = x - point;
    precise float r2 = radius * radius;
    if (dc2 <= r2 || glam_dot(normal, to_x) < 0.0) {
        return 0.0;
    }
    precise float pdf = 1.0 / (2.0 * LIGHT_PI * light_one_minus_cos_max(r2 / dc2));
    return rust_is_finite(pdf) ? pdf : 0.0;
}

// sample_sphere_cone: uniform directions in the cone that sees the sphere from x, through
// a = 1 − cos θ (pbrt-v4 Sphere::Sample without the small-angle branch); false from inside.
bool light_sample_sphere_cone(vec3 center, float radius, vec3 x, vec2 u, out vec3 point,
        out vec3 normal, out float pdf) {
    point = vec3(0.0);
    normal = vec3(0.0);
    pdf = 0.0;
    precise vec3 to_center = center - x;
    float dc2 = glam_length_squared(to_center);
    precise float r2 = radius * radius;
    if (dc2 <= r2) {
        return false;
    }
    precise float dc = sqrt(dc2);
    precise float sin2_max = r2 / dc2;
    precise float sin_max = sqrt(sin2_max);
    float one_minus_max = light_one_minus_cos_max(sin2_max);
    precise float a = u.x * one_minus_max;
    precise float sin2_theta = a * (2.0 - a);
    precise float cos_theta = 1.0 - a;
    precise float cos_alpha = sin2_theta / sin_max
        + cos_theta * sqrt(rust_max(1.0 - sin2_theta / sin2_max, 0.0));
    precise float sin_alpha = sqrt(rust_max(1.0 - cos_alpha * cos_alpha, 0.0));
    precise float phi = 2.0 * LIGHT_PI * u.y;
    precise vec3 axis = -to_center / dc;
    Frame frame = frame_from_normal(axis);
    precise vec3 local = vec3(sin_alpha * cos(phi), sin_alpha * sin(phi), cos_alpha);
    precise vec3 n = frame_to_world(frame, local);
    precise vec3 p = center + radius * n;
    precise float density = 1.0 / (2.0 * LIGHT_PI * one_minus_max);
    point = p;
    normal = n;
    pdf = density;
    return rust_is_finite(density);
}

// Light::pdf: solid-angle density at x of light_sample_point producing `point`; 0 for delta
// lights and where it cannot be produced.
float light_pdf(uint light, vec3 x, vec3 point) {
    uint kind = scene_lights[light].kind;
    if (kind == LIGHT_QUAD || kind == LIGHT_TRIANGLE) {
        vec3 n = light_face_normal(light);
        float len = glam_length(n);
        precise float area = kind == LIGHT_QUAD ? len : 0.5 * len;
        return light_area_to_solid_angle(x, point, glam_normalize(n), area, light_two_sided(light));
    }
    if (kind == LIGHT_SPHERE) {
        return light_sphere_pdf(light_p0(light), scene_lights[light].radius, x, point);
    }
    return 0.0;
}

// Light::sample_point: a point of the light seen from x with its solid-angle pdf and radiance
// (PointOnLight); false when it cannot emit toward x.
bool light_sample_point(uint light, vec3 x, vec2 u, out vec3 point, out vec3 normal,
        out float pdf, out vec3 radiance) {
    uint kind = scene_lights[light].kind;
    point = vec3(0.0);
    normal = vec3(0.0);
    pdf = 0.0;
    radiance = light_emission(light);
    if (kind == LIGHT_QUAD) {
        precise vec3 p = light_p0(light) + u.x * light_p1(light) + u.y * light_p2(light);
        point = p;
        normal = glam_normalize(light_face_normal(light));
        pdf = light_pdf(light, x, p);
        return pdf > 0.0;
    }
    if (kind == LIGHT_TRIANGLE) {
        // Uniform barycentrics: b0 = 1 − √u0, b1 = √u0 (1 − u1), b2 = √u0 u1.
        precise float su = sqrt(u.x);
        precise float b1 = su * (1.0 - u.y);
        precise float b2 = su * u.y;
        precise vec3 p = (1.0 - su) * light_p0(light) + b1 * light_p1(light) + b2 * light_p2(light);
        point = p;
        // A two-sided emitter's normal at x3 faces x2, as a one-sided one's must.
        vec3 winding = glam_normalize(light_face_normal(light));
        precise vec3 to_x = x - p;
        bool flip = light_two_sided(light) && glam_dot(winding, to_x) < 0.0;
        normal = flip ? -winding : winding;
        pdf = light_pdf(light, x, p);
        return pdf > 0.0;
    }
    if (kind == LIGHT_SPHERE) {
        return light_sample_sphere_cone(light_p0(light), scene_lights[light].radius, x, u, point,
            normal, pdf);
    }
    if (kind == LIGHT_POINT) {
        vec3 position = light_p0(light);
        float d2 = glam_distance_squared(position, x);
        if (!(d2 > 0.0)) {
            return false;
        }
        point = position;
        pdf = 1.0;
        precise vec3 e = radiance / d2;
        radiance = e;
        return true;
    }
    // Directional: x3 placed DIRECTIONAL_DISTANCE against the direction of travel.
    vec3 direction = light_p0(light);
    precise vec3 p = x - LIGHT_DIRECTIONAL_DISTANCE * direction;
    point = p;
    normal = direction;
    pdf = 1.0;
    return true;
}

// Lights::selection_pmf.
float lights_selection_pmf(uint light) {
    return scene_lights[light].pmf;
}

// Lights::select: the light whose CDF interval [cdf[i−1], cdf[i]) contains u (the first i with
// cdf[i] > u, by bisection as partition_point), clamped to the last light.
uint lights_select(float u) {
    uint lo = 0u;
    uint hi = LIGHT_COUNT;
    while (lo < hi) {
        uint mid = lo + (hi - lo) / 2u;
        if (scene_lights[mid].cdf <= u) {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    return min(lo, LIGHT_COUNT - 1u);
}

// Lights::sample: a light picked with u.x, a point on it with u.yz, seen from x (x2).
bool lights_sample(vec3 x, vec3 u, out LightSample s) {
    uint light = lights_select(u.x);
    float pmf = scene_lights[light].pmf;
    s.light = light;
    s.point = vec3(0.0);
    s.normal = vec3(0.0);
    s.wi = vec3(0.0);
    s.distance = 0.0;
    s.radiance = vec3(0.0);
    s.pdf = 0.0;
    s.is_delta = light_is_delta(light);
    vec3 point;
    vec3 normal;
    float pdf;
    vec3 radiance;
    if (!light_sample_point(light, x, u.yz, point, normal, pdf, radiance)) {
        return false;
    }
    precise vec3 offset = point - x;
    float distance = glam_length(offset);
    if (!(distance > 0.0 && pmf > 0.0)) {
        return false;
    }
    s.point = point;
    s.normal = normal;
    precise vec3 wi = offset / distance;
    s.wi = wi;
    s.distance = distance;
    s.radiance = radiance;
    precise float total = pmf * pdf;
    s.pdf = total;
    return true;
}

// Lights::pdf: solid-angle density of lights_sample returning `point` on `light`, selection
// included; 0 for delta lights.
float lights_pdf(vec3 x, uint light, vec3 point) {
    precise float pdf = scene_lights[light].pmf * light_pdf(light, x, point);
    return pdf;
}

// Lights::radiance.
vec3 lights_radiance(uint light, vec3 point, vec3 toward) {
    return light_radiance(light, point, toward);
}

#endif
