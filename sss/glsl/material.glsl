// Twin of sss::material::Material (sss/src/material/). Derived values (d = scale·ℓ/s(A), r_max
// per channel, κ_dist, the Fresnel normalisation) are computed on the host in f32 exactly as Translucent::d, r_max and
// r_max_all compute them and uploaded, so the GPU never re-derives them with its own
// transcendentals. Per-sample profile values (exp) stay on the GPU: burley_pdf_disk.

#ifndef SSS_MATERIAL_GLSL
#define SSS_MATERIAL_GLSL

#include "burley.glsl"
#include "frame.glsl"
#include "fresnel.glsl"

// GpuMaterial and its kinds MATERIAL_<KIND> (engine/src/contract.rs).
#include "contract/engine.glsl"

bool material_is_translucent(GpuMaterial m) {
    return m.kind == MATERIAL_TRANSLUCENT;
}

vec3 material_albedo(GpuMaterial m) {
    return vec3(m.albedo[0], m.albedo[1], m.albedo[2]);
}

// Lambert::emitted: L_e toward a viewer on the front (winding) side, or on either side of a
// two-sided emitter; zero for other materials.
vec3 material_emitted(GpuMaterial m, bool front) {
    vec3 emission = vec3(m.emission[0], m.emission[1], m.emission[2]);
    return front || m.two_sided != 0u ? emission : vec3(0.0);
}

// Translucent::d.
vec3 material_d(GpuMaterial m) {
    return vec3(m.d[0], m.d[1], m.d[2]);
}

// Translucent::r_max.
vec3 material_r_max(GpuMaterial m) {
    return vec3(m.r_max[0], m.r_max[1], m.r_max[2]);
}

// Translucent::r_max_all.
float material_r_max_all(GpuMaterial m) {
    return m.r_max_all;
}

// Translucent::profile_rgb: A_c · R_{d_c}(r) per channel, 0 beyond r_max_all [001 Eq. 3].
vec3 material_profile_rgb(GpuMaterial m, float r) {
    if (r > m.r_max_all) {
        return vec3(0.0);
    }
    precise vec3 p = vec3(m.albedo[0] * burley_pdf_disk(m.d[0], r),
        m.albedo[1] * burley_pdf_disk(m.d[1], r),
        m.albedo[2] * burley_pdf_disk(m.d[2], r));
    return p;
}

// Translucent::fresnel: the normalised Fresnel transmittance of the material's ior.
FresnelTransmission material_fresnel(GpuMaterial m) {
    return FresnelTransmission(m.ior, m.fresnel_normalization);
}

#endif
