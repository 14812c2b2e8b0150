#version 460
// The candidates pass: the GLSL twin of the Candidates arm of engine/src/cpu.rs, i.e.
// `candidates::generate` + `candidates::shadow_test` (engine/src/candidates.rs) and the
// diagnostics' `hybrid_choice`, one invocation per pixel [001 §3.1, Eq. 10].
//
// Bindings: the scene's, then PassKernel::Candidates's (engine/src/plan/kernels.rs); the diag
// holds (probes, hits, hybrid choice 0 none / 1 reconnection / 2 delayed, error code).
// Diagnostics other than the error code are written only when `collect_diagnostics` is set, as
// on the CPU. The error code is 0 or the ResampleCode RESAMPLE_INVALID_* of the InvalidCandidate
// that `generate` returned (reported as PipelineError::Candidate); that pixel's reservoir is
// then empty.
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require

layout(local_size_x = 64) in;

// KEPT_HITS, HIT_OVERFLOW, LOOP_BUDGET_CUT and the purposes PURPOSE_*.
#include "contract/engine.glsl"
// Hit lists of KEPT_HITS: the built-in scenes' probes stay far below (engine/tests/vulkan_bssrdf.rs
// measures the largest count); beyond it the CPU's extra hits would be missing here.
#define BVH_MAX_HITS KEPT_HITS
#define SCENE_BINDING 0
#include "domain.glsl"
#include "reservoir.glsl"
#include "loop_budget.glsl"

#include "contract/pass_params.glsl"

#include "contract/pass_candidates_bindings.glsl"

// ProbeCounts.
struct ProbeCounts {
    uint probes;
    uint hits;
    // A probe had more hits than the BVH_MAX_HITS this pass keeps.
    bool overflow;
};

vec3 candidates_light_numbers(inout Stream rng) {
    float u0 = stream_next_f32(rng);
    float u1 = stream_next_f32(rng);
    float u2 = stream_next_f32(rng);
    return vec3(u0, u1, u2);
}

// candidates::generate: the canonical reservoir of `domain` from `bssrdf_samples` BSSRDF samples;
// every hit of a probe streams with weight p-hat / (M p_disk p_light) [001 Eq. 10], confidence M.
// Returns 0 or reservoir.glsl's code of the InvalidCandidate.
uint candidates_generate(SssDomain domain, uint bssrdf_samples, bool shared_light,
        out PixelReservoir result, out ProbeCounts counts) {
    result = reservoir_empty();
    counts = ProbeCounts(0u, 0u, false);
    Stream probe_rng = stream_new(
        StreamKey(domain.pixel, domain.frame, domain.pass, PURPOSE_PROBE), domain.seed);
    Stream light_rng = stream_new(
        StreamKey(domain.pixel, domain.frame, domain.pass, PURPOSE_LIGHT), domain.seed);
    Stream select_rng = stream_new(
        StreamKey(domain.pixel, domain.frame, domain.pass, PURPOSE_SELECT), domain.seed);
    precise float inv_m = 1.0 / float(max(bssrdf_samples, 1u));
    Ris ris = ris_new();
    for (uint m = 0u; m < bssrdf_samples; m++) {
        uint error = ris_skip(ris, 1.0);
        if (error != 0u) {
            return error;
        }
        float u_technique = stream_next_f32(probe_rng);
        float u_radius = stream_next_f32(probe_rng);
        float u_angle = stream_next_f32(probe_rng);
        Probe probe = bssrdf_probe_sample(domain.selection, u_technique, u_radius, u_angle);
        bssrdf_probe_trace(probe, domain.x1);
        counts.probes += 1u;
        counts.hits += bvh_hit_count;
        vec3 shared_numbers = shared_light ? candidates_light_numbers(light_rng) : vec3(0.0);
        uint stored = min(bvh_hit_count, uint(BVH_MAX_HITS));
        for (uint rank = 0u; rank < stored; rank++) {
            vec3 u_light = shared_light ? shared_numbers : candidates_light_numbers(light_rng);
            float u_select = stream_next_f32(select_rng);
            EntryPoint x2 = bssrdf_entry_point_from_hit(bvh_hits[rank]);
            float p_disk = domain_p_disk(domain, x2);
            LightSample light;
            if (!lights_sample(x2.position, u_light, light)) {
                continue;
            }
            precise float density = p_disk * light.pdf;
            if (!(density > 0.0 && !isinf(density))) {
                continue;
            }
            BssrdfSample bssrdf = bssrdf_sample_new(probe, rank, x2, p_disk);
            SssSample x = sss_sample_new(bssrdf, light.light, light.point);
            float target = domain_target(domain, x);
            // w = p-hat(x) / (M p_disk p_light)   [001 Eq. 10]
            precise float weight = inv_m * target / density;
            if (!isnan(weight) && !isinf(weight)) {
                error = ris_update(ris, x, target, weight, 0.0, u_select);
                if (error != 0u) {
                    return error;
                }
            }
        }
        // Hits beyond the stored ones would be lost (a bias the CPU does not have): the pixel
        // reports HIT_OVERFLOW and the host fails the run. Their numbers are still drawn so that
        // the following probes use the CPU's.
        counts.overflow = counts.overflow || bvh_hit_count > stored;
        for (uint rank = stored; rank < bvh_hit_count; rank++) {
            if (!shared_light) {
                candidates_light_numbers(light_rng);
            }
            stream_next_f32(select_rng);
        }
    }
    result = ris_finish(ris);
    return 0u;
}

