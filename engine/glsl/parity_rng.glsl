#version 460
// Parity kernel for restir/glsl/rng.glsl: per key, `draws` next_u32 values, then `draws`
// next_f32 values from a fresh stream of the same key (engine/tests/vulkan_parity.rs).
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#include "rng.glsl"

layout(local_size_x = 64) in;

layout(std430, binding = 0) readonly buffer Keys { StreamKey keys[]; };
layout(std430, binding = 1) writeonly buffer Bits { uint bits[]; };
layout(std430, binding = 2) writeonly buffer Units { float units[]; };

layout(push_constant) uniform Params {
    uint count;
    uint draws;
    uint seed_lo;
    uint seed_hi;
} params;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= params.count) {
        return;
    }
    uint64_t seed = (uint64_t(params.seed_hi) << 32) | uint64_t(params.seed_lo);
    Stream s = stream_new(keys[i], seed);
    for (uint k = 0u; k < params.draws; k++) {
        bits[i * params.draws + k] = stream_next_u32(s);
    }
    Stream t = stream_new(keys[i], seed);
    for (uint k = 0u; k < params.draws; k++) {
        units[i * params.draws + k] = stream_next_f32(t);
    }
}
