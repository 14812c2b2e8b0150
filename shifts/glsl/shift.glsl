// Shift mappings on SSS paths: the GLSL twins of restir::shift::{Fail, Shift} and of every
// shift of the `shifts` crate (shifts/src/*.rs), dispatched on the index of
// engine::preset::ShiftKind::ALL (DESIGN §5, §9).
//
// A shift is `uint f(..., out SssSample y, out float jacobian)`: SHIFT_OK with `y = T(x)` and
// `J = |T'(x)|`, or the Fail code. Include after `#define SCENE_BINDING ...`; the including
// shader enables GL_EXT_shader_explicit_arithmetic_types_int64. The twins live in
// reconnection.glsl, delayed.glsl, hybrid.glsl, inversion.glsl and broken.glsl, which this file
// includes in dependency order (include shift.glsl, not them).

#ifndef SHIFTS_SHIFT_GLSL
#define SHIFTS_SHIFT_GLSL

#include "domain.glsl"

// restir::shift::Fail (0 = the shift succeeded).
const uint SHIFT_OK = 0u;
const uint SHIFT_FAIL_NOT_INVERTIBLE = 1u;
const uint SHIFT_FAIL_OUT_OF_SUPPORT = 2u;
const uint SHIFT_FAIL_OCCLUDED = 3u;
const uint SHIFT_FAIL_DEGENERATE = 4u;
const uint SHIFT_FAIL_REJECTED = 5u;

// engine::preset::ShiftKind::ALL, in order.
const uint SHIFT_IDENTITY = 0u;
const uint SHIFT_RECONNECTION = 1u;
const uint SHIFT_DELAYED = 2u;
const uint SHIFT_HYBRID = 3u;
const uint SHIFT_INVERTING_EXACT = 4u;
const uint SHIFT_INVERTING_DEFERRED = 5u;
const uint SHIFT_DELAYED_WITHOUT_JACOBIAN = 6u;
const uint SHIFT_DELAYED_WITHOUT_VISIBILITY = 7u;
const uint SHIFT_HYBRID_IGNORING_CRITERION = 8u;
const uint SHIFT_KIND_COUNT = 9u;

// SssSample::with_bssrdf: the same light vertex with a new BSSRDF part (padding zeroed, as
// SssSample::new writes it).
SssSample shift_with_bssrdf(SssSample s, BssrdfSample b) {
    SssSample y = s;
    y.bary = float[2](b.bary.x, b.bary.y);
    y.object = b.object;
    y.prim = b.prim;
    y.technique = b.technique;
    y.u_radius = b.u_radius;
    y.u_angle = b.u_angle;
    y.index = b.index;
    y.p_disk = b.p_disk;
    y.padding = uint[3](0u, 0u, 0u);
    return y;
}

#include "reconnection.glsl"
#include "delayed.glsl"
#include "hybrid.glsl"
#include "inversion.glsl"
#include "broken.glsl"

// A ShiftKind built for a receiver (ShiftKind::with_shift): the hybrid's thresholds come from
// the receiver's material.
struct ShiftSpec {
    uint kind;
    Hybrid hybrid;
};

// ShiftKind::with_shift(material).
ShiftSpec shift_spec(uint kind, GpuMaterial receiver_material) {
    return ShiftSpec(kind, hybrid_for_material(receiver_material));
}

// ShiftKind::resolves_deferred_index.
bool shift_resolves_deferred_index(uint kind) {
    return kind == SHIFT_INVERTING_DEFERRED;
}

// Shift::shift of kind `spec.kind` from `src` into `dst`; SHIFT_FAIL_REJECTED for an unknown
// kind (the host validates kinds before dispatching). Mesa inlines every call, so each call
// site of a ray-tracing function multiplies the shader's size (and its compile time on
// lavapipe): every replaying kind (delayed, hybrid, the three negative controls) goes through
// the single delayed_replay call below with the kind's parameters.
uint shift_shift(ShiftSpec spec, SssSample x, SssDomain src, SssDomain dst, out SssSample y,
                 out float jacobian) {
    y = x;
    jacobian = 1.0;
    uint kind = spec.kind;
    if (kind == SHIFT_IDENTITY) {
        return SHIFT_OK;
    }
    if (kind == SHIFT_RECONNECTION) {
        return reconnection_shift(x, dst, y, jacobian);
    }
    if (kind == SHIFT_INVERTING_EXACT || kind == SHIFT_INVERTING_DEFERRED) {
        uint policy = kind == SHIFT_INVERTING_EXACT ? INDEX_POLICY_EXACT : INDEX_POLICY_DEFERRED;
        return inversion_shift(policy, x, src, dst, y, jacobian);
    }
    if (kind >= SHIFT_KIND_COUNT) {
        return SHIFT_FAIL_REJECTED;
    }
    bool hybrid = kind == SHIFT_HYBRID || kind == SHIFT_HYBRID_IGNORING_CRITERION;
    bool respect_offset = kind == SHIFT_HYBRID;
    Hybrid thresholds = kind == SHIFT_HYBRID
        ? spec.hybrid
        : broken_hybrid_ignoring_criterion_thresholds(src);
    if (hybrid) {
        bool replay;
        uint fail = hybrid_reconnection_branch(thresholds, x, src, dst, respect_offset, replay, y);
        if (fail != SHIFT_OK || !replay) {
            return fail;
        }
    }
    EntryPoint y2;
    uint fail = delayed_replay(x, src, dst, broken_delayed_checks(kind), y, jacobian, y2);
    if (fail != SHIFT_OK) {
        return fail;
    }
    if (hybrid && hybrid_offset_rejects(thresholds, dst, y2, respect_offset)) {
        return SHIFT_FAIL_REJECTED;
    }
    return SHIFT_OK;
}

// Shift::target_from given the back-shift's result T_{r->j}(y) (fail code, sample, Jacobian):
// p̂_{<-j}(y) = p̂_j(T_{r->j}(y)) |T'_{r->j}(y)|, 0 when the back-shift failed (DESIGN §9,
// [001 Eq. 7]). The caller runs the shift itself, so that a shader has one shift_shift call site.
float shift_target_from(uint fail, SssDomain other, SssSample back, float jacobian) {
    if (fail != SHIFT_OK) {
        return 0.0;
    }
    precise float t = domain_target(other, back) * jacobian;
    return t;
}

#endif
