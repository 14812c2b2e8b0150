#version 460
// The single-scatter method per pixel: the GLSL twin of the `single-scatter` method
// (methods/src/single_scatter/mod.rs over sss::integrator::single_scatter::render; read them side
// by side, the estimator's math is sss/glsl/single_scatter.glsl). Paper 000's hybrid estimator on
// translucent pixels (path-traced zero and single scattering through the material's boundary,
// diffusion with R - R1 for the rest), the path tracer's direct lighting on Lambert pixels, the
// exits lit by the scene's lights with shadow rays (engine/glsl/include/scene_lighting.glsl, the
// twin of engine::scene_lighting::SceneLighting).
//
// Streams, as on the CPU: sample s of a pixel draws from StreamKey { pixel, frame, s,
// SINGLE_SCATTER_PURPOSE_SINGLE_SCATTER } (single_scatter_sample_stream), and the light selection
// at its exits from one stream per pixel, StreamKey { pixel, frame, 0,
// PURPOSE_SINGLE_SCATTER_LIGHT }, that runs on through the pixel's samples (the CPU's
// exit_lighting, a RefCell shared by the pixel's samples). Finite samples are summed in f64 in
// sample order and the mean is sum / spp (pt::render_pixels); a NaN or infinite sample, or one
// whose diffusion probe had more than BVH_MAX_HITS hits (the GPU keeps only that many, the CPU
// all: such a sample would be biased low), is left out of the sum but not of the divisor and
// counted in w (pt_accumulate).
//
// One dispatch per sample: dispatch `sample_index` runs sample `sample_index` of every pixel and
// carries the light-selection stream, the f64 sum and the tallies in SingleScatterPixelState
// (binding 12); the last (sample_index = spp - 1) writes the mean. Lavapipe shares one budget of
// 65 535 loop iterations among all loops of an invocation group and silently cuts every loop
// short once it is spent; one sample per dispatch (a few chords, one probe, a few shadow rays per
// pixel) keeps within it, and a probe loop at the end of each dispatch counts the dispatches where
// it was not (`cut`), so a cut sample is never passed off as a result.
//
// Bindings: scene 0-8, 9 G-buffer (GPixel), 10 vec4 out (rgb = mean; w = samples left out),
// 11 RandomWalkMedium per material, 12 SingleScatterPixelState per pixel, 13
// SingleScatterProfile per material (both per-material buffers computed on the host from
// Medium::from_translucent and MultipleScattering::new; zeroed placeholders for Lambert
// materials). Push constants: SingleScatterParams.
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require

layout(local_size_x = 64) in;

// SingleScatterParams (methods/src/single_scatter/contract.rs): spp, the sample this dispatch
// runs, the ChannelSelection and PtHits codes, max_segments.
#include "contract/single_scatter_params.glsl"

#define SCENE_BINDING 0
// As method_pt.glsl: every probe hit of the built-in scenes is kept (KEPT_HITS of the contract),
// beyond is left out and counted.
#include "contract/engine.glsl"
#define BVH_MAX_HITS KEPT_HITS
#include "scene.glsl"
#include "pt.glsl"
#include "random_walk.glsl"
#include "loop_budget.glsl"
// SceneLighting: exit_lighting_* and scene_lighting_selection.
#include "scene_lighting.glsl"
#include "single_scatter.glsl"

// What a pixel carries from one dispatch to the next (std430, 56 bytes; Rust twin
// methods::single_scatter::vulkan::SingleScatterPixelState): the light-selection stream, the f64
// sum of the finite samples, the samples left out, the samples whose chain was cut
// (Orders::truncated) and the dispatches whose loops the device cut short.
struct SingleScatterPixelState {
    Stream selection;
    double sum[3];
    uint left_out;
    uint truncated;
    uint cut;
    uint pad;
};

layout(std430, binding = 9) readonly buffer GBufferIn { GPixel gbuffer[]; };
layout(std430, binding = 10) writeonly buffer ImageOut { vec4 image[]; };
layout(std430, binding = 11) readonly buffer Media { RandomWalkMedium media[]; };
layout(std430, binding = 12) buffer StateInOut { SingleScatterPixelState states[]; };
layout(std430, binding = 13) readonly buffer Profiles { SingleScatterProfile profiles[]; };

void main() {
    uint pixel = gl_GlobalInvocationID.x;
    if (pixel >= frame_params.width * frame_params.height) {
        return;
    }
    uint s = params.sample_index;
    SingleScatterPixelState state = states[pixel];
    if (s == 0u) {
        Stream selection = stream_new(
            StreamKey(pixel, frame_params.frame, 0u, PURPOSE_SINGLE_SCATTER_LIGHT), scene_seed());
        state = SingleScatterPixelState(selection, double[3](0.0, 0.0, 0.0), 0u, 0u, 0u, 0u);
    }
    GPixel x1 = gbuffer[pixel];
    if (x1.valid != 0u) {
        uint material = scene_material_of_object(x1.object);
        Stream rng = single_scatter_sample_stream(pixel, frame_params.frame, s, scene_seed());
        scene_lighting_selection = state.selection;
        uint overflow = pt_hit_overflow;
        SingleScatterOrders orders = single_scatter_estimate(x1, media[material],
            profiles[material], params.channel_selection, params.hits, params.max_segments, rng);
        state.selection = scene_lighting_selection;
        if (orders.truncated) {
            state.truncated++;
        }
        precise vec3 value = orders.zero + orders.single + orders.multiple;
        pt_accumulate(value, overflow, state.sum, state.left_out);
    }
    if (!loop_budget_intact(min(frame_params.width, 1u))) {
        state.cut++;
    }
    states[pixel] = state;
    if (s + 1u == params.spp) {
        precise dvec3 mean = dvec3(state.sum[0], state.sum[1], state.sum[2]) / double(params.spp);
        image[pixel] = vec4(vec3(mean), float(state.left_out));
    }
}