// candidates::shadow_test: W = 0 if x2-x3 of the canonical sample is occluded; the sample stays.
void candidates_shadow_test(SssDomain domain, inout PixelReservoir canonical) {
    if (canonical.has_sample != 0u && !domain_visible(domain, canonical.y)) {
        canonical.ucw = 0.0;
    }
}

// cpu::hybrid_choice: 1 reconnection, 2 delayed, 0 without a sample on x1's object.
uint candidates_hybrid_choice(SssDomain domain, PixelReservoir reservoir) {
    bool reconnection;
    if (reservoir.has_sample == 0u
            || !hybrid_uses_reconnection(hybrid_for_material(domain.material), reservoir.y, domain,
                reconnection)) {
        return 0u;
    }
    return reconnection ? 1u : 2u;
}

void main() {
    uint pixel = gl_GlobalInvocationID.x;
    if (pixel >= frame_params.width * frame_params.height) {
        return;
    }
    uint64_t seed = (uint64_t(frame_params.seed_hi) << 32) | uint64_t(frame_params.seed_lo);
    SssDomain domain;
    if (!domain_new(gpixels[pixel], pixel, frame_params.frame, params.pass, seed, domain)) {
        reservoirs_out[pixel] = reservoir_empty();
        diag[pixel] = uvec4(0u);
        return;
    }
    domain.target = params.target;
    PixelReservoir canonical;
    ProbeCounts counts;
    uint error = candidates_generate(domain, params.bssrdf_samples, params.shared_light != 0u,
        canonical, counts);
    if (error != 0u) {
        reservoirs_out[pixel] = reservoir_empty();
        diag[pixel] = uvec4(0u, 0u, 0u, error);
        return;
    }
    candidates_shadow_test(domain, canonical);
    reservoirs_out[pixel] = canonical;
    uvec4 diagnostics = uvec4(0u);
    if (params.collect_diagnostics != 0u) {
        uint choice = candidates_hybrid_choice(domain, canonical);
        diagnostics = uvec4(counts.probes, counts.hits, choice, 0u);
    }
    if (counts.overflow) {
        diagnostics.w = HIT_OVERFLOW;
    }
    if (!loop_budget_intact(min(frame_params.width, 1u))) {
        diagnostics.w = LOOP_BUDGET_CUT;
    }
    diag[pixel] = diagnostics;
}
