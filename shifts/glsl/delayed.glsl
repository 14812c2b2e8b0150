// Delayed reconnection [001 §3.2.2]: random replay of the stored BSSRDF IS draw at y1, then
// reconnection to the kept x3: the twin of shifts/src/delayed.rs. Included by shift.glsl
// (include that file, not this one).

#ifndef SHIFTS_DELAYED_GLSL
#define SHIFTS_DELAYED_GLSL

// Checks: which parts of delayed reconnection run, the bits DELAYED_CHECK_* of
// contract/shifts.glsl; only the negative controls of broken.glsl switch one off.

// light_jacobian: |cos θ_y / cos θ_x| ‖x3 − x2‖² / ‖x3 − y2‖² [001 Eq. 11]; 1 for delta lights,
// 0 for an unknown light.
float delayed_light_jacobian(uint light, vec3 x3, vec3 x2, vec3 y2) {
    if (light >= LIGHT_COUNT) {
        return 0.0;
    }
    uint kind = scene_lights[light].kind;
    vec3 normal;
    if (kind == LIGHT_QUAD || kind == LIGHT_TRIANGLE) {
        normal = glam_normalize_or_zero(light_face_normal(light));
    } else if (kind == LIGHT_SPHERE) {
        precise vec3 outward = x3 - light_p0(light);
        normal = glam_normalize_or_zero(outward);
    } else {
        return 1.0;
    }
    precise vec3 to_x = x2 - x3;
    precise vec3 to_y = y2 - x3;
    float dx2 = glam_length_squared(to_x);
    float dy2 = glam_length_squared(to_y);
    precise float num = abs(glam_dot(normal, to_y)) * dx2 * sqrt(dx2);
    precise float den = abs(glam_dot(normal, to_x)) * dy2 * sqrt(dy2);
    precise float ratio = num / den;
    return den > 0.0 ? ratio : 0.0;
}

// replay: delayed reconnection of `x` from `src` into `dst` with `checks`; also returns y2.
// The uniform hit pick of an unknown index draws from the receiver's PURPOSE_PICK stream.
uint delayed_replay(SssSample x, SssDomain src, SssDomain dst, uint checks, out SssSample y,
                    out float jacobian, out EntryPoint y2) {
    y = x;
    jacobian = 1.0;
    y2 = EntryPoint(0u, 0u, vec2(0.0), vec3(0.0), vec3(0.0), vec3(0.0));
    if (src.x1.object != dst.x1.object) {
        return SHIFT_FAIL_REJECTED;
    }
    if (x.technique >= BSSRDF_TECHNIQUE_COUNT) {
        return SHIFT_FAIL_DEGENERATE;
    }
    EntryPoint x2;
    if (!domain_entry_point(src, x, x2)) {
        return SHIFT_FAIL_REJECTED;
    }
    Probe probe = Probe(x.technique, x.u_radius, x.u_angle);
    bssrdf_probe_trace(probe, dst.x1);
    float u_pick = 0.0;
    if (x.index == BSSRDF_INDEX_UNKNOWN) {
        Stream pick = domain_shift_stream(dst, PURPOSE_PICK, src);
        u_pick = stream_next_f32(pick);
    }
    uint rank;
    BvhHit hit;
    if (!bssrdf_pick_hit(x.index, u_pick, rank, hit)) {
        return SHIFT_FAIL_OUT_OF_SUPPORT;
    }
    y2 = bssrdf_entry_point_from_hit(hit);
    float p_disk_y = domain_p_disk(dst, y2);
    if (!(p_disk_y > 0.0 && !isinf(p_disk_y))) {
        return SHIFT_FAIL_DEGENERATE;
    }
    y = shift_with_bssrdf(x, bssrdf_sample_new(probe, rank, y2, p_disk_y));
    if ((checks & DELAYED_CHECK_JACOBIAN) != 0u) {
        float light = delayed_light_jacobian(y.light, sample_x3(y), x2.position, y2.position);
        // [001 Eq. 11]
        precise float j = x.p_disk / p_disk_y * light;
        jacobian = j;
    }
    if (!(jacobian > 0.0 && !isinf(jacobian))) {
        return SHIFT_FAIL_DEGENERATE;
    }
    if ((checks & DELAYED_CHECK_VISIBILITY) != 0u && !domain_visible(dst, y)) {
        return SHIFT_FAIL_OCCLUDED;
    }
    return SHIFT_OK;
}

// DelayedReconnection::shift: the replay with every check (run by shift_shift).
void delayed_shift(ShiftSpec spec, SssSample x, SssDomain src, SssDomain dst,
                   inout ShiftPlan plan) {
    plan.replay = DELAYED_CHECKS_ALL;
}

#endif
