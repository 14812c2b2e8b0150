// The pairings of a reciprocal spatial pass: the GLSL twin of engine::reciprocal::Pairing
// (engine/src/reciprocal.rs; read the two side by side). Per neighbour slot one offset for the
// frame, uniform in the disk of the frame's radius, and stripes along the offset's axis that
// send a pixel to p + o or p - o (an involution). Integer arithmetic but for the disk sample
// (sss/glsl/sampling.glsl), whose cos and sin may round differently from the CPU's: the offset
// `floor(o + 1/2)` then differs only where `o + 1/2` is within a few ulp of an integer.
//
// The including shader enables GL_EXT_shader_explicit_arithmetic_types_int64 (rng.glsl).

#ifndef ENGINE_RECIPROCAL_GLSL
#define ENGINE_RECIPROCAL_GLSL

// PURPOSE_PAIRS.
#include "contract/engine.glsl"
#include "rng.glsl"
#include "sampling.glsl"

// Pairing: the offset floor(o + 1/2) (never zero), the axis of the stripes (0: x, where
// offset.x != 0; 1: y) and their phase in 0..|offset[axis]|.
struct Pairing {
    ivec2 offset;
    uint axis;
    int phase;
};

// Pairing::draw: the pairing of neighbour slot `slot` of pass `pass` at `frame`, from the stream
// (slot, frame, pass, PAIRS); false when the offset rounds to zero (the slot is empty).
bool pairing_draw(float radius, uint slot, uint frame, uint pass, uint64_t seed,
                  out Pairing pairing) {
    Stream rng = stream_new(StreamKey(slot, frame, pass, PURPOSE_PAIRS), seed);
    float u_radius = stream_next_f32(rng);
    float u_angle = stream_next_f32(rng);
    precise vec2 o = sampling_uniform_disk(radius, u_radius, u_angle) + vec2(0.5);
    pairing.offset = ivec2(floor(o));
    pairing.axis = pairing.offset.x != 0 ? 0u : 1u;
    pairing.phase = 0;
    if (pairing.offset == ivec2(0)) {
        return false;
    }
    int stride = abs(pairing.offset[pairing.axis]);
    precise float phase = stream_next_f32(rng) * float(stride);
    pairing.phase = min(int(phase), stride - 1);
    return true;
}

// i32::div_euclid(a, b) for b > 0: the floor of a / b (GLSL's / truncates towards zero).
int reciprocal_div_floor(int a, int b) {
    return a >= 0 ? a / b : -((-a - 1) / b) - 1;
}

// Pairing::partner: p + offset where the stripe floor((p[axis] + phase) / |offset[axis]|) is
// even, p - offset where it is odd (two's complement: the low bit is the parity).
ivec2 pairing_partner(Pairing pairing, ivec2 p) {
    int stripe = reciprocal_div_floor(p[pairing.axis] + pairing.phase,
                                      abs(pairing.offset[pairing.axis]));
    return (stripe & 1) == 0 ? p + pairing.offset : p - pairing.offset;
}

#endif
