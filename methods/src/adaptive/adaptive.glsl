// The variance-guided sample count of paper 004: the GLSL twin of
// methods/src/adaptive/cpu.rs (read the two side by side; same functions, same operation
// order). A sample of the method is pt_estimate_with (pt.glsl) with the radius sampling of the
// parameters; a frame's pixel value is the f64 mean of its samples rounded to f32, as on the CPU.
//
// Per frame and translucent pixel: the history carried by gbuffer_reproject (gbuffer.glsl) from
// the previous frame's history buffer (valid = 0 where the CPU has None), the count
// adaptive_sample_count, the samples, then adaptive_update with the perceptual luminance of the
// mean; other pixels take b_min samples and keep no history. pow() in
// adaptive_perceptual_luminance is the device's (not bit-exact with libm's powf): a count that
// sits on an integer boundary of ⌈n̂⌉ may differ from the CPU's.

#ifndef SSS_ADAPTIVE_GLSL
#define SSS_ADAPTIVE_GLSL

#include "scene.glsl"

// 1.0 / GAMMA in f32 (GAMMA = 2.2).
const float ADAPTIVE_INVERSE_GAMMA = 0.45454543828964233;

// std430, 24 bytes: AdaptiveParams (radius in RadiusSampling order, bssrdf.glsl).
struct AdaptiveParams {
    float alpha;
    float target_variance;
    float kappa;
    uint b_min;
    uint b_max;
    uint radius;
};

// std430, 16 bytes (Rust twin engine::vulkan::GpuHistory): Option<History>, valid = 0 for None.
struct History {
    float mean_count;
    float mean;
    float variance;
    uint valid;
};

// History::COLD.
History adaptive_history_cold() {
    return History(0.0, 0.0, 0.0, 1u);
}

// sample_count [004 Eq. 7, 13-15]: kappa Delta + E(n-bar) clamped to [b_min, b_max], rounded up;
// b_min without history.
uint adaptive_sample_count(AdaptiveParams params, History h) {
    if (h.valid == 0u) {
        return params.b_min;
    }
    precise float k = 2.0 / params.alpha - 1.0;
    precise float ratio = h.variance / params.target_variance;
    precise float expected = ratio * h.mean_count;
    precise float correction = (ratio - 1.0) * h.mean_count * (k - 1.0);
    precise float estimate = params.kappa * correction + expected;
    if (!(estimate > float(params.b_min))) {
        return params.b_min;
    }
    if (estimate >= float(params.b_max)) {
        return params.b_max;
    }
    return uint(ceil(estimate));
}

// update [004 Eq. 6, 8, 9]; without history (count, value, sigma0^2) [004 Eq. 16-17].
History adaptive_update(AdaptiveParams params, History h, uint count, float value) {
    if (h.valid == 0u) {
        return History(float(count), value, params.target_variance, 1u);
    }
    float alpha = params.alpha;
    precise float keep = 1.0 - alpha;
    precise float diff = value - h.mean;
    precise float mean_count = keep * h.mean_count + alpha * float(count);
    precise float mean = keep * h.mean + alpha * value;
    precise float variance = keep * h.variance + alpha * keep * (diff * diff);
    return History(mean_count, mean, variance, 1u);
}

// perceptual_luminance: Y^(1/2.2), 0 for Y <= 0.
float adaptive_perceptual_luminance(vec3 rgb) {
    float y = luminance(rgb);
    if (y > 0.0) {
        return pow(y, ADAPTIVE_INVERSE_GAMMA);
    }
    return 0.0;
}

#endif
