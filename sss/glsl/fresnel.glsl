// Fresnel terms of a smooth dielectric: the GLSL twin of sss/src/material/fresnel.rs (read them
// side by side). FresnelTransmission's normalisation 1 - F_dr(eta) is computed on the host (f64
// closed form with logarithms) and uploaded in GpuMaterial; the device only divides by it.

#ifndef SSS_FRESNEL_GLSL
#define SSS_FRESNEL_GLSL

#include "frame.glsl"

// fresnel_dielectric: unpolarised reflectance, cos_i on the incident side, eta = eta_t / eta_i;
// 1 under total internal reflection.
float fresnel_dielectric(float cos_i_in, float eta) {
    precise float cos_i = rust_clamp(cos_i_in, 0.0, 1.0);
    precise float sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if (sin2_t >= 1.0) {
        return 1.0;
    }
    precise float cos_t = sqrt(1.0 - sin2_t);
    precise float r_parallel = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    precise float r_perpendicular = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    precise float f = 0.5 * (r_parallel * r_parallel + r_perpendicular * r_perpendicular);
    return f;
}

// FresnelTransmission: the normalised transmittance F_t(mu) = (1 - F(mu, eta)) / (1 - F_dr(eta))
// of the BSSRDF [001 Eq. 2]; `normalization` = 1 - F_dr(eta) as the host computed it.
struct FresnelTransmission {
    float eta;
    float normalization;
};

// FresnelTransmission::eval: mu clamped to [0, 1] (F_t(mu <= 0) = 0).
float fresnel_transmission_eval(FresnelTransmission ft, float mu) {
    precise float t = (1.0 - fresnel_dielectric(mu, ft.eta)) / ft.normalization;
    return t;
}

#endif
