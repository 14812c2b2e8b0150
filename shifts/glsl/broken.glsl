// Negative controls: deliberately wrong shifts that the conformance and parity tests must
// detect; the twin of shifts/src/broken.rs, as the plans by which each deviates from its correct
// shift. Never render with one. Included by shift.glsl (include that file, not this one).

#ifndef SHIFTS_BROKEN_GLSL
#define SHIFTS_BROKEN_GLSL

#include "hybrid.glsl"

// DelayedWithoutJacobian: the replay without the Jacobian of [001 Eq. 11] (J = 1).
void broken_delayed_without_jacobian_shift(ShiftSpec spec, SssSample x, SssDomain src,
                                           SssDomain dst, inout ShiftPlan plan) {
    plan.replay = DELAYED_CHECK_VISIBILITY;
}

// DelayedWithoutVisibility: the replay without the y2-x3 visibility test.
void broken_delayed_without_visibility_shift(ShiftSpec spec, SssSample x, SssDomain src,
                                             SssDomain dst, inout ShiftPlan plan) {
    plan.replay = DELAYED_CHECK_JACOBIAN;
}

// HybridIgnoringCriterion: the source's thresholds, and no test on the offset path (not a
// bijection).
void broken_hybrid_ignoring_criterion_shift(ShiftSpec spec, SssSample x, SssDomain src,
                                            SssDomain dst, inout ShiftPlan plan) {
    hybrid_plan(hybrid_for_material(src.material), false, x, src, dst, plan);
}

// DelayedJacobianOff: the replay with its Jacobian times BROKEN_JACOBIAN_ERROR (3% too large).
void broken_delayed_jacobian_off_shift(ShiftSpec spec, SssSample x, SssDomain src, SssDomain dst,
                                       inout ShiftPlan plan) {
    plan.replay = DELAYED_CHECKS_ALL;
    plan.jacobian_factor = BROKEN_JACOBIAN_ERROR;
}

#endif
