// Xie et al.'s approximate inverse of the Burley radius CDF [004 Eq. 21] with the density of its
// own samples: the GLSL twin of sss/src/profile/xie.rs (read them side by side; same algorithm,
// same operation order). A Xie sampler is its `d`. exp and the expm1/log1p substitutes of
// burley.glsl are evaluated on the device (not bit-exact with libm).

#ifndef SSS_XIE_GLSL
#define SSS_XIE_GLSL

#include "burley.glsl"

// XIE_C: the damping constant c of [004 Eq. 21].
const float XIE_C = 2.5715;
// XIE_INVERSE_ITERATIONS of the bracketed Newton solve (sss/src/contract.rs).
#include "contract/sss.glsl"

// approximate_inverse: g(xi | c) = d ((2 - c) xi - 2) ln(1 - xi) for xi in (0, 1).
float xie_approximate_inverse(float d, float c, float xi) {
    precise float g = d * ((2.0 - c) * xi - 2.0) * burley_log1p(-xi);
    return g;
}

// Xie::sample_radius: g(xi); 0 for xi <= 0, +inf for xi >= 1.
float xie_sample_radius(float d, float xi) {
    if (isnan(xi) || xi <= 0.0) {
        return 0.0;
    }
    if (xi >= 1.0) {
        return burley_infinity();
    }
    return xie_approximate_inverse(d, XIE_C, xi);
}

// Xie::inverse_t: t = -ln(1 - g^{-1}(r)), the root of (2 + k(1 - e^{-t})) t = r/d in
// [rho/(2 + k), rho/2], by Newton kept inside the bracket.
float xie_inverse_t(float d, float r) {
    if (isnan(r) || r <= 0.0) {
        return 0.0;
    }
    if (isinf(r)) {
        return burley_infinity();
    }
    precise float k = XIE_C - 2.0;
    precise float rho = r / d;
    precise float lo = rho / (2.0 + k);
    precise float hi = rho / 2.0;
    precise float t = 0.5 * (lo + hi);
    for (int i = 0; i < XIE_INVERSE_ITERATIONS; i++) {
        precise float one_minus_decay = -burley_expm1(-t);
        precise float h = (2.0 + k * one_minus_decay) * t - rho;
        if (h == 0.0) {
            break;
        }
        if (h > 0.0) {
            hi = t;
        } else {
            lo = t;
        }
        precise float dh = 2.0 + k * one_minus_decay + k * t * exp(-t);
        precise float newton = t - h / dh;
        precise float next = (newton >= lo && newton <= hi) ? newton : 0.5 * (lo + hi);
        if (next == t) {
            break;
        }
        t = next;
    }
    return t;
}

// Xie::cdf: g^{-1}(r) = 1 - e^{-t}.
float xie_cdf(float d, float r) {
    precise float c = -burley_expm1(-xie_inverse_t(d, r));
    return c;
}

// Xie::pdf_radius: 1 / g'(g^{-1}(r)) = e^{-t} / (d (k t e^{-t} + 2 + k xi)); 0 for r < 0, NaN or
// +inf.
float xie_pdf_radius(float d, float r) {
    if (isnan(r) || r < 0.0 || isinf(r)) {
        return 0.0;
    }
    precise float k = XIE_C - 2.0;
    float t = xie_inverse_t(d, r);
    precise float xi = -burley_expm1(-t);
    precise float decay = exp(-t);
    precise float pdf = decay / (d * (k * t * decay + 2.0 + k * xi));
    return pdf;
}

// Xie::pdf_disk: pdf_radius(r) / (2 pi r); 0 for r <= 0 or non-finite r.
float xie_pdf_disk(float d, float r) {
    if (!(r > 0.0) || isinf(r)) {
        return 0.0;
    }
    precise float pdf = xie_pdf_radius(d, r) / ((2.0 * BURLEY_PI) * r);
    return pdf;
}

#endif
