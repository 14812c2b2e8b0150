// Shift mappings on SSS paths: the GLSL twins of restir::shift::{Fail, Shift} and the dispatch
// over the registered shifts (shifts/src/registry.rs, DESIGN §5, §9).
//
// A shift's code is its ShiftKind::code, the constant SHIFT_<KIND> of the contract; the list
// SHIFT_KINDS(X) names every registered kind with its twin, and contract/shift_twins.glsl
// includes the twins' files. Include this file after `#define SCENE_BINDING ...`; the including
// shader enables GL_EXT_shader_explicit_arithmetic_types_int64.
//
// A twin is the function its registry line names (`<module>_..._shift` of
// shifts/glsl/<module>.glsl): `void f(ShiftSpec spec, SssSample x, SssDomain src, SssDomain dst,
// inout ShiftPlan plan)`. It runs the shift's own checks and fills the plan:
// SHIFT_OK or a Fail code (SHIFT_FAIL_*) in `plan.fail`, `y = T(x)` and `J = |T'(x)|` so far,
// and which of the shared steps that trace rays should follow (probabilistic inversion,
// delayed-reconnection replay). shift_shift runs those steps once for every kind: Mesa inlines
// every call, so each call site of a ray-tracing function multiplies the shader's size and its
// compile time on lavapipe. A registered kind without its twin does not compile.

#ifndef SHIFTS_SHIFT_GLSL
#define SHIFTS_SHIFT_GLSL

// SHIFT_OK and the Fail codes SHIFT_FAIL_*.
#include "contract/restir.glsl"
// The kinds SHIFT_<KIND> and their list SHIFT_KINDS(X).
#include "contract/shifts.glsl"
#include "domain.glsl"

// A ShiftKind built for a receiver (ShiftKind::with_shift): the kind and the receiver's
// material (the hybrid's thresholds come from it).
struct ShiftSpec {
    uint kind;
    GpuMaterial receiver;
};

// ShiftKind::with_shift(material).
ShiftSpec shift_spec(uint kind, GpuMaterial receiver_material) {
    return ShiftSpec(kind, receiver_material);
}

// What a shift's twin decided, and the shared steps that follow it in shift_shift.
struct ShiftPlan {
    // SHIFT_OK, or the Fail code of the shift's own checks (no step runs then).
    uint fail;
    // T(x) and |T'(x)| so far (x and 1 to start).
    SssSample y;
    float jacobian;
    // Reconnection with probabilistic inversion of x for dst [001 Alg. 4] (inversion_shift of
    // inversion.glsl) with `index_policy`, which replaces y and J.
    bool invert;
    uint index_policy;
    // 0, or the DELAYED_CHECK_* bits of a delayed-reconnection replay of x at dst
    // (delayed.glsl), which replaces y and J.
    uint replay;
    // After a replay: fail (Rejected) where the offset path y1-y2 is connectable by `hybrid`
    // (the hybrid's bijectivity rule, DESIGN §9).
    bool reject_connectable;
    Hybrid hybrid;
    // Negative controls only (broken.glsl): a factor on the final J, 1 for every correct shift.
    float jacobian_factor;
};

ShiftPlan shift_plan_new(SssSample x) {
    return ShiftPlan(SHIFT_OK, x, 1.0, false, INDEX_POLICY_EXACT, 0u, false, Hybrid(0.0, 0.0),
                     1.0);
}

// SssSample::with_bssrdf: the same light vertex with a new BSSRDF part.
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
    return y;
}

// The shared steps: reconnection's support checks, inverting reconnection, the replay.
#include "reconnection.glsl"
#include "inversion.glsl"
#include "delayed.glsl"
// The registered shifts' twins.
#include "contract/shift_twins.glsl"

// ShiftKind::resolves_deferred_index.
bool shift_resolves_deferred_index(uint kind) {
#define SHIFT_RESOLVES(KIND, twin, resolves) \
    if (kind == KIND) { \
        return resolves; \
    }
    SHIFT_KINDS(SHIFT_RESOLVES)
#undef SHIFT_RESOLVES
    return false;
}

// Shift::shift of kind `spec.kind` from `src` into `dst`: the kind's twin, then the steps it
// asked for. The host sends registered kinds only (PassParams::new takes a ShiftKind).
uint shift_shift(ShiftSpec spec, SssSample x, SssDomain src, SssDomain dst, out SssSample y,
                 out float jacobian) {
    ShiftPlan plan = shift_plan_new(x);
    switch (spec.kind) {
#define SHIFT_TWIN(KIND, twin, resolves) \
    case KIND: \
        twin(spec, x, src, dst, plan); \
        break;
        SHIFT_KINDS(SHIFT_TWIN)
#undef SHIFT_TWIN
    default:
        // Not a registered kind: no shift (never one of them by default).
        plan.fail = SHIFT_FAIL_REJECTED;
    }
    if (plan.fail == SHIFT_OK && plan.invert) {
        plan.fail = inversion_shift(plan.index_policy, x, src, dst, plan.y, plan.jacobian);
    }
    if (plan.fail == SHIFT_OK && plan.replay != 0u) {
        EntryPoint y2;
        plan.fail = delayed_replay(x, src, dst, plan.replay, plan.y, plan.jacobian, y2);
        if (plan.fail == SHIFT_OK && plan.reject_connectable
            && hybrid_connectable(plan.hybrid, dst.x1, y2)) {
            plan.fail = SHIFT_FAIL_REJECTED;
        }
    }
    precise float scaled = plan.jacobian * plan.jacobian_factor;
    y = plan.y;
    jacobian = scaled;
    return plan.fail;
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
