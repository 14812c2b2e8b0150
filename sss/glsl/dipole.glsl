// The Jensen dipole [002 Table 1, §4]: the GLSL twin of sss/src/profile/dipole.rs (Dipole) and of
// the DipoleProfiles of sss/src/material/dipole.rs (read them side by side; same algorithm, same
// operation order).
//
// Representation: a Dipole is a GpuDipole whose per-material constants are computed on the host in
// f32 exactly as Dipole computes them (reduced albedo, sigma_tr, z_r, z_v) together with the
// quantities that need a transcendental of those constants (pole_probability(Real) and
// total_reflectance), so the device never re-derives them. Per-sample values stay on the device:
// exp in the profile and the Newton solve, expm1/log1p through burley.glsl's substitutes, and
// r.hypot(z) as sqrt(r r + z z) (libm's hypotf rounds once from double: up to 1 ulp apart). The
// parity tests therefore bound the difference rather than expect bits.

#ifndef SSS_DIPOLE_GLSL
#define SSS_DIPOLE_GLSL

#include "burley.glsl"
#include "frame.glsl"

const float DIPOLE_PI = 3.14159265358979323846;
// f32::EPSILON.
const float DIPOLE_F32_EPSILON = 1.1920928955078125e-7;
// ONE_MINUS_EPSILON: the largest f32 below 1.
const float DIPOLE_ONE_MINUS_EPSILON = 0.999999940395355225;
// DIPOLE_NEWTON_ITERATIONS and the poles DIPOLE_POLE_* (sss/src/contract.rs).
#include "contract/sss.glsl"

// std430, 24 bytes (Rust twin engine::vulkan::GpuDipole): Dipole's fields plus
// pole_probability(Real) and total_reflectance() from the host.
struct GpuDipole {
    float reduced_albedo;
    float sigma_tr;
    float z_r;
    float z_v;
    float p_real;
    float rho;
};

// Dipole::depth.
float dipole_depth(GpuDipole d, uint pole) {
    return pole == DIPOLE_POLE_REAL ? d.z_r : d.z_v;
}

// One pole's term z (1 + sigma_tr s) e^{-sigma_tr s} / s^3 of Dipole::profile.
float dipole_term(GpuDipole d, float r, float z) {
    precise float s = sqrt(r * r + z * z);
    precise float t = z * (1.0 + d.sigma_tr * s) * exp(-d.sigma_tr * s) / (s * s * s);
    return t;
}

// Dipole::profile: R_d(r) = alpha'/(4 pi) sum_z z (1 + sigma_tr s) e^{-sigma_tr s} / s^3.
float dipole_profile(GpuDipole d, float r) {
    precise float p = d.reduced_albedo / (4.0 * DIPOLE_PI)
        * (dipole_term(d, r, d.z_r) + dipole_term(d, r, d.z_v));
    return p;
}

// Dipole::pdf_disk: R_d(r) / rho; 0 for r < 0 (or NaN) or rho = 0.
float dipole_pdf_disk(GpuDipole d, float r) {
    if (!(r >= 0.0 && d.rho > 0.0)) {
        return 0.0;
    }
    precise float p = dipole_profile(d, r) / d.rho;
    return p;
}

// Dipole::pole_cdf: 1 - exp(-sigma_tr r^2/(s + z) - ln(1 + r^2/z^2)/2).
float dipole_pole_cdf(GpuDipole d, uint pole, float r) {
    if (isnan(r) || r <= 0.0) {
        return 0.0;
    }
    float z = dipole_depth(d, pole);
    precise float s = sqrt(r * r + z * z);
    precise float ratio = r / z;
    precise float x = -(d.sigma_tr * r * r / (s + z) + 0.5 * burley_log1p(ratio * ratio));
    precise float f = -burley_expm1(x);
    return f;
}

// Dipole::cdf: the mixture P(real) F_real + (1 - P(real)) F_virtual.
float dipole_cdf(GpuDipole d, float r) {
    precise float f = d.p_real * dipole_pole_cdf(d, DIPOLE_POLE_REAL, r)
        + (1.0 - d.p_real) * dipole_pole_cdf(d, DIPOLE_POLE_VIRTUAL, r);
    return f;
}

// Dipole::sample_pole: monotone Newton on t = ln(s/z) for sigma_tr z (e^t - 1) + t + ln(1 - xi)
// = 0, then r = z sqrt(e^{2t} - 1). xi <= 0 gives 0, xi >= 1 gives +inf.
float dipole_sample_pole(GpuDipole d, uint pole, float xi) {
    if (isnan(xi) || xi <= 0.0) {
        return 0.0;
    }
    if (xi >= 1.0) {
        return burley_infinity();
    }
    float z = dipole_depth(d, pole);
    precise float a = d.sigma_tr * z;
    precise float log_survival = -burley_log1p(-xi);
    precise float t = a > 0.0 ? rust_min(log_survival, burley_log1p(log_survival / a))
                              : log_survival;
    for (int i = 0; i < DIPOLE_NEWTON_ITERATIONS; i++) {
        precise float e = burley_expm1(t);
        precise float h = a * e + t - log_survival;
        precise float step = h / (a * (e + 1.0) + 1.0);
        t = t - step;
        precise float tolerance = DIPOLE_F32_EPSILON * t;
        if (isnan(step) || abs(step) <= tolerance) {
            break;
        }
    }
    precise float r = z * sqrt(rust_max(burley_expm1(2.0 * t), 0.0));
    return r;
}

// Dipole::sample_radius: the pole by u against P(real), u rescaled, that pole inverted [002 §4].
float dipole_sample_radius(GpuDipole d, float u) {
    if (u < d.p_real) {
        precise float xi = u / d.p_real;
        return dipole_sample_pole(d, DIPOLE_POLE_REAL, rust_min(xi, DIPOLE_ONE_MINUS_EPSILON));
    }
    precise float xi = (u - d.p_real) / (1.0 - d.p_real);
    return dipole_sample_pole(d, DIPOLE_POLE_VIRTUAL, rust_min(xi, DIPOLE_ONE_MINUS_EPSILON));
}

// ---------------------------------------------------------------- material/dipole.rs

// std430, 76 bytes: DipoleProfiles (the three channels' dipoles of a material, r_max_all).
struct GpuDipoleProfiles {
    GpuDipole channels[3];
    float r_max_all;
};

// DipoleProfiles::profile_rgb: R_d,c(r) per channel, 0 beyond r_max_all.
vec3 dipole_profiles_profile_rgb(GpuDipoleProfiles p, float r) {
    if (r > p.r_max_all) {
        return vec3(0.0);
    }
    return vec3(dipole_profile(p.channels[0], r), dipole_profile(p.channels[1], r),
        dipole_profile(p.channels[2], r));
}

#endif
