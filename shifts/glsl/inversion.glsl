// Reconnection followed by probabilistic inversion [001 §4.2, Alg. 4]: the twin of
// shifts/src/inversion.rs. Part of shift.glsl (include that file, not this one).

#ifndef SHIFTS_INVERSION_GLSL
#define SHIFTS_INVERSION_GLSL

// InvertingReconnection::shift: reconnection (J = 1), then the technique drawn from its
// posterior with γ, the first number of the receiver's PURPOSE_INVERSION stream, and inverted;
// the exact policy re-traces the chord for the index (NotInvertible if x2 is not found).
uint inversion_shift(uint policy, SssSample x, SssDomain src, SssDomain dst, out SssSample y,
                     out float jacobian) {
    jacobian = 1.0;
    uint fail = reconnection_reconnect(x, dst, y);
    if (fail != SHIFT_OK) {
        return fail;
    }
    EntryPoint x2;
    if (!domain_entry_point(dst, y, x2)) {
        return SHIFT_FAIL_REJECTED;
    }
    Stream stream = domain_shift_stream(dst, PURPOSE_INVERSION, src);
    float gamma = stream_next_f32(stream);
    Probe probe;
    float p_disk;
    if (bssrdf_invert_random_numbers(dst.x1, dst.selection, x2, gamma, probe, p_disk)
        != BSSRDF_INVERT_OK) {
        return SHIFT_FAIL_OUT_OF_SUPPORT;
    }
    uint index = INDEX_UNKNOWN;
    if (policy == INDEX_POLICY_EXACT && !bssrdf_find_index(dst.x1, probe, x2, index)) {
        return SHIFT_FAIL_NOT_INVERTIBLE;
    }
    y = shift_with_bssrdf(y, bssrdf_sample_new(probe, index, x2, p_disk));
    return SHIFT_OK;
}

// resolve_deferred_index: for the sample selected after a pass, re-trace its chord at
// `domain`'s x1 and store x2's rank (unknown if x2 is not found); a known index is kept.
void inversion_resolve_deferred_index(SssDomain domain, inout SssSample y) {
    if (y.index != INDEX_UNKNOWN || y.technique >= BSSRDF_TECHNIQUE_COUNT) {
        return;
    }
    EntryPoint x2;
    if (!domain_entry_point(domain, y, x2)) {
        return;
    }
    uint index;
    bssrdf_find_index(domain.x1, Probe(y.technique, y.u_radius, y.u_angle), x2, index);
    y.index = index;
}

// The registered InvertingReconnection kinds: inversion_shift with their policy (run by
// shift_shift).
void inversion_exact_shift(ShiftSpec spec, SssSample x, SssDomain src, SssDomain dst,
                           inout ShiftPlan plan) {
    plan.invert = true;
    plan.index_policy = INDEX_POLICY_EXACT;
}

void inversion_deferred_shift(ShiftSpec spec, SssSample x, SssDomain src, SssDomain dst,
                              inout ShiftPlan plan) {
    plan.invert = true;
    plan.index_policy = INDEX_POLICY_DEFERRED;
}

#endif
