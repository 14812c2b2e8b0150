// The shift registry: one line per shift, read twice: by `kind.rs` (the Rust `ShiftKind`: name,
// CPU shift for a receiver of material `m`, GPU code = position here) and by `engine/build.rs`
// (the GLSL constants `SHIFT_<KIND>` and the dispatch list of `shifts/glsl/shift.glsl`).
// Adding a shift: its Rust file, its GLSL twin, and one line here (docs/adding-a-shift.md).
//
// Kind = "name", glsl_file::glsl_twin, |m| cpu_shift(m) [, resolves_deferred_index];
// What a shift does with a sample's stored BSSRDF random numbers is declared by its type
// (`numbers::DeclaresNumbers`), next to the code that does it, not here.

shift_registry! {
    /// `T(x) = x`, `J = 1`: a domain onto itself (canonical samples).
    Identity = "identity", reconnection::reconnection_identity_shift, |_| Identity;
    /// Reconnection `[y0, y1, x2, x3]`, `J = 1` [001 §3.2.1].
    Reconnection = "reconnection", reconnection::reconnection_shift, |_| Reconnection;
    /// Delayed reconnection: replay the BSSRDF IS draw at y1, keep x3 [001 §3.2.2, Eq. 11].
    DelayedReconnection = "delayed", delayed::delayed_shift, |_| DelayedReconnection;
    /// Hybrid shift [001 §4.1], κ_dist = 2·max d of the receiver's material, κ_orient = 0.5.
    Hybrid = "hybrid", hybrid::hybrid_shift, Hybrid::for_material;
    /// Reconnection + probabilistic inversion [001 Alg. 4], index re-traced during the shift.
    InvertingExact = "inverting-reconnection-exact", inversion::inversion_exact_shift, |_| InvertingReconnection { policy: IndexPolicy::Exact };
    /// Reconnection + probabilistic inversion, index resolved for the selected sample only.
    InvertingDeferred = "inverting-reconnection-deferred", inversion::inversion_deferred_shift, |_| InvertingReconnection { policy: IndexPolicy::Deferred }, resolves_deferred_index;
    /// Reconnection where x2 lies at least 2·max d from both exit points (the worked example).
    DistantReconnection = "distant-reconnection", distant::distant_shift, DistantReconnection::for_material;
    /// Negative control: delayed reconnection with `J = 1`.
    DelayedWithoutJacobian = "broken:delayed-without-jacobian", broken::broken_delayed_without_jacobian_shift, |_| broken::DelayedWithoutJacobian;
    /// Negative control: delayed reconnection without the y2↔x3 visibility test.
    DelayedWithoutVisibility = "broken:delayed-without-visibility", broken::broken_delayed_without_visibility_shift, |_| broken::DelayedWithoutVisibility;
    /// Negative control: a hybrid whose offset path ignores the criterion.
    HybridIgnoringCriterion = "broken:hybrid-ignoring-criterion", broken::broken_hybrid_ignoring_criterion_shift, |_| broken::HybridIgnoringCriterion;
    /// Negative control near δ, never for rendering: delayed reconnection with `J · 1.03`.
    DelayedJacobianOff = "broken:delayed-jacobian-3pct-high", broken::broken_delayed_jacobian_off_shift, |_| broken::DelayedJacobianOff;
}
