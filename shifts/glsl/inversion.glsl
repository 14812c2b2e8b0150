// Reconnection followed by probabilistic inversion [001 §4.2, Alg. 4]: the twin of
// shifts/src/inversion.rs. Part of shift.glsl (include that file, not this one).

#ifndef SHIFTS_INVERSION_GLSL
#define SHIFTS_INVERSION_GLSL

// invert_at: probabilistic inversion of x2 at `end`'s x1 with gamma_end, the first number of
// end's PURPOSE_INVERSION stream keyed by `partner` [001 Alg. 4]; with `find`, x2's rank among
// the re-traced chord's hits (NotInvertible when x2 is not among them, index BSSRDF_INDEX_UNKNOWN
// without `find`).
uint inversion_invert_at(SssDomain end, SssDomain partner, EntryPoint x2, bool find,
                         out Probe probe, out float p_disk, out uint index) {
    index = BSSRDF_INDEX_UNKNOWN;
    Stream stream = domain_shift_stream(end, PURPOSE_INVERSION, partner);
    float gamma = stream_next_f32(stream);
    if (bssrdf_invert_random_numbers(end.x1, end.selection, x2, gamma, probe, p_disk)
        != BSSRDF_INVERT_OK) {
        return SHIFT_FAIL_OUT_OF_SUPPORT;
    }
    if (find && !bssrdf_find_index(end.x1, probe, x2, index)) {
        return SHIFT_FAIL_NOT_INVERTIBLE;
    }
    return SHIFT_OK;
}

// InvertingReconnection::shift: reconnection (J = 1), then x2 inverted at the receiver; the
// exact policy re-traces the chord for the index there and also inverts and re-traces at the
// source with the source's gamma, the back-shift's own inversion (NotInvertible if x2 is not
// found at either end). Mesa inlines every call, so the two ends share one call site: a loop
// over (dst, src), then (src, dst), the Rust code's order.
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
    bool exact = policy == INDEX_POLICY_EXACT;
    Probe probe;
    float p_disk;
    uint index;
    for (uint end = 0u; end < (exact ? 2u : 1u); end++) {
        SssDomain at = dst;
        SssDomain partner = src;
        if (end == 1u) {
            at = src;
            partner = dst;
        }
        Probe end_probe;
        float end_p_disk;
        uint end_index;
        fail = inversion_invert_at(at, partner, x2, exact, end_probe, end_p_disk, end_index);
        if (fail != SHIFT_OK) {
            return fail;
        }
        if (end == 0u) {
            probe = end_probe;
            p_disk = end_p_disk;
            index = end_index;
        }
    }
    y = shift_with_bssrdf(y, bssrdf_sample_new(probe, index, x2, p_disk));
    return SHIFT_OK;
}

// resolve_deferred_index: for the sample selected after a pass, re-trace its chord at
// `domain`'s x1 and store x2's rank (unknown if x2 is not found); a known index is kept.
void inversion_resolve_deferred_index(SssDomain domain, inout SssSample y) {
    if (y.index != BSSRDF_INDEX_UNKNOWN || y.technique >= BSSRDF_TECHNIQUE_COUNT) {
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
