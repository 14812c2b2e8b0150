#version 460
// Function-level parity kernel of the reuse GLSL (engine/tests/vulkan_reuse.rs): mode 0
// evaluates MIS weights (restir/glsl/mis.glsl), mode 1 streams candidates through a reservoir
// (restir/glsl/reservoir.glsl), mode 2 shifts a pixel's reservoir sample into another pixel
// (shifts/glsl/shift.glsl), mode 3 computes a reciprocal pass's frame radius per case (its
// pass; engine/glsl/include/frame_radius.glsl), mode 4 what a pixel sends its partner of one
// slot of a reciprocal pass (engine/glsl/include/exchange.glsl). Bindings: 0-8 the scene, 9
// GPixel (modes 2-4), 10 PixelReservoir (modes 2 and 4), 11 the cases, 12 the results.
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#define SCENE_BINDING 0
#include "scene.glsl"
#include "mis.glsl"
#include "reservoir.glsl"
#include "shift.glsl"

layout(local_size_x = 64) in;

// Mode 0: one MIS weight m_i(y) and whether the scheme reads every target.
struct MisCase {
    float targets[16];
    float confidences[16];
    uint n;
    uint kind;
    uint i;
    uint pad;
};

// Mode 1: up to 8 candidates; `skip` bit j streams candidate j through Ris::skip.
struct RisCase {
    float target[8];
    float weight[8];
    float confidence[8];
    float u[8];
    uint count;
    uint skip;
    uint pad0;
    uint pad1;
};

// Mode 2: shift kind `kind` of the sample of pixel `src` into pixel `dst` (frame_params.frame,
// pass `pass`).
struct ShiftCase {
    uint src;
    uint dst;
    uint kind;
    uint pass;
};

// Shift::shift's result (fail = 0: y and jacobian) and p̂_dst(y); fail = 255 when a pixel has
// no domain.
struct ShiftResult {
    SssSample y;
    float jacobian;
    uint fail;
    float target;
    uint pad;
};

struct RisResult {
    PixelReservoir reservoir;
    uint error;
    uint selected;
    uint pad0;
    uint pad1;
};

layout(std430, binding = 11) readonly buffer MisCases { MisCase mis_cases[]; };
layout(std430, binding = 11) readonly buffer RisCases { RisCase ris_cases[]; };
layout(std430, binding = 12) writeonly buffer MisResults { vec2 mis_results[]; };
layout(std430, binding = 12) writeonly buffer RisResults { RisResult ris_results[]; };
layout(std430, binding = 9) readonly buffer Pixels { GPixel gpixels[]; };
layout(std430, binding = 10) readonly buffer Reservoirs { PixelReservoir reservoirs[]; };
layout(std430, binding = 11) readonly buffer ShiftCases { ShiftCase shift_cases[]; };
layout(std430, binding = 12) writeonly buffer ShiftResults { ShiftResult shift_results[]; };

layout(std430, binding = 11) readonly buffer RadiusCases { uint radius_passes[]; };
layout(std430, binding = 12) writeonly buffer RadiusResults { float radius_results[]; };

#include "include/frame_radius.glsl"
#include "include/reciprocal.glsl"
#include "include/exchange.glsl"

// Mode 4: slot `slot` of pass `pass` (pairings in the disk of `radius`) at pixel `pixel`, with
// shift kind `kind`.
struct ExchangeCase {
    uint pixel;
    uint slot;
    uint pass;
    uint kind;
    float radius;
    uint pad0;
    uint pad1;
    uint pad2;
};

// exchange_send's status and values; status = 255 when the pixel has no domain.
struct ExchangeResult {
    Sent sent;
    uint status;
    uint pad0;
    uint pad1;
    uint pad2;
};

layout(std430, binding = 11) readonly buffer ExchangeCases { ExchangeCase exchange_cases[]; };
layout(std430, binding = 12) writeonly buffer ExchangeResults { ExchangeResult exchange_results[]; };

layout(push_constant) uniform Params {
    uint mode;
    uint count;
    uint pad0;
    uint pad1;
} params;

void main() {
    uint c = gl_GlobalInvocationID.x;
    if (c >= params.count) {
        return;
    }
    if (params.mode == 0u) {
        MisCase m = mis_cases[c];
        float w = mis_weight(m.kind, m.i, m.targets, m.confidences, m.n);
        mis_results[c] = vec2(w, mis_needs_all_targets(m.kind, m.i) ? 1.0 : 0.0);
        return;
    }
    if (params.mode == 3u) {
        radius_results[c] = reciprocal_frame_radius(radius_passes[c]);
        return;
    }
    if (params.mode == 4u) {
        ExchangeCase ec = exchange_cases[c];
        ExchangeResult r;
        r.status = 255u;
        r.sent.y = reservoir_empty().y;
        r.sent.jacobian = 0.0;
        r.sent.target = 0.0;
        r.sent.source_target = 0.0;
        r.pad0 = 0u;
        r.pad1 = 0u;
        r.pad2 = 0u;
        uint64_t seed = scene_seed();
        uint frame = frame_params.frame;
        GPixel g = gpixels[ec.pixel];
        SssDomain source;
        if (domain_new(g, ec.pixel, frame, ec.pass, seed, source)) {
            Pairing pairing;
            bool paired = pairing_draw(ec.radius, ec.slot, frame, ec.pass, seed, pairing);
            r.status = exchange_send(source, g.object, reservoirs[ec.pixel], paired, pairing,
                                     ec.kind, r.sent);
        }
        exchange_results[c] = r;
        return;
    }
    if (params.mode == 2u) {
        ShiftCase sc = shift_cases[c];
        ShiftResult r;
        r.y = reservoir_empty().y;
        r.jacobian = 0.0;
        r.fail = 255u;
        r.target = 0.0;
        r.pad = 0u;
        SssDomain src;
        SssDomain dst;
        uint frame = frame_params.frame;
        uint64_t seed = scene_seed();
        if (domain_new(gpixels[sc.src], sc.src, frame, sc.pass, seed, src)
            && domain_new(gpixels[sc.dst], sc.dst, frame, sc.pass, seed, dst)) {
            ShiftSpec spec = shift_spec(sc.kind, dst.material);
            SssSample x = reservoirs[sc.src].y;
            r.fail = shift_shift(spec, x, src, dst, r.y, r.jacobian);
            if (r.fail == SHIFT_OK) {
                r.target = domain_target(dst, r.y);
            } else {
                r.y = reservoir_empty().y;
                r.jacobian = 0.0;
            }
        }
        shift_results[c] = r;
        return;
    }
    RisCase rc = ris_cases[c];
    Ris ris = ris_new();
    uint error = 0u;
    for (uint j = 0u; j < rc.count && error == 0u; j++) {
        SssSample y = reservoir_empty().y;
        y.prim = j;
        if ((rc.skip & (1u << j)) != 0u) {
            error = ris_skip(ris, rc.confidence[j]);
        } else {
            error = ris_update(ris, y, rc.target[j], rc.weight[j], rc.confidence[j], rc.u[j]);
        }
    }
    RisResult r;
    r.reservoir = ris_finish(ris);
    r.error = error;
    r.selected = r.reservoir.y.prim;
    r.pad0 = 0u;
    r.pad1 = 0u;
    ris_results[c] = r;
}
