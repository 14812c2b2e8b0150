// The resampling driver [001 Alg. 2]: the GLSL twin of restir::resample::resample, specialised to
// the SSS domain and the shifts of shift.glsl, and of the shared tail of engine::reuse
// (Step::run: resample, resolve a deferred index, count shift diagnostics, sum the
// Rao-Blackwellised value).
//
// The domains and reservoirs of one step are shader-private globals (index 0 = the receiver,
// 1..n-1 the neighbours) so that no large array is copied per call. Errors (ResampleError) are
// one uint, 0 = none: the low byte is the kind (a ResampleCode, RESAMPLE_* of the contract),
// bits 8..15 the domain index (`source`; the domain count for RESAMPLE_TOO_MANY_DOMAINS);
// restir::resample::ResampleError::from_gpu reads them back.
// Include after `#define SCENE_BINDING ...`; the including shader enables
// GL_EXT_shader_explicit_arithmetic_types_int64.

#ifndef RESTIR_RESAMPLE_GLSL
#define RESTIR_RESAMPLE_GLSL

#include "mis.glsl"
#include "reservoir.glsl"
#include "shift.glsl"

// The inputs of one resampling step.
SssDomain resample_domains[MAX_DOMAINS];
PixelReservoir resample_inputs[MAX_DOMAINS];

// A ResampleError code: `kind` (a RESAMPLE_* or RESAMPLE_INVALID_* code) from domain `source`.
uint resample_error(uint kind, uint source) {
    return kind | (min(source, 255u) << 8);
}

