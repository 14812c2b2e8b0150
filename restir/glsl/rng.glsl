// Stream random numbers: the GLSL twin of restir/src/rng.rs (read the two side by side).
//
// Key -> seed: splitmix64 over the packed key words and the run seed; generator: PCG32
// (XSH-RR output on a 64-bit LCG, as rand_pcg::Pcg32). Integer-only, so the GPU sequence is the
// CPU's bit for bit. The including shader enables
// GL_EXT_shader_explicit_arithmetic_types_int64 (device feature shaderInt64).

#ifndef RESTIR_RNG_GLSL
#define RESTIR_RNG_GLSL

// One independent random stream: a pixel at a frame, inside a pass, for one purpose.
struct StreamKey {
    uint pixel;
    uint frame;
    uint pass;
    uint purpose;
};

// A keyed PCG32 stream: LCG state and odd increment (2 * stream + 1).
struct Stream {
    uint64_t state;
    uint64_t increment;
};

const uint64_t PCG32_MULTIPLIER = 6364136223846793005UL;

// One step of splitmix64 used as a 64-bit finaliser (Steele, Lea & Flood 2014).
uint64_t splitmix64(uint64_t x) {
    uint64_t z = x + 0x9E3779B97F4A7C15UL;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9UL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBUL;
    return z ^ (z >> 31);
}

// The generator for `key` under the run seed `seed` (StreamKey::seed_pair, then Pcg32::new).
Stream stream_new(StreamKey key, uint64_t seed) {
    uint64_t k0 = (uint64_t(key.pixel) << 32) | uint64_t(key.frame);
    uint64_t k1 = (uint64_t(key.pass) << 32) | uint64_t(key.purpose);
    uint64_t state = splitmix64(seed ^ splitmix64(k0 ^ splitmix64(k1)));
    uint64_t stream = splitmix64(state ^ 0xD1B54A32D192ED03UL);
    Stream s;
    s.increment = (stream << 1) | 1UL;
    s.state = (state + s.increment) * PCG32_MULTIPLIER + s.increment;
    return s;
}

// The next 32 random bits: XSH-RR of the current state, then one LCG step.
uint stream_next_u32(inout Stream s) {
    uint64_t old = s.state;
    s.state = old * PCG32_MULTIPLIER + s.increment;
    uint xorshifted = uint(((old >> 18) ^ old) >> 27);
    uint rot = uint(old >> 59);
    return (xorshifted >> rot) | (xorshifted << ((32u - rot) & 31u));
}

// `(u >> 8) * 2^-24`: 24 random bits, exactly representable, in [0, 1).
float u32_to_unit_f32(uint u) {
    return float(u >> 8) * (1.0 / 16777216.0);
}

// A uniform float in [0, 1); 1.0 is never returned.
float stream_next_f32(inout Stream s) {
    return u32_to_unit_f32(stream_next_u32(s));
}

#endif
