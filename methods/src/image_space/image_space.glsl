// Image-space subsurface scattering of paper 002: the GLSL twin of
// methods/src/image_space/cpu.rs (read the two side by side; same functions, same random
// numbers in the same order, same operation order). Per pass: an irradiance kernel writes
// image_space_irradiance_at for every translucent pixel, then a gather kernel computes
// image_space_gather_pixel and image_space_exit_radiance per translucent pixel (Lambert pixels:
// pt_estimate, the path tracer's sample `pass`).
//
// Include after `#define SCENE_BINDING ...` and the int64 extension (this file includes pt.glsl,
// hence bssrdf.glsl, scene.glsl and dipole.glsl). The gather reads other pixels of the frame: the
// including kernel defines
//   GPixel image_space_fetch_pixel(uint pixel);      // the frame's G-buffer
//   vec3 image_space_fetch_irradiance(uint pixel);   // this pass's irradiance buffer
// (declared below, defined anywhere in the kernel). Rust's `lookup` closure is
// image_space_lookup_pixel, the only lookup the device needs.
//
// Host data: a GatherProfile per material (its GpuDipoleProfiles, its FresnelTransmission — the
// material's ior and 1 − F_dr(ior), as GpuMaterial carries them —, ρ_c and the renormalised P(c),
// all computed on the host as GatherProfile::new does) and the ImageSpaceSettings.
// Device transcendentals (not bit-exact with libm): exp/expm1/log1p of the dipole, sqrt is exact,
// cos/sin of the disk angle.

#ifndef SSS_IMAGE_SPACE_GLSL
#define SSS_IMAGE_SPACE_GLSL

#include "rng.glsl"
#include "pt.glsl"

// IMAGE_SPACE_PURPOSE_IRRADIANCE, IMAGE_SPACE_PURPOSE_GATHER and the lookups IMAGE_SPACE_ENTRY,
// IMAGE_SPACE_OFF_SCREEN, IMAGE_SPACE_OCCLUDED (contract.rs beside this file).
#include "contract/image_space.glsl"
// std::f32::consts::PI and TAU.
const float IMAGE_SPACE_PI = 3.14159274101257324;
const float IMAGE_SPACE_TAU = 6.28318548202514648;

GPixel image_space_fetch_pixel(uint pixel);
vec3 image_space_fetch_irradiance(uint pixel);

// std430, 24 bytes: ImageSpaceSettings.
struct ImageSpaceSettings {
    uint irradiance_samples;
    uint importance_samples;
    uint uniform_samples;
    float channel[3];
};

// std430, 108 bytes (Rust twin engine::vulkan::GpuGatherProfile): GatherProfile (dipoles, the
// material's F_t, reflectance ρ_c, renormalised P(c)).
struct GatherProfile {
    GpuDipoleProfiles dipoles;
    FresnelTransmission fresnel;
    float reflectance[3];
    float channel[3];
};

// EntryCounts: samples, off_screen, occluded, outside, edge_on.
struct EntryCounts {
    uint samples;
    uint off_screen;
    uint occluded;
    uint outside;
    uint edge_on;
};

// Receiver: x_o, the frame of its camera-facing geometric normal, the eye.
struct Receiver {
    vec3 position;
    Frame frame;
    vec3 eye;
};

// GatherProfile::pick_channel: the channel whose cumulative interval contains u (never one of
// probability 0).
uint image_space_gather_profile_pick_channel(GatherProfile p, float u) {
    precise float cumulative = 0.0;
    uint last = 0u;
    for (uint c = 0u; c < 3u; c++) {
        float probability = p.channel[c];
        if (probability <= 0.0) {
            continue;
        }
        cumulative = cumulative + probability;
        last = c;
        if (u < cumulative) {
            return c;
        }
    }
    return last;
}

