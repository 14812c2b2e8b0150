#version 460
// Parity kernel for sss/glsl/{light,camera,material}.glsl (engine/tests/vulkan_scene.rs):
// per query, a light sample, the light pdf and radiance at a given point, camera projection
// and spatial radius, the material profile and Fresnel transmission.
// Bindings: the scene (0..8), 9 queries, 10 results. Push constants: the query count.
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require

layout(local_size_x = 64) in;

layout(push_constant) uniform Params {
    uint count;
} params;

#define SCENE_BINDING 0
#include "scene.glsl"

struct SceneQuery {
    float x[3];
    float u[3];
    // A point on light `light` for the pdf and radiance queries.
    float p[3];
    uint light;
    float r;
    float mu;
    float max_d;
    uint material;
};

struct SceneResult {
    uint sampled;
    uint light;
    uint is_delta;
    float distance;
    float point[3];
    float normal[3];
    float wi[3];
    float radiance[3];
    float pdf;
    // lights_pdf(x, sample.light, sample.point).
    float pdf_at_sample;
    float selection_pmf;
    // luminance(u).
    float luminance;
    // lights_radiance(query light, p, x).
    float radiance_at[3];
    uint projected;
    float pixel[2];
    float radius_px;
    float profile[3];
    float fresnel;
    // lights_pdf(x, query light, p).
    float pdf_at;
};

layout(std430, binding = 9) readonly buffer Queries { SceneQuery queries[]; };
layout(std430, binding = 10) writeonly buffer Results { SceneResult results[]; };

float[3] to_array(vec3 v) {
    return float[3](v.x, v.y, v.z);
}

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= params.count) {
        return;
    }
    SceneQuery q = queries[i];
    vec3 x = vec3(q.x[0], q.x[1], q.x[2]);
    vec3 u = vec3(q.u[0], q.u[1], q.u[2]);
    vec3 p = vec3(q.p[0], q.p[1], q.p[2]);
    SceneResult res;
    LightSample s;
    res.sampled = lights_sample(x, u, s) ? 1u : 0u;
    res.light = s.light;
    res.is_delta = s.is_delta ? 1u : 0u;
    res.distance = s.distance;
    res.point = to_array(s.point);
    res.normal = to_array(s.normal);
    res.wi = to_array(s.wi);
    res.radiance = to_array(s.radiance);
    res.pdf = s.pdf;
    res.pdf_at_sample = res.sampled != 0u ? lights_pdf(x, s.light, s.point) : 0.0;
    res.selection_pmf = lights_selection_pmf(q.light);
    res.luminance = luminance(u);
    res.radiance_at = to_array(lights_radiance(q.light, p, x));
    vec2 pixel;
    res.projected = camera_project(frame_params.camera, x, pixel) ? 1u : 0u;
    res.pixel = float[2](pixel.x, pixel.y);
    res.radius_px = camera_spatial_radius_px(frame_params.camera, x, q.max_d);
    GpuMaterial m = scene_materials[q.material];
    res.profile = to_array(material_is_translucent(m) ? material_profile_rgb(m, q.r) : vec3(0.0));
    res.fresnel =
        material_is_translucent(m) ? fresnel_transmission_eval(material_fresnel(m), q.mu) : 0.0;
    res.pdf_at = lights_pdf(x, q.light, p);
    results[i] = res;
}
