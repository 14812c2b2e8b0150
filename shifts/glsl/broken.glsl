// Negative controls: deliberately wrong shifts that the conformance and parity tests must
// detect; the twin of shifts/src/broken.rs, as the parameters by which each deviates from its
// correct shift (the dispatcher of shift.glsl runs them). Never render with one. Part of
// shift.glsl (include that file, not this one).

#ifndef SHIFTS_BROKEN_GLSL
#define SHIFTS_BROKEN_GLSL

// The checks delayed_replay runs for a replaying kind: DelayedWithoutJacobian drops the
// Jacobian of [001 Eq. 11] (J = 1), DelayedWithoutVisibility the y2-x3 visibility test.
uint broken_delayed_checks(uint kind) {
    if (kind == SHIFT_DELAYED_WITHOUT_JACOBIAN) {
        return DELAYED_CHECK_VISIBILITY;
    }
    if (kind == SHIFT_DELAYED_WITHOUT_VISIBILITY) {
        return DELAYED_CHECK_JACOBIAN;
    }
    return DELAYED_CHECKS_ALL;
}

// HybridIgnoringCriterion: the source's thresholds, and no test on the offset path (not a
// bijection).
Hybrid broken_hybrid_ignoring_criterion_thresholds(SssDomain src) {
    return hybrid_for_material(src.material);
}

#endif
