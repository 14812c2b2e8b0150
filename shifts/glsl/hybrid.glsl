// The hybrid shift [001 §4.1]: reconnection or delayed reconnection by the criterion, tested on
// both the base and the offset path: the twin of shifts/src/hybrid.rs (Hybrid, for_material and
// connectable are in domain.glsl). Hybrid::shift_checked is split at its replay so that the
// dispatcher of shift.glsl runs a single delayed_replay call site for every replaying kind.
// Part of shift.glsl (include that file, not this one).

#ifndef SHIFTS_HYBRID_GLSL
#define SHIFTS_HYBRID_GLSL

// The first half of Hybrid::shift_checked: x2 on src's object (else Rejected); a connectable
// base path is reconnected (and, when `respect_offset`, Rejected unless the offset path is
// connectable too). `replay` is set when the base path is not connectable: the caller then runs
// delayed_replay with every check and hybrid_offset_rejects on its y2.
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

// The second half: a replayed offset path must not be connectable (when `respect_offset`).
bool hybrid_offset_rejects(Hybrid hybrid, SssDomain dst, EntryPoint y2, bool respect_offset) {
    return respect_offset && hybrid_connectable(hybrid, dst.x1, y2);
}

#endif
