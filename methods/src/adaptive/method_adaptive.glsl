#version 460
// The adaptive method of paper 004 per pixel and frame: the GLSL twin of
// methods/src/adaptive/cpu.rs render_frame (read the two side by side; the controller is
// adaptive.glsl beside it). Per translucent pixel: the history carried from the previous frame by
// gbuffer_reproject (none on frame 0 or a disocclusion), the count n = adaptive_sample_count,
// n samples of pt_estimate_with with the parameters' radius sampling, the mean, then
// adaptive_update with its perceptual luminance; other pixels take b_min samples and keep no
// history. Sample j uses the path tracer's stream StreamKey { pixel, frame, j, PURPOSE_PT }, as
// on the CPU; finite samples are summed in f64 in sample order and the mean (sum / n in f64) is
// rounded to f32; non-finite samples (or samples whose probe had more than BVH_MAX_HITS hits) are
// left out of the sum but not of the divisor.
//
// One dispatch per sample index: dispatch `sample_index` = j of 0..b_max adds sample j to every
// pixel whose count exceeds j, so that every dispatch's loops stay far inside lavapipe's loop
// budget (loop_budget.glsl) whatever b_max is. Dispatch 0 also reprojects the history and sets
// the count; the last one (j = b_max - 1) writes the mean and the next history.
//
// Bindings: scene 0-8 (FrameParams with the previous frame's camera), 9 G-buffer (GPixel),
// 10 vec4 out (rgb = mean, w = samples left out), 11 the previous frame's G-buffer, 12 the
// previous frame's History per pixel (valid = 0 where the CPU has None), 13 this frame's History
// per pixel (written), 14 AdaptiveState per pixel (count, running sum, tallies, carried history).
// Push constants: AdaptiveMethodParams.
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require

layout(local_size_x = 64) in;

#include "contract/adaptive_method_params.glsl"

#define SCENE_BINDING 0
#include "contract/engine.glsl"
#include "contract/adaptive.glsl"
#define BVH_MAX_HITS KEPT_HITS
#include "scene.glsl"
#include "pt.glsl"
#include "gbuffer.glsl"
#include "adaptive.glsl"
#include "loop_budget.glsl"

layout(std430, binding = 9) readonly buffer GBufferIn { GPixel gbuffer[]; };
layout(std430, binding = 10) writeonly buffer ImageOut { vec4 image[]; };
layout(std430, binding = 11) readonly buffer PreviousGBuffer { GPixel previous_gbuffer[]; };
layout(std430, binding = 12) readonly buffer PreviousHistory { History previous_history[]; };
layout(std430, binding = 13) writeonly buffer NextHistory { History next_history[]; };
layout(std430, binding = 14) buffer StateBuffer { AdaptiveState state[]; };

GPixel gbuffer_fetch_earlier(uint pixel) {
    return previous_gbuffer[pixel];
}

AdaptiveParams controller() {
    return AdaptiveParams(params.alpha, params.target_variance, params.kappa, params.b_min,
        params.b_max, params.radius);
}

// The history `carried` of render_frame: the previous frame's at the reprojected pixel, for
// translucent pixels of a frame with a previous one; valid = 0 otherwise.
History carried_history(GPixel g, bool translucent) {
    History none = History(0.0, 0.0, 0.0, 0u);
    if (!translucent || frame_params.has_previous == 0u) {
        return none;
    }
    uint q;
    if (!gbuffer_reproject(frame_params.previous_camera, g, q)) {
        return none;
    }
    return previous_history[q];
}

void main() {
    uint pixel = gl_GlobalInvocationID.x;
    if (pixel >= frame_params.width * frame_params.height) {
        return;
    }
    GPixel g = gbuffer[pixel];
    uint j = params.sample_index;
    AdaptiveState carried = state[pixel];
    bool translucent = g.valid != 0u && material_is_translucent(scene_material(g.object));
    if (j == 0u) {
        History h = carried_history(g, translucent);
        uint count = g.valid != 0u ? adaptive_sample_count(controller(), h) : 0u;
        carried = AdaptiveState(double[3](0.0, 0.0, 0.0), count, 0u, 0u, h.mean_count, h.mean,
            h.variance, h.valid, 0u);
    }
    if (j < carried.count) {
        PtOptions options = pt_options_default();
        options.radius = params.radius;
        Stream rng = pt_sample_stream(pixel, frame_params.frame, j, scene_seed());
        uint overflow = pt_hit_overflow;
        vec3 value = pt_estimate_with(g, PT_HITS_ALL, options, rng);
        pt_accumulate(value, overflow, carried.sum, carried.left_out);
    }
    if (!loop_budget_intact(min(frame_params.width, 1u))) {
        carried.cut++;
    }
    state[pixel] = carried;
    if (j + 1u == params.b_max) {
        precise dvec3 mean = dvec3(0.0);
        if (carried.count > 0u) {
            mean = dvec3(carried.sum[0], carried.sum[1], carried.sum[2])
                / double(carried.count);
        }
        image[pixel] = vec4(vec3(mean), float(carried.left_out));
        History next = History(0.0, 0.0, 0.0, 0u);
        if (translucent) {
            History h = History(carried.history_mean_count, carried.history_mean,
                carried.history_variance, carried.history_valid);
            next = adaptive_update(controller(), h, carried.count,
                adaptive_perceptual_luminance(vec3(mean)));
        }
        next_history[pixel] = next;
    }
}