// resample: combines resample_inputs[0] (the receiver's canonical reservoir) with the `n - 1`
// neighbours into the receiver's domain, one uniform number per input from `rng`, weights
// w_i = m_i(y_i) p̂_r(y_i) W_i J_i; a failed shift or an empty input adds its confidence only.
// Also returns Step::count_shifts' (shifted, failed, improved) from the forward shifts (the
// shifts are deterministic, so re-applying them as the CPU does gives the same outcomes), and,
// when `rao_blackwellise`, the Rao-Blackwellised value Σ_i f(y_i) m_i W_i J_i over the inputs
// with a positive weight (resample_observed's `observe` in Step::run; 0 otherwise).
//
// Every shift (forward T_{i->r}(x_i) at j = 0, back-shifts T_{r->j}(y) for j >= 1) runs through
// the one shift_shift call of the inner loop: Mesa inlines every call site.
uint resample_resample(uint n, ShiftSpec shift, uint mis, bool rao_blackwellise,
                       inout Stream rng, out PixelReservoir result, out uvec3 counts,
                       out vec3 rao_blackwellised) {
    result = reservoir_empty();
    counts = uvec3(0u);
    rao_blackwellised = vec3(0.0);
    precise vec3 sum = vec3(0.0);
    if (n > MAX_DOMAINS) {
        return resample_error(RESAMPLE_TOO_MANY_DOMAINS, n);
    }
    float confidences[MAX_DOMAINS];
    float targets[MAX_DOMAINS];
    for (uint j = 0u; j < MAX_DOMAINS; j++) {
        confidences[j] = j < n ? resample_inputs[j].confidence : 0.0;
        targets[j] = 0.0;
    }
    float canonical_target = resample_inputs[0].has_sample != 0u
        ? domain_target(resample_domains[0], resample_inputs[0].y)
        : 0.0;
    Ris ris = ris_new();
    for (uint i = 0u; i < n; i++) {
        PixelReservoir source = resample_inputs[i];
        float u = stream_next_f32(rng);
        if (!(reservoir_is_finite(source.ucw) && source.ucw >= 0.0)) {
            return resample_error(RESAMPLE_INVALID_UCW, i);
        }
        if (source.has_sample == 0u) {
            uint code = ris_skip(ris, source.confidence);
            if (code != 0u) {
                return resample_error(code, i);
            }
            continue;
        }
        SssSample x = source.y;
        SssSample y = x;
        float jacobian = 1.0;
        float target = 0.0;
        bool weighted = false;
        bool all_targets = mis_needs_all_targets(mis, i);
        bool skipped = false;
        for (uint j = 0u; j < n; j++) {
            bool forward = j == 0u;
            if (!(forward ? i > 0u : weighted && all_targets && j != i)) {
                if (!forward) {
                    continue;
                }
            } else {
                SssSample shifted;
                float shift_jacobian;
                uint fail = shift_shift(shift, forward ? x : y, resample_domains[forward ? i : 0u],
                                        resample_domains[forward ? 0u : j], shifted,
                                        shift_jacobian);
                if (!forward) {
                    targets[j] = shift_target_from(fail, resample_domains[j], shifted,
                                                   shift_jacobian);
                    continue;
                }
                counts.x += 1u;
                if (fail != SHIFT_OK) {
                    counts.y += 1u;
                    skipped = true;
                    break;
                }
                if (!(reservoir_is_finite(shift_jacobian) && shift_jacobian > 0.0)) {
                    return resample_error(RESAMPLE_BAD_JACOBIAN, i);
                }
                y = shifted;
                jacobian = shift_jacobian;
            }
            // After the forward shift (or the canonical sample's identity): p̂_r(y) and the
            // targets the MIS weight reads.
            target = domain_target(resample_domains[0], y);
            if (i > 0u && target > canonical_target) {
                counts.z += 1u;
            }
            if (!(reservoir_is_finite(target) && target >= 0.0)) {
                return resample_error(RESAMPLE_INVALID_TARGET, i);
            }
            weighted = target > 0.0 && source.ucw > 0.0;
            for (uint k = 0u; k < MAX_DOMAINS; k++) {
                targets[k] = 0.0;
            }
            targets[0] = target;
            if (i > 0u) {
                precise float own = domain_target(resample_domains[i], x) / jacobian;
                targets[i] = own;
            }
        }
        if (skipped) {
            uint code = ris_skip(ris, source.confidence);
            if (code != 0u) {
                return resample_error(code, i);
            }
            continue;
        }
        float m = weighted ? mis_weight(mis, i, targets, confidences, n) : 0.0;
        // w_i = m_i(y_i) p̂_r(y_i) W_i J_i   [001 Eq. 6]
        precise float w = m * target * source.ucw * jacobian;
        uint code = ris_update(ris, y, target, w, source.confidence, u);
        if (code != 0u) {
            return resample_error(code, i);
        }
        if (rao_blackwellise && w > 0.0) {
            // Σ_i f(y_i) · m_i W_i J_i = E[f(Y)·W | inputs]   [001 Eq. 6]
            precise float factor = m * source.ucw * jacobian;
            precise vec3 term = domain_contribution(resample_domains[0], y) * factor;
            sum = sum + term;
        }
    }
    result = ris_finish(ris);
    rao_blackwellised = sum;
    return 0u;
}

// Step::run: the receiver's stream (pixel, frame, pass, SELECT), resample, resolve a deferred
// index of the selected sample, the shift counts when `collect`, and the Rao-Blackwellised value
// when `rao_blackwellise` (Shade::AllInputs). Returns the error code.
uint resample_step(uint n, uint shift_kind, uint mis, uint select_purpose, bool collect,
                   bool rao_blackwellise, out PixelReservoir result, out uvec3 counts,
                   out vec3 rao_blackwellised) {
    SssDomain receiver = resample_domains[0];
    ShiftSpec shift = shift_spec(shift_kind, receiver.material);
    Stream rng = stream_new(
        StreamKey(receiver.pixel, receiver.frame, receiver.pass, select_purpose), receiver.seed);
    uint error = resample_resample(n, shift, mis, rao_blackwellise, rng, result, counts,
                                   rao_blackwellised);
    if (!collect) {
        counts = uvec3(0u);
    }
    if (error != 0u) {
        return error;
    }
    if (shift_resolves_deferred_index(shift_kind) && result.has_sample != 0u) {
        inversion_resolve_deferred_index(receiver, result.y);
    }
    return 0u;
}

#endif
