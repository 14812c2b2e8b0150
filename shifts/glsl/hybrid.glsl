// The hybrid shift [001 §4.1]: reconnection or delayed reconnection by the criterion, tested on
// both the base and the offset path: the twin of shifts/src/hybrid.rs (Hybrid, for_material and
// connectable are in domain.glsl). Hybrid::shift_checked is split at its replay, which
// shift_shift runs (one delayed_replay call site for every replaying kind). Included by
// shift.glsl (include that file, not this one).

#ifndef SHIFTS_HYBRID_GLSL
#define SHIFTS_HYBRID_GLSL

// The first half of Hybrid::shift_checked: x2 on src's object (else Rejected); a connectable
// base path is reconnected (and, when `respect_offset`, Rejected unless the offset path is
// connectable too). `replay` is set when the base path is not connectable: hybrid_plan then asks
// for the replay with every check and the test of its offset path.
uint hybrid_reconnection_branch(Hybrid hybrid, SssSample x, SssDomain src, SssDomain dst,
                                bool respect_offset, out bool replay, out SssSample y) {
    y = x;
    replay = false;
    EntryPoint x2;
    if (!domain_entry_point(src, x, x2)) {
        return SHIFT_FAIL_REJECTED;
    }
    if (!hybrid_connectable(hybrid, src.x1, x2)) {
        replay = true;
        return SHIFT_OK;
    }
    uint fail = reconnection_reconnect(x, dst, y);
    if (fail != SHIFT_OK) {
        return fail;
    }
    if (respect_offset && !hybrid_connectable(hybrid, dst.x1, x2)) {
        return SHIFT_FAIL_REJECTED;
    }
    return SHIFT_OK;
}

// Hybrid::shift_checked as a plan: the reconnection branch, or a replay with every check after
// which a connectable offset path is rejected (when `respect_offset`).
void hybrid_plan(Hybrid hybrid, bool respect_offset, SssSample x, SssDomain src, SssDomain dst,
                 inout ShiftPlan plan) {
    bool replay;
    plan.fail = hybrid_reconnection_branch(hybrid, x, src, dst, respect_offset, replay, plan.y);
    if (plan.fail == SHIFT_OK && replay) {
        plan.replay = DELAYED_CHECKS_ALL;
        plan.reject_connectable = respect_offset;
        plan.hybrid = hybrid;
    }
}

// Hybrid::shift with Hybrid::for_material of the receiver.
void hybrid_shift(ShiftSpec spec, SssSample x, SssDomain src, SssDomain dst,
                  inout ShiftPlan plan) {
    hybrid_plan(hybrid_for_material(spec.receiver), true, x, src, dst, plan);
}

#endif
