//! `p_disk`: the one-sample MIS density of BSSRDF IS over the nine techniques, in surface area
//! measure at x2 (DESIGN §9 "BSSRDF IS PDF").

use glam::Vec3;

use super::probe::ExitPoint;
use super::technique::{RadiusSampling, Technique, TechniqueSelection};

/// The per-technique terms `P(a) P(c) p_{d_c}(r_a) |n2·axis_a| 1[‖x2 − x1‖ ≤ r_max,c]`, in
/// [`Technique::index`] order. Their sum is `p_disk`, their ratios the posterior over techniques
/// that probabilistic inversion samples [001 Alg. 4, line 1].
pub fn technique_terms(
    x1: &ExitPoint,
    selection: &TechniqueSelection,
    x2: Vec3,
    n2: Vec3,
) -> [f32; Technique::COUNT] {
    technique_terms_with(x1, selection, RadiusSampling::Exact, x2, n2)
}

/// [`technique_terms`] for techniques whose radii come from `radius`: `p_{d_c}` is then the
/// density of that sampler.
pub fn technique_terms_with(
    x1: &ExitPoint,
    selection: &TechniqueSelection,
    radius: RadiusSampling,
    x2: Vec3,
    n2: Vec3,
) -> [f32; Technique::COUNT] {
    let distance2 = (x2 - x1.position).length_squared();
    Technique::ALL.map(|t| {
        let p = selection.probability(t);
        let r_max = x1.r_max[t.channel];
        if p <= 0.0 || distance2 > r_max * r_max {
            return 0.0;
        }
        let r_a = x1.disk_coordinates(t.axis, x2).length();
        let axis = x1.disk_basis(t.axis)[2];
        p * radius.pdf_disk(&x1.profiles[t.channel], r_a) * n2.dot(axis).abs()
    })
}

/// `p_disk(x2 | x1) = Σ_a Σ_c P(a) P(c) p_{d_c}(r_a) |n2·axis_a| 1[‖x2 − x1‖ ≤ r_max,c]`, with `n2`
/// the geometric normal at x2 (DESIGN §9). Zero where no technique reaches x2.
pub fn p_disk(x1: &ExitPoint, selection: &TechniqueSelection, x2: Vec3, n2: Vec3) -> f32 {
    technique_terms(x1, selection, x2, n2).iter().sum()
}

/// [`p_disk`] for techniques whose radii come from `radius`.
pub fn p_disk_with(
    x1: &ExitPoint,
    selection: &TechniqueSelection,
    radius: RadiusSampling,
    x2: Vec3,
    n2: Vec3,
) -> f32 {
    technique_terms_with(x1, selection, radius, x2, n2)
        .iter()
        .sum()
}
