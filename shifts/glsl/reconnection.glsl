// The identity shift and reconnection [y0, y1, x2, x3] [001 §3.2.1]: the twin of
// shifts/src/reconnection.rs. Included by shift.glsl (include that file, not this one).

#ifndef SHIFTS_RECONNECTION_GLSL
#define SHIFTS_RECONNECTION_GLSL

// reconnect: the support checks of reconnection into `dst`: x2 on y1's object (Rejected), within
// r_max of the widest channel and with p̂_dst > 0 (OutOfSupport). `y = x` on success.
uint reconnection_reconnect(SssSample x, SssDomain dst, out SssSample y) {
    y = x;
    EntryPoint x2;
    if (!domain_entry_point(dst, x, x2)) {
        return SHIFT_FAIL_REJECTED;
    }
    precise vec3 d = x2.position - dst.x1.position;
    float r = glam_length(d);
    if (isnan(r) || r > material_r_max_all(dst.material) || domain_target(dst, x) <= 0.0) {
        return SHIFT_FAIL_OUT_OF_SUPPORT;
    }
    return SHIFT_OK;
}

// Identity::shift: y = x, J = 1, never fails.
void reconnection_identity_shift(ShiftSpec spec, SssSample x, SssDomain src, SssDomain dst,
                                 inout ShiftPlan plan) {
}

// Reconnection::shift: keeps x2 and x3, J = 1.
void reconnection_shift(ShiftSpec spec, SssSample x, SssDomain src, SssDomain dst,
                        inout ShiftPlan plan) {
    plan.fail = reconnection_reconnect(x, dst, plan.y);
}

#endif
