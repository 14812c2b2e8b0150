#version 460
// The path-tracer method per pixel: the GLSL twin of sss::integrator::pt::render for one pixel
// (the `pt[:spp]` method of methods/src/pt/mod.rs uses the All hit policy, `pt-one-hit` UniformOne). Sample s uses
// the stream StreamKey { pixel, frame, s, PURPOSE_PT }; finite samples are summed in f64 in sample order and
// the mean (sum / spp in f64) is rounded to f32, as the CPU's DVec3 mean and `as_vec3`.
// Samples left out of the sum (but not of the divisor), counted in w: NaN or infinite ones, as on
// the CPU, and those whose probe had more than BVH_MAX_HITS hits (the GPU keeps only that many,
// the CPU all of them, so such a sample would be biased low).
// Bindings: scene 0-8, 9 G-buffer (GPixel), 10 vec4 out (rgb = mean, w = samples left out),
// 11 PtState per pixel (the running sum; `cut` counts samples whose loops the device cut short).
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require

layout(local_size_x = 64) in;

// PtParams (contract.rs beside this file): spp, the PtHits code, the sample this dispatch adds
// (one dispatch per sample, see below).
#include "contract/pt_params.glsl"

#define SCENE_BINDING 0
// Hits kept per probe (KEPT_HITS of the contract). Probes of the path tracer see at most 8 on
// the built-in scenes (bumpy, 32×32, 64 spp); 16 leaves room, beyond is flagged.
#include "contract/engine.glsl"
#include "contract/pt.glsl"
#define BVH_MAX_HITS KEPT_HITS
#include "scene.glsl"
#include "pt.glsl"
#include "loop_budget.glsl"

// PtState (contract/pt.glsl) is the running sum of a pixel between dispatches: one dispatch
// per sample keeps every dispatch's loops far inside lavapipe's loop budget (loop_budget.glsl)
// whatever spp is.

layout(std430, binding = 9) readonly buffer GBufferIn { GPixel gbuffer[]; };
layout(std430, binding = 10) writeonly buffer ImageOut { vec4 image[]; };
layout(std430, binding = 11) buffer StateBuffer { PtState state[]; };

void main() {
    uint pixel = gl_GlobalInvocationID.x;
    if (pixel >= frame_params.width * frame_params.height) {
        return;
    }
    GPixel x1 = gbuffer[pixel];
    if (x1.valid == 0u) {
        image[pixel] = vec4(0.0);
        return;
    }
    uint s = params.sample_index;
    PtState carried = state[pixel];
    if (s == 0u) {
        carried = PtState(double[3](0.0, 0.0, 0.0), 0u, 0u);
    }
    Stream rng = pt_sample_stream(pixel, frame_params.frame, s, scene_seed());
    uint overflow = pt_hit_overflow;
    vec3 value = pt_estimate(x1, params.hits, rng);
    pt_accumulate(value, overflow, carried.sum, carried.left_out);
    if (!loop_budget_intact(min(frame_params.width, 1u))) {
        carried.cut++;
    }
    state[pixel] = carried;
    if (s + 1u == params.spp) {
        precise dvec3 mean = dvec3(carried.sum[0], carried.sum[1], carried.sum[2])
            / double(params.spp);
        image[pixel] = vec4(vec3(mean), float(carried.left_out));
    }
}
