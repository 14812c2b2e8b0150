#version 460
// Spatial reuse: the GLSL twin of engine::reuse::spatial, one invocation per pixel.
// `neighbours` pixels drawn uniformly in the disk of radius Camera::spatial_radius_px around
// the pixel centre; one outside the image, equal to the pixel, without a translucent primary hit
// or on another object is not taken; each taken neighbour's confidence is capped when
// confidence_cap > 0; the reservoirs are combined by restir/glsl/resample.glsl. Bindings:
// the scene's, then PassKernel::Spatial's (engine/src/plan/kernels.rs); the diag holds (shifted,
// failed, improved, error code of resample.glsl). With params.shade (Shade::AllInputs) a pixel
// the pass resampled gets its Rao-Blackwellised value in rao_blackwellised (w = 1).
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
// KEPT_HITS, LOOP_BUDGET_CUT, TEMPORAL_*, the purposes PURPOSE_*.
#include "contract/engine.glsl"
// Hits kept per probe, as in pass_candidates: a sample's intersection index is below KEPT_HITS.
#define BVH_MAX_HITS KEPT_HITS
#define SCENE_BINDING 0
#include "scene.glsl"
#include "resample.glsl"
#include "loop_budget.glsl"
#include "sampling.glsl"

layout(local_size_x = 64) in;

#include "contract/pass_spatial_bindings.glsl"

#include "contract/pass_params.glsl"

void main() {
    uint pixel = gl_GlobalInvocationID.x;
    uint width = frame_params.width;
    uint height = frame_params.height;
    if (pixel >= width * height) {
        return;
    }
    PixelReservoir stored = reservoirs_in[pixel];
    reservoirs_out[pixel] = stored;
    diag[pixel] = uvec4(0u);
    GPixel g = gpixels[pixel];
    uint64_t seed = scene_seed();
    uint frame = frame_params.frame;
    if (!domain_new(g, pixel, frame, params.pass, seed, resample_domains[0])) {
        return;
    }
    resample_domains[0].target = params.target;
    resample_inputs[0] = stored;
    float max_d = bssrdf_max_element(material_d(resample_domains[0].material));
    float radius = camera_spatial_radius_px(frame_params.camera,
                                            vec3(g.position[0], g.position[1], g.position[2]),
                                            max_d);
    precise vec2 centre = vec2(float(pixel % width) + 0.5, float(pixel / width) + 0.5);
    Stream rng = stream_new(StreamKey(pixel, frame, params.pass, PURPOSE_NEIGHBOURS), seed);
    uint n = 1u;
    for (uint k = 0u; k < params.neighbours; k++) {
        float u_radius = stream_next_f32(rng);
        float u_angle = stream_next_f32(rng);
        precise vec2 qf = centre + sampling_uniform_disk(radius, u_radius, u_angle);
        if (!(qf.x >= 0.0 && qf.y >= 0.0 && qf.x < float(width) && qf.y < float(height))) {
            continue;
        }
        uint q = uint(qf.y) * width + uint(qf.x);
        if (q == pixel) {
            continue;
        }
        GPixel g_q = gpixels[q];
        SssDomain domain;
        if (!domain_new(g_q, q, frame, params.pass, seed, domain)) {
            continue;
        }
        domain.target = params.target;
        if (g_q.object != g.object) {
            continue;
        }
        if (n < MAX_DOMAINS) {
            resample_domains[n] = domain;
            resample_inputs[n] = reservoirs_in[q];
            if (params.confidence_cap > 0.0) {
                resample_inputs[n].confidence = reservoir_cap_confidence(
                    resample_inputs[n].confidence, stored.confidence, params.confidence_cap);
            }
        }
        n += 1u;
    }
    PixelReservoir result;
    uvec3 counts;
    vec3 rao_blackwellised_value;
    bool rao_blackwellise = params.shade != 0u;
    uint error = resample_step(n, params.shift, params.mis, PURPOSE_SELECT,
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
