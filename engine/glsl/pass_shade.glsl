#version 460
// The shade pass: the GLSL twin of engine/src/cpu.rs `shade` per pixel. Translucent primary
// hits get f(Y) W of their reservoir (reuse::shade), or with params.shade (Shade::AllInputs) the
// Rao-Blackwellised value of the frame's last reuse pass that resampled them, where one was
// written (rao_blackwellised[pixel].w != 0); other primary hits get one sample of the
// path tracer's estimator with the stream StreamKey { pixel, frame, pass, OPAQUE }, so a ReSTIR
// image and a path-traced one estimate the same radiance everywhere. A non-finite value is
// written as 0 with w = 1 (the CPU counts it in `nan_count`); so is a path-traced sample whose
// probe had more than BVH_MAX_HITS hits (the GPU keeps only that many, so it would be biased).
// Bindings: the scene's, then PassKernel::Shade's (engine/src/plan/kernels.rs).
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require

layout(local_size_x = 64) in;

#include "contract/pass_params.glsl"

#define SCENE_BINDING 0
// Hits kept per probe (KEPT_HITS of the contract). Probes of the path tracer see at most 8 on
// the built-in scenes (bumpy, 32×32, 64 spp); 16 leaves room, beyond is flagged.
#include "contract/engine.glsl"
#define BVH_MAX_HITS KEPT_HITS
#include "scene.glsl"
#include "sample.glsl"
#include "domain.glsl"
#include "pt.glsl"

#include "contract/pass_shade_bindings.glsl"

// reuse::shade: f(Y) W, 0 for an empty reservoir.
vec3 reuse_shade(SssDomain domain, PixelReservoir reservoir) {
    if (reservoir.has_sample == 0u) {
        return vec3(0.0);
    }
    precise vec3 value = domain_contribution(domain, reservoir.y) * reservoir.ucw;
    return value;
}

void main() {
    uint pixel = gl_GlobalInvocationID.x;
    if (pixel >= frame_params.width * frame_params.height) {
        return;
    }
    GPixel x1 = gpixels[pixel];
    if (x1.valid == 0u) {
        image[pixel] = vec4(0.0);
        return;
    }
    uint64_t seed = scene_seed();
    SssDomain domain;
    vec3 value;
    if (domain_new(x1, pixel, frame_params.frame, params.pass, seed, domain)) {
        domain.target = params.target;
        // Selected shading binds no per-pixel values: the buffer is read only with params.shade.
        vec4 rao_blackwellised_value = vec4(0.0);
        if (params.shade != 0u) {
            rao_blackwellised_value = rao_blackwellised[pixel];
        }
        if (rao_blackwellised_value.w != 0.0) {
            value = rao_blackwellised_value.xyz;
        } else {
            value = reuse_shade(domain, reservoirs_in[pixel]);
        }
    } else {
        Stream rng = stream_new(StreamKey(pixel, frame_params.frame, params.pass, PURPOSE_OPAQUE), seed);
        value = pt_estimate(x1, PT_HITS_ALL, rng);
    }
    bool finite = !any(isnan(value)) && !any(isinf(value));
    image[pixel] = finite && pt_hit_overflow == 0u ? vec4(value, 0.0) : vec4(0.0, 0.0, 0.0, 1.0);
}
