#version 460
// Parity kernel for sss/glsl/single_scatter.glsl (test only; the method's kernel is
// method_single_scatter.glsl): sample `params.sample` of paper 000's hybrid estimator at every
// G-buffer pixel, with a fixed directional "sun" as the exits' lighting and the hit policy as a
// parameter (engine/tests/vulkan_single_scatter.rs computes the same on the CPU). One dispatch
// per sample keeps lavapipe's loop budget.
//
// Bindings: scene 0-8, 9 G-buffer (GPixel), 10 vec4 out (rgb = zero + single + multiple, w = 1
// where the estimate was truncated), 11 RandomWalkMedium per material, 12 SingleScatterProfile
// per material, 13 uvec4 diag per pixel (x = 1 when the device cut loops short).
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require

layout(local_size_x = 64) in;

layout(push_constant) uniform Params {
    uint sample_index;
    uint channel_selection;
    uint hits_policy;
    uint max_segments;
} params;

#define SCENE_BINDING 0
// As method_pt.glsl: every probe hit of the built-in scenes is kept (KEPT_HITS of the contract).
#include "contract/engine.glsl"
#define BVH_MAX_HITS KEPT_HITS
#include "scene.glsl"
#include "pt.glsl"
#include "random_walk.glsl"
#include "loop_budget.glsl"

// The sun of the test: light travelling along -Y with irradiance SUN at normal incidence, NEE
// only, no visibility (the test's CPU `Sun`).
const vec3 SUN = vec3(1.0, 0.75, 0.5);

bool exit_lighting_sample(vec3 point, vec3 normal, vec2 u, out ExitLightSample s) {
    s = ExitLightSample(vec3(0.0, 1.0, 0.0), SUN, 0.0, true);
    return normal.y > 0.0;
}

float exit_lighting_pdf(vec3 point, vec3 normal, vec3 wi) {
    return 0.0;
}

vec3 exit_lighting_radiance(vec3 point, vec3 wi) {
    return vec3(0.0);
}

#include "single_scatter.glsl"

layout(std430, binding = 9) readonly buffer GBufferIn { GPixel gbuffer[]; };
layout(std430, binding = 10) writeonly buffer ImageOut { vec4 image[]; };
layout(std430, binding = 11) readonly buffer Media { RandomWalkMedium media[]; };
layout(std430, binding = 12) readonly buffer Profiles { SingleScatterProfile profiles[]; };
layout(std430, binding = 13) writeonly buffer Diag { uvec4 diag[]; };

void main() {
    uint pixel = gl_GlobalInvocationID.x;
    if (pixel >= frame_params.width * frame_params.height) {
        return;
    }
    GPixel x1 = gbuffer[pixel];
    vec4 out_value = vec4(0.0);
    if (x1.valid != 0u) {
        uint material = scene_material_of_object(x1.object);
        Stream rng = single_scatter_sample_stream(pixel, frame_params.frame, params.sample_index,
                                                  scene_seed());
        SingleScatterOrders o = single_scatter_estimate(x1, media[material], profiles[material],
            params.channel_selection, params.hits_policy, params.max_segments, rng);
        precise vec3 total = o.zero + o.single + o.multiple;
        out_value = vec4(total, o.truncated ? 1.0 : 0.0);
    }
    image[pixel] = out_value;
    diag[pixel] = uvec4(loop_budget_intact(min(frame_params.width, 1u)) ? 0u : 1u, 0u, 0u, 0u);
}
