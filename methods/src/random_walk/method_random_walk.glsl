#version 460
// The random-walk method per pixel: the GLSL twin of methods::random_walk::render
// (methods/src/random_walk/mod.rs; read the two side by side). Pixels whose object has a
// translucent material get the mean of `spp` volumetric walks (sss/glsl/random_walk.glsl) on the
// object's own mesh, Fresnel-free diffuse boundary, next-event estimation at the exit; Lambert
// pixels get the path tracer's mean of `spp` samples, as method_pt.glsl computes it.
//
// Streams: the walks of a pixel share StreamKey { pixel, frame, 0, PURPOSE_WALK } and the light
// selection at their exits StreamKey { pixel, frame, 0, PURPOSE_WALK_LIGHT }, as on the CPU;
// path-traced sample s has its own stream (pt_sample_stream). Finite walk estimates are summed
// in f64 in sample order and divided by their count; path-traced ones are divided by spp.
//
// One dispatch per sample: dispatch `sample` (push constant pad[0]) runs walk or path-traced
// sample number `sample` of every pixel, carrying the two walk streams, the f64 sum and the
// tallies from the previous dispatch in RandomWalkPixelState (binding 13); the last one
// (sample = spp - 1) writes the mean. Lavapipe (llvmpipe) shares one budget of 65 535 loop
// iterations among all loops of an invocation group and silently cuts every loop short once
// it is spent (gallivm's LP_MAX_TGSI_LOOP_ITERATIONS); one walk per dispatch keeps within it,
// and a probe loop at the end of each dispatch counts the dispatches where it was not
// (RandomWalkStats::cut), so a cut walk is never passed off as a result.
//
// Bindings: scene 0-8, 9 G-buffer (GPixel), 10 vec4 out (rgb = mean; w = samples left out as
// non-finite), 11 RandomWalkMedium per material (this method's own: the walk's sigma_s,
// sigma_t, g and interface, which GpuMaterial lacks), 12 RandomWalkStats per pixel (how its
// walks ended), 13 RandomWalkPixelState per pixel (carried between dispatches).
// Push constants: MethodParams (spp, then the sample index in pad[0]).
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require

layout(local_size_x = 64) in;

// MethodParams (engine/src/contract.rs): spp; pad[0] is the sample this dispatch runs.
#include "contract/method_params.glsl"

#define SCENE_BINDING 0
#include "scene.glsl"
#include "pt.glsl"
#include "random_walk.glsl"
#include "loop_budget.glsl"
// SceneLighting: exit_lighting_* and scene_lighting_selection.
#include "scene_lighting.glsl"

// How the walks of one pixel ended (std430, 36 bytes; Rust twin methods::random_walk::vulkan::WalkStats):
// the sum of the exit weights (walk::Exit::weight) of exited walks, the largest |weight_c - 1|
// among them, the count of each WalkEnd, the non-finite samples (walks or path-traced) and the
// dispatches whose loops the device cut short.
struct RandomWalkStats {
    float weight_sum[3];
    float max_weight_deviation;
    uint exited;
    uint terminated;
    uint truncated;
    uint nonfinite;
    uint cut;
};

// What a pixel carries from one dispatch to the next (std430, 64 bytes; Rust twin
// engine::vulkan::WalkPixelState): the walk and light-selection streams, the f64 sum of
// the finite samples and their count.
struct RandomWalkPixelState {
    Stream walk;
    Stream selection;
    double sum[3];
    uint finite;
    uint pad;
};

layout(std430, binding = 9) readonly buffer GBufferIn { GPixel gbuffer[]; };
layout(std430, binding = 10) writeonly buffer ImageOut { vec4 image[]; };
layout(std430, binding = 11) readonly buffer Media { RandomWalkMedium media[]; };
layout(std430, binding = 12) buffer StatsInOut { RandomWalkStats stats[]; };
layout(std430, binding = 13) buffer StateInOut { RandomWalkPixelState states[]; };

