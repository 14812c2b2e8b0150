#version 460
// Parity kernel for engine/glsl/include/reciprocal.glsl: per query (radius, slot, frame, pass),
// the pairing's partner of each of `pixels` pixels, or the pixel itself where the slot is empty
// (engine/tests/vulkan_parity.rs).
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#include "include/reciprocal.glsl"

layout(local_size_x = 64) in;

// engine::vulkan::PairingQuery.
struct PairingQuery {
    float radius;
    uint slot;
    uint frame;
    uint pass;
};

layout(std430, binding = 0) readonly buffer Queries { PairingQuery queries[]; };
layout(std430, binding = 1) readonly buffer Pixels { ivec2 pixels[]; };
layout(std430, binding = 2) writeonly buffer Partners { ivec2 partners[]; };

layout(push_constant) uniform Params {
    uint count;
    uint pixels;
    uint seed_lo;
    uint seed_hi;
} params;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= params.count) {
        return;
    }
    uint64_t seed = (uint64_t(params.seed_hi) << 32) | uint64_t(params.seed_lo);
    PairingQuery q = queries[i];
    Pairing pairing;
    bool paired = pairing_draw(q.radius, q.slot, q.frame, q.pass, seed, pairing);
    for (uint k = 0u; k < params.pixels; k++) {
        ivec2 p = pixels[k];
        partners[i * params.pixels + k] = paired ? pairing_partner(pairing, p) : p;
    }
}
