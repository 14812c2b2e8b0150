// The stored sample and reservoir of the SSS pipeline: the twin of shifts/src/sample.rs. The
// structs SssSample and PixelReservoir come from the contract (shifts/src/contract.rs), in std430
// with arrays of float where Rust has arrays of f32 (a vec3 would align to 16), and
// BSSRDF_INDEX_UNKNOWN from sss/src/contract.rs.

#ifndef SHIFTS_SAMPLE_GLSL
#define SHIFTS_SAMPLE_GLSL

#include "contract/sss.glsl"
#include "contract/shifts.glsl"

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
    r.ucw = 0.0;
    r.confidence = 0.0;
    r.has_sample = 0u;
    return r;
}

#endif