// GatherProfile::importance_density: sum_c P(c) R_d,c(r') / rho_c.
float image_space_gather_profile_importance_density(GatherProfile p, float r) {
    precise float sum = 0.0;
    for (uint c = 0u; c < 3u; c++) {
        if (p.channel[c] > 0.0) {
            precise float term = p.channel[c]
                * (dipole_profile(p.dipoles.channels[c], r) / p.reflectance[c]);
            sum = sum + term;
        }
    }
    return sum;
}

// projection_jacobian: |dA_x / dA_p'| = |n'.v'| d^3 / (|n.v| d'^3) [002 Eq. 8]; 0 edge-on.
float image_space_projection_jacobian(vec3 eye, vec3 p_prime, vec3 n_prime, vec3 x, vec3 n) {
    precise vec3 v_prime = p_prime - eye;
    precise vec3 v = x - eye;
    float d2 = glam_length_squared(v);
    float d2_prime = glam_length_squared(v_prime);
    precise float denominator = abs(glam_dot(n, v)) * d2_prime * sqrt(d2_prime);
    if (!(denominator > 0.0)) {
        return 0.0;
    }
    precise float j = abs(glam_dot(n_prime, v_prime)) * d2 * sqrt(d2) / denominator;
    return j;
}

// lookup_pixel: the pixel q whose (jittered) sample lies nearest to the projection of p' under
// `camera` (the frame's), an entry point if it shows `object`: x where the eye ray through p'
// meets q's tangent plane, q's geometric normal and irradiance; occluded where that ray runs
// parallel to the plane or meets it behind the eye.
uint image_space_lookup_pixel(GpuCamera camera, uint object, vec3 p_prime, out vec3 position,
        out vec3 normal, out vec3 irradiance) {
    position = vec3(0.0);
    normal = vec3(0.0);
    irradiance = vec3(0.0);
    vec2 c;
    if (!camera_project(camera, p_prime, c)) {
        return IMAGE_SPACE_OFF_SCREEN;
    }
    precise vec2 q = floor(vec2(c.x - camera.jitter[0], c.y - camera.jitter[1]));
    if (!(q.x >= 0.0 && q.y >= 0.0 && q.x < float(camera.width) && q.y < float(camera.height))) {
        return IMAGE_SPACE_OFF_SCREEN;
    }
    uint pixel = uint(q.y) * camera.width + uint(q.x);
    GPixel g = image_space_fetch_pixel(pixel);
    if (g.valid == 0u || g.object != object) {
        return IMAGE_SPACE_OCCLUDED;
    }
    vec3 eye = camera_eye(camera);
    vec3 n = pt_vec3(g.geometric_normal);
    precise vec3 ray = p_prime - eye;
    precise float t = glam_dot(n, pt_vec3(g.position) - eye) / glam_dot(n, ray);
    if (!(t > 0.0 && rust_is_finite(t))) {
        return IMAGE_SPACE_OCCLUDED;
    }
    precise vec3 x = eye + ray * t;
    position = x;
    normal = n;
    irradiance = image_space_fetch_irradiance(pixel);
    return IMAGE_SPACE_ENTRY;
}

