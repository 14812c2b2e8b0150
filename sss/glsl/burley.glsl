// Burley's normalized diffusion profile for one colour channel: the GLSL twin of
// sss/src/profile/burley.rs [001 Eq. 3-4] (read the two side by side; same algorithm, same
// operation order).
//
// GLSL has no expm1/log1p, and its exp/log/asinh/sinh carry only the Vulkan precision bounds
// (exp: 3 + 2|x| ulp; log: 3 ulp outside [0.5, 2], absolute 2^-21 inside; asinh/sinh inherit
// from log/exp, i.e. absolute error near 0). The twin therefore builds expm1, log1p, asinh and
// sinh from +, *, / and sqrt (series below), and calls the native exp/log only where their
// relative bound holds. It still differs from the CPU in the last bits; the parity test
// (engine/tests/vulkan_parity.rs) states the tolerance and how it follows from these bounds.

#ifndef SSS_BURLEY_GLSL
#define SSS_BURLEY_GLSL

// BURLEY_R_MAX_QUANTILE (sss/src/contract.rs).
#include "contract/sss.glsl"

const float BURLEY_PI = 3.14159265358979323846;

float burley_infinity() {
    return uintBitsToFloat(0x7F800000u);
}

// e^x - 1: degree-9 Taylor (Horner) for |x| <= 1/2, whose truncation is below 2^-26 relative;
// beyond, exp(x) - 1 loses at most a factor e^x / |e^x - 1| <= 1.55 (x <= -1/2) of exp's bound.
float burley_expm1(float x) {
    if (abs(x) > 0.5) {
        precise float e = exp(x) - 1.0;
        return e;
    }
    precise float p = 1.0 / 362880.0;
    p = p * x + 1.0 / 40320.0;
    p = p * x + 1.0 / 5040.0;
    p = p * x + 1.0 / 720.0;
    p = p * x + 1.0 / 120.0;
    p = p * x + 1.0 / 24.0;
    p = p * x + 1.0 / 6.0;
    p = p * x + 0.5;
    p = p * x + 1.0;
    p = p * x;
    return p;
}

// ln(1 + z) = 2 atanh(s), s = z / (2 + z), as an odd series in s for z in [-1/2, 1]
// (|s| <= 1/3, truncation after s^17 below 2^-27 relative); elsewhere 1 + z loses nothing
// and lies outside [1/2, 2], where the native log has a relative bound.
float burley_log1p(float z) {
    if (z < -0.5 || z > 1.0) {
        precise float l = log(1.0 + z);
        return l;
    }
    precise float s = z / (2.0 + z);
    precise float s2 = s * s;
    precise float p = 1.0 / 17.0;
    p = p * s2 + 1.0 / 15.0;
    p = p * s2 + 1.0 / 13.0;
    p = p * s2 + 1.0 / 11.0;
    p = p * s2 + 1.0 / 9.0;
    p = p * s2 + 1.0 / 7.0;
    p = p * s2 + 1.0 / 5.0;
    p = p * s2 + 1.0 / 3.0;
    p = p * s2 + 1.0;
    precise float l = 2.0 * s * p;
    return l;
}

// ln x with a relative bound everywhere: x in [1/2, 2] goes through log1p (x - 1 is exact there).
float burley_log(float x) {
    if (x >= 0.5 && x <= 2.0) {
        return burley_log1p(x - 1.0);
    }
    return log(x);
}

// asinh(w) for w >= 0: ln(1 + w + w^2 / (1 + sqrt(1 + w^2))), without cancellation near 0.
float burley_asinh(float w) {
    precise float w2 = w * w;
    precise float z = w + w2 / (1.0 + sqrt(1.0 + w2));
    return burley_log1p(z);
}

// sinh(a) for 0 <= a <= 1/2 (all the Cardano step needs): odd Taylor series to a^11
// (truncation below 2^-30 relative).
float burley_sinh_small(float a) {
    precise float a2 = a * a;
    precise float p = 1.0 / 39916800.0;
    p = p * a2 + 1.0 / 362880.0;
    p = p * a2 + 1.0 / 5040.0;
    p = p * a2 + 1.0 / 120.0;
    p = p * a2 + 1.0 / 6.0;
    p = p * a2 + 1.0;
    precise float s = a * p;
    return s;
}

// Density of the radius r: (e^{-r/d} + e^{-r/3d}) / (4d); 0 for r < 0 or non-finite r.
float burley_pdf_radius(float d, float r) {
    if (isnan(r) || r < 0.0 || isinf(r)) {
        return 0.0;
    }
    precise float pdf = (exp(-r / d) + exp(-r / (3.0 * d))) / (4.0 * d);
    return pdf;
}

// Disk-area density R_d(r) = (e^{-r/d} + e^{-r/3d}) / (8 pi d r) [001 Eq. 3]; 0 for r <= 0 and
// for non-finite r.
float burley_pdf_disk(float d, float r) {
    if (!(r > 0.0) || isinf(r)) {
        return 0.0;
    }
    precise float pdf = burley_pdf_radius(d, r) / ((2.0 * BURLEY_PI) * r);
    return pdf;
}

// P(r) = 1 - e^{-r/d}/4 - 3e^{-r/3d}/4 [001 Eq. 4] through expm1; 0 for r <= 0, 1 for r = inf.
float burley_cdf(float d, float r) {
    if (isnan(r) || r <= 0.0) {
        return 0.0;
    }
    precise float v = -(0.25 * burley_expm1(-r / d) + 0.75 * burley_expm1(-r / (3.0 * d)));
    return min(v, 1.0);
}

// The inverse of burley_cdf for u in [0, 1): Cardano on x^3 + 3x = 4(1 - u), x = e^{-r/3d},
// and for u <= 1/2 Newton on y = 1 - x (y^3 - 3y^2 + 6y = 4u). u <= 0 gives 0, u >= 1 gives inf.
float burley_sample_radius(float d, float u) {
    if (isnan(u) || u <= 0.0) {
        return 0.0;
    }
    if (u >= 1.0) {
        return burley_infinity();
    }
    precise float x_cardano = 2.0 * burley_sinh_small(burley_asinh(2.0 * (1.0 - u)) / 3.0);
    if (u > 0.5) {
        precise float r = -3.0 * d * burley_log(x_cardano);
        return r;
    }
    // f'(y) = 3((y - 1)^2 + 1) >= 3, so Newton is safe.
    precise float y = max(1.0 - x_cardano, 0.0);
    for (int i = 0; i < 3; i++) {
        precise float f = y * (y * (y - 3.0) + 6.0) - 4.0 * u;
        precise float df = 3.0 * ((y - 1.0) * (y - 1.0) + 1.0);
        y -= f / df;
    }
    precise float r = -3.0 * d * burley_log1p(-y);
    return r;
}

// Truncation radius P^{-1}(R_MAX_QUANTILE).
float burley_r_max(float d) {
    return burley_sample_radius(d, BURLEY_R_MAX_QUANTILE);
}

#endif
