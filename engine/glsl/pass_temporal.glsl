#version 460
// Temporal reuse [001 §5.1]: the GLSL twin of engine::reuse::temporal, one invocation per
// pixel. Reprojects x1 into the previous frame, accepts the previous pixel if it shows the same
// object at a similar depth and normal, caps its confidence and combines the two reservoirs
// (restir/glsl/resample.glsl). Without a previous frame or an accepted pixel the canonical
// reservoir passes unchanged. Bindings: the scene's, then
// PassKernel::Temporal's (engine/src/plan/kernels.rs); the diag holds (shifted, failed, improved,
// error code of resample.glsl). With params.shade (Shade::AllInputs) a pixel the pass resampled
// gets its Rao-Blackwellised value in rao_blackwellised (w = 1); other pixels keep theirs.
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
// KEPT_HITS, LOOP_BUDGET_CUT, TEMPORAL_*, the purposes PURPOSE_*.
#include "contract/engine.glsl"
// Hits kept per probe, as in pass_candidates: a sample's intersection index is below KEPT_HITS.
#define BVH_MAX_HITS KEPT_HITS
#define SCENE_BINDING 0
#include "scene.glsl"
#include "resample.glsl"
#include "loop_budget.glsl"

layout(local_size_x = 64) in;

#include "contract/pass_temporal_bindings.glsl"

#include "contract/pass_params.glsl"

// reproject: the previous frame's pixel that shows x1, if it passes the reprojection checks.
bool reproject(GPixel g, out uint q) {
    q = 0u;
    vec2 c;
    if (!camera_project(frame_params.previous_camera, domain_gpixel_vec3(g.position), c)) {
        return false;
    }
    uint qx = uint(c.x);
    uint qy = uint(c.y);
    uint width = frame_params.previous_camera.width;
    if (qx >= width || qy >= frame_params.previous_camera.height) {
        return false;
    }
    q = qy * width + qx;
    GPixel g_prev = previous_gpixels[q];
    if (g_prev.valid == 0u) {
        return false;
    }
    precise vec3 to_eye = domain_gpixel_vec3(g.position) - camera_eye(frame_params.previous_camera);
    float depth = glam_length(to_eye);
    precise float depth_error = abs(g_prev.depth - depth);
    precise float depth_bound = TEMPORAL_DEPTH_TOLERANCE * depth;
    return g_prev.object == g.object && depth_error <= depth_bound
        && glam_dot(domain_gpixel_vec3(g_prev.geometric_normal), domain_gpixel_vec3(g.geometric_normal))
            >= TEMPORAL_NORMAL_COSINE;
}

void main() {
    uint pixel = gl_GlobalInvocationID.x;
    if (pixel >= frame_params.width * frame_params.height) {
        return;
    }
    PixelReservoir stored = reservoirs_in[pixel];
    reservoirs_out[pixel] = stored;
    diag[pixel] = uvec4(0u);
    GPixel g = gpixels[pixel];
    uint64_t seed = scene_seed();
    if (!domain_new(g, pixel, frame_params.frame, params.pass, seed, resample_domains[0])) {
        return;
    }
    resample_domains[0].target = params.target;
    uint q;
    if (frame_params.has_previous == 0u || frame_params.frame == 0u || !reproject(g, q)) {
        return;
    }
    if (!domain_new(previous_gpixels[q], q, frame_params.frame - 1u, params.pass, seed,
                    resample_domains[1])) {
        return;
    }
    resample_domains[1].target = params.target;
    resample_inputs[0] = stored;
    resample_inputs[1] = previous_reservoirs[q];
    resample_inputs[1].confidence = reservoir_cap_confidence(
        resample_inputs[1].confidence, stored.confidence, params.confidence_cap);
    PixelReservoir result;
    uvec3 counts;
    vec3 rao_blackwellised_value;
    bool rao_blackwellise = params.shade != 0u;
    uint error = resample_step(2u, params.shift, params.mis, PURPOSE_SELECT,
                               params.collect_diagnostics != 0u, rao_blackwellise, result,
                               counts, rao_blackwellised_value);
    reservoirs_out[pixel] = error == 0u ? result : stored;
    // Step::run's Some(sum): this pass resampled the pixel.
    if (rao_blackwellise && error == 0u) {
        rao_blackwellised[pixel] = vec4(rao_blackwellised_value, 1.0);
    }
    if (!loop_budget_intact(min(frame_params.width, 1u))) {
        error = LOOP_BUDGET_CUT;
    }
    diag[pixel] = uvec4(counts, error);
}