void main() {
    uint pixel = gl_GlobalInvocationID.x;
    if (pixel >= frame_params.width * frame_params.height) {
        return;
    }
    uint sample_index = params.pad[0];
    bool last = sample_index + 1u >= params.spp;
    RandomWalkStats tally = stats[pixel];
    RandomWalkPixelState state = states[pixel];
    if (sample_index == 0u) {
        tally = RandomWalkStats(float[3](0.0, 0.0, 0.0), 0.0, 0u, 0u, 0u, 0u, 0u);
        state.sum = double[3](0.0, 0.0, 0.0);
        state.finite = 0u;
    }
    GPixel x1 = gbuffer[pixel];
    if (x1.valid == 0u || params.spp == 0u) {
        image[pixel] = vec4(0.0);
        stats[pixel] = tally;
        states[pixel] = state;
        return;
    }
    precise dvec3 sum = dvec3(state.sum[0], state.sum[1], state.sum[2]);
    uint material = scene_material_of_object(x1.object);
    // As on the CPU, a material has a medium exactly when it is translucent.
    bool walk = material_is_translucent(scene_materials[material]);
    vec3 value;
    if (!walk) {
        // pt_estimate's Lambert branch, called directly so that its translucent branch is not
        // compiled in.
        Stream rng = pt_sample_stream(pixel, frame_params.frame, sample_index, scene_seed());
        value = pt_estimate_lambert(scene_materials[material], x1, rng);
    } else {
        vec3 position = pt_vec3(x1.position);
        vec3 view = pt_vec3(x1.view);
        vec3 n = scene_geometric_normal(x1.prim);
        // The camera sees closed objects from outside: x1's outward normal faces the viewer.
        bool inward_winding = glam_dot(n, view) < 0.0;
        vec3 n1 = inward_winding ? -n : n;
        if (sample_index == 0u) {
            uint64_t seed = scene_seed();
            state.selection = stream_new(
                StreamKey(pixel, frame_params.frame, 0u, PURPOSE_WALK_LIGHT), seed);
            state.walk = stream_new(
                StreamKey(pixel, frame_params.frame, 0u, PURPOSE_WALK), seed);
        }
        scene_lighting_selection = state.selection;
        Stream stream = state.walk;
        RandomWalkExit exit;
        uint end = random_walk_estimate_exitant(x1.object, inward_winding, media[material],
                                                position, n1, view, true, stream, value, exit);
        state.walk = stream;
        state.selection = scene_lighting_selection;
        if (end == RANDOM_WALK_END_EXITED) {
            tally.exited++;
            precise vec3 weight_sum =
                vec3(tally.weight_sum[0], tally.weight_sum[1], tally.weight_sum[2]) + exit.weight;
            tally.weight_sum = float[3](weight_sum.x, weight_sum.y, weight_sum.z);
            vec3 deviation = abs(exit.weight - vec3(1.0));
            tally.max_weight_deviation =
                rust_max(tally.max_weight_deviation, random_walk_max_element(deviation));
        } else if (end == RANDOM_WALK_END_TERMINATED) {
            tally.terminated++;
        } else {
            tally.truncated++;
        }
    }
    if (any(isnan(value)) || any(isinf(value))) {
        tally.nonfinite++;
    } else {
        sum = sum + dvec3(value);
        state.finite++;
    }
    if (!loop_budget_intact(min(params.spp, 1u))) {
        tally.cut++;
    }
    state.sum = double[3](sum.x, sum.y, sum.z);
    if (last) {
        // pt::render divides by spp, random_walk::render by the finite walks.
        uint count = walk ? state.finite : params.spp;
        precise dvec3 mean = count > 0u ? sum / double(count) : dvec3(0.0);
        image[pixel] = vec4(vec3(mean), float(tally.nonfinite));
    }
    stats[pixel] = tally;
    states[pixel] = state;
}
