// Reconnection with a distance threshold: the twin of shifts/src/distant.rs (the worked example
// of docs/adding-a-shift.md). Included through contract/shift_twins.glsl by shift.glsl.

#ifndef SHIFTS_DISTANT_GLSL
#define SHIFTS_DISTANT_GLSL

// DistantReconnection::for_material: 2 max d, uploaded as GpuMaterial::kappa_dist.
float distant_for_material(GpuMaterial material) {
    return material.kappa_dist;
}

// DistantReconnection::shift: Rejected unless x2 lies at least min_distance from both exit
// points, then reconnection (J = 1).
void distant_shift(ShiftSpec spec, SssSample x, SssDomain src, SssDomain dst,
                   inout ShiftPlan plan) {
    float min_distance = distant_for_material(spec.receiver);
    EntryPoint x2;
    if (!domain_entry_point(src, x, x2)) {
        plan.fail = SHIFT_FAIL_REJECTED;
        return;
    }
    bool far_src = glam_length(x2.position - src.x1.position) >= min_distance;
    bool far_dst = glam_length(x2.position - dst.x1.position) >= min_distance;
    if (!(far_src && far_dst)) {
        plan.fail = SHIFT_FAIL_REJECTED;
        return;
    }
    plan.fail = reconnection_reconnect(x, dst, plan.y);
}

#endif
