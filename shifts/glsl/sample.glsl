// The stored sample and reservoir of the SSS pipeline: std430 twins of shifts::SssSample
// (shifts/src/sample.rs, 64 bytes) and engine::layout::PixelReservoir (80 bytes). Arrays of
// float keep the std430 layout identical to the Rust #[repr(C)] structs (a vec3 would align to 16).

#ifndef SHIFTS_SAMPLE_GLSL
#define SHIFTS_SAMPLE_GLSL

// SssSample::index when the intersection index is deferred (shifts::INDEX_UNKNOWN).
const uint INDEX_UNKNOWN = 0xFFFFFFFFu;

struct SssSample {
    float x3[3];
    uint light;
    float bary[2];
    uint object;
    uint prim;
    uint technique;
    float u_radius;
    float u_angle;
    uint index;
    float p_disk;
    uint padding[3];
};

struct PixelReservoir {
    SssSample y; // `sample` in Rust (a reserved word in GLSL)
    float ucw;
    float confidence;
    uint has_sample;
    uint padding;
};

vec3 sample_x3(SssSample s) {
    return vec3(s.x3[0], s.x3[1], s.x3[2]);
}

vec2 sample_bary(SssSample s) {
    return vec2(s.bary[0], s.bary[1]);
}

PixelReservoir reservoir_empty() {
    PixelReservoir r;
    r.y.x3 = float[3](0.0, 0.0, 0.0);
    r.y.light = 0u;
    r.y.bary = float[2](0.0, 0.0);
    r.y.object = 0u;
    r.y.prim = 0u;
    r.y.technique = 0u;
    r.y.u_radius = 0.0;
    r.y.u_angle = 0.0;
    r.y.index = 0u;
    r.y.p_disk = 0.0;
    r.y.padding = uint[3](0u, 0u, 0u);
    r.ucw = 0.0;
    r.confidence = 0.0;
    r.has_sample = 0u;
    r.padding = 0u;
    return r;
}

#endif
