// Weighted reservoir sampling [001 Alg. 1]: the GLSL twin of restir/src/reservoir.rs, specialised
// to the SSS sample (GLSL has no generics). The streaming state `Ris` and the stored state
// `PixelReservoir` (shifts/glsl/sample.glsl) are two types, as in Rust.
//
// Typed errors become codes: `ris_update` / `ris_skip` return 0 or one of the RESAMPLE_INVALID_*
// codes, which the resampling driver (resample.glsl) tags with the domain index and the passes
// write into their diag buffer's `w` (see resample.glsl for the layout).

#ifndef RESTIR_RESERVOIR_GLSL
#define RESTIR_RESERVOIR_GLSL

#include "sample.glsl"
// The error codes RESAMPLE_INVALID_* (InvalidCandidate) and RESAMPLE_* (ResampleError).
#include "contract/restir.glsl"

// `f32::is_finite`.
bool reservoir_is_finite(float x) {
    return !isnan(x) && !isinf(x);
}

// `c_prev <- min(c_prev, cap * c_cur)`: the temporal confidence cap [001 §5]. `f32::min`
// semantics: a NaN operand yields the other one.
float reservoir_cap_confidence(float c_prev, float c_cur, float cap) {
    precise float capped = cap * c_cur;
    if (isnan(c_prev)) {
        return capped;
    }
    if (isnan(capped)) {
        return c_prev;
    }
    return capped < c_prev ? capped : c_prev;
}

// Streaming GRIS state [001 Alg. 1-2] (restir::reservoir::Ris<SssSample>).
struct Ris {
    float w_sum;
    float confidence;
    bool has_selected;
    SssSample selected;
    float selected_target;
};

Ris ris_new() {
    Ris r;
    r.w_sum = 0.0;
    r.confidence = 0.0;
    r.has_selected = false;
    r.selected = reservoir_empty().y;
    r.selected_target = 0.0;
    return r;
}

// Ris::update: streams candidate `y` with target p̂_r(y), resampling weight `w` and confidence
// `c`; `u * w_sum < w` selects [001 Alg. 1]. Returns 0 or the InvalidCandidate code; a bad input
// never poisons the state (same order of checks as the Rust).
uint ris_update(inout Ris ris, SssSample y, float target, float weight, float confidence,
                float u) {
    bool confidence_ok = reservoir_is_finite(confidence) && confidence >= 0.0;
    if (confidence_ok) {
        ris.confidence = ris.confidence + confidence;
    }
    if (!(reservoir_is_finite(weight) && weight >= 0.0)) {
        return RESAMPLE_INVALID_WEIGHT;
    }
    if (!(reservoir_is_finite(target) && target >= 0.0)) {
        return RESAMPLE_INVALID_TARGET;
    }
    if (!confidence_ok) {
        return RESAMPLE_INVALID_CONFIDENCE;
    }
    if (weight > 0.0 && target > 0.0) {
        precise float w_sum = ris.w_sum + weight;
        if (!reservoir_is_finite(w_sum)) {
            return RESAMPLE_INVALID_WEIGHT;
        }
        ris.w_sum = w_sum;
        precise float scaled = u * w_sum;
        if (scaled < weight) {
            ris.has_selected = true;
            ris.selected = y;
            ris.selected_target = target;
        }
    }
    return 0u;
}

// Ris::skip: a candidate without a sample; its confidence still counts.
uint ris_skip(inout Ris ris, float confidence) {
    if (reservoir_is_finite(confidence) && confidence >= 0.0) {
        ris.confidence = ris.confidence + confidence;
        return 0u;
    }
    return RESAMPLE_INVALID_CONFIDENCE;
}

// Ris::finish: `W = w_sum / p̂_r(Y)` [001 Alg. 2, line 7], 0 without a sample or when not finite;
// stored as PixelReservoir::from(&Reservoir) (a missing sample is all zero bytes).
PixelReservoir ris_finish(Ris ris) {
    PixelReservoir r = reservoir_empty();
    r.confidence = ris.confidence;
    if (ris.has_selected) {
        precise float ucw = ris.w_sum / ris.selected_target;
        r.y = ris.selected;
        r.ucw = reservoir_is_finite(ucw) ? ucw : 0.0;
        r.has_sample = 1u;
    }
    return r;
}

#endif