// gather_pixel: B(x_o) per channel [002 Eq. 4] from N_i dipole and N_u uniform tangent-plane
// samples combined by the balance heuristic; entry points of `object` looked up under `camera`.
vec3 image_space_gather_pixel(Receiver receiver, GatherProfile profile,
        ImageSpaceSettings settings, GpuCamera camera, uint object, inout Stream rng,
        inout EntryCounts counts) {
    float r_support = profile.dipoles.r_max_all;
    bool black = profile.channel[0] == 0.0 && profile.channel[1] == 0.0
        && profile.channel[2] == 0.0;
    uint importance = black ? 0u : settings.importance_samples;
    precise float uniform_density =
        float(settings.uniform_samples) / (IMAGE_SPACE_PI * r_support * r_support);
    precise vec3 sum = vec3(0.0);
    for (uint j = 0u; j < importance + settings.uniform_samples; j++) {
        counts.samples++;
        float r_prime;
        if (j < importance) {
            uint c = image_space_gather_profile_pick_channel(profile, stream_next_f32(rng));
            r_prime = dipole_sample_radius(profile.dipoles.channels[c], stream_next_f32(rng));
        } else {
            precise float r = r_support * sqrt(stream_next_f32(rng));
            r_prime = r;
        }
        precise float phi = IMAGE_SPACE_TAU * stream_next_f32(rng);
        if (!(r_prime <= r_support)) {
            counts.outside++;
            continue;
        }
        precise vec3 offset = cos(phi) * receiver.frame.t + sin(phi) * receiver.frame.b;
        precise vec3 p_prime = receiver.position + r_prime * offset;
        vec3 x, normal, irradiance;
        uint found = image_space_lookup_pixel(camera, object, p_prime, x, normal, irradiance);
        if (found == IMAGE_SPACE_OFF_SCREEN) {
            counts.off_screen++;
            continue;
        }
        if (found == IMAGE_SPACE_OCCLUDED) {
            counts.occluded++;
            continue;
        }
        float r = glam_length(x - receiver.position);
        if (r > r_support) {
            counts.outside++;
            continue;
        }
        float jacobian = image_space_projection_jacobian(receiver.eye, p_prime, receiver.frame.n,
            x, normal);
        if (jacobian == 0.0) {
            counts.edge_on++;
            continue;
        }
        precise float density = float(importance)
            * image_space_gather_profile_importance_density(profile, r_prime) + uniform_density;
        precise vec3 term = dipole_profiles_profile_rgb(profile.dipoles, r) * irradiance
            * (jacobian / density);
        sum = sum + term;
    }
    return sum;
}

// irradiance_at: E(x) [002 Eq. 5], the mean of `samples` light samples
// L_e F_t(n_s.wi) (n_s.wi) / p_light with the material's F_t = `fresnel`, shadow-tested.
vec3 image_space_irradiance_at(GPixel x, FresnelTransmission fresnel, uint samples,
        inout Stream rng) {
    vec3 position = pt_vec3(x.position);
    vec3 shading_normal = pt_vec3(x.shading_normal);
    precise vec3 sum = vec3(0.0);
    for (uint i = 0u; i < samples; i++) {
        float u0 = stream_next_f32(rng);
        float u1 = stream_next_f32(rng);
        float u2 = stream_next_f32(rng);
        LightSample light;
        if (!lights_sample(position, vec3(u0, u1, u2), light)) {
            continue;
        }
        float cos_i = glam_dot(shading_normal, light.wi);
        if (!(cos_i > 0.0 && light.pdf > 0.0)) {
            continue;
        }
        if (pt_occluded(position, pt_vec3(x.geometric_normal), light.wi, light.distance)) {
            continue;
        }
        precise float scale = fresnel_transmission_eval(fresnel, cos_i) * cos_i / light.pdf;
        sum = sum + light.radiance * scale;
    }
    if (samples > 0u) {
        precise vec3 mean = sum / float(samples);
        return mean;
    }
    return vec3(0.0);
}

// exit_radiance: F_t(n_o.wo)/pi B [002 Eq. 3] with the material's F_t = `fresnel`.
vec3 image_space_exit_radiance(GPixel x, FresnelTransmission fresnel, vec3 b) {
    precise float scale = PT_FRAC_1_PI * fresnel_transmission_eval(fresnel,
        glam_dot(pt_vec3(x.shading_normal), pt_vec3(x.view)));
    precise vec3 l = b * scale;
    return l;
}

// The irradiance stream of pixel `pixel` in pass `pass` (the StreamKey of `irradiance`).
Stream image_space_irradiance_stream(uint pixel, uint frame, uint pass, uint64_t seed) {
    return stream_new(StreamKey(pixel, frame, pass, IMAGE_SPACE_PURPOSE_IRRADIANCE), seed);
}

// The gather stream of pixel `pixel` in pass `pass` (the StreamKey of `pass_values`).
Stream image_space_gather_stream(uint pixel, uint frame, uint pass, uint64_t seed) {
    return stream_new(StreamKey(pixel, frame, pass, IMAGE_SPACE_PURPOSE_GATHER), seed);
}

#endif
