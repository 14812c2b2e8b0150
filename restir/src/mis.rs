//! Resampling MIS weights `m_i(y)` as plug-ins, separate from shifts (DESIGN §3, §9).
//!
//! Index 0 is always the receiver (canonical) domain, indices `1..=k` the neighbours.
//! `targets[j] = p̂_{←j}(y)` (with `targets[0] = p̂_r(y)`), `confidences[j] = c_j`.
//! A scheme says which targets it reads ([`MisScheme::needs_all_targets`]), so streaming schemes
//! stay O(k): the driver fills only `targets[0]` and `targets[i]` for them.

use std::fmt;

pub use crate::contract::{MAX_DOMAINS, MisKind};

/// What a scheme promises about the estimate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Bias {
    /// `Σ_j m_j(y) = 1` over the domains that can produce `y`, for any supports.
    Unbiased,
    /// Unbiased only when every shift is a bijection between the supports of all domains.
    BiasedUnlessSupportsAgree,
}

impl Bias {
    pub fn is_unbiased_when_supports_differ(self) -> bool {
        self == Bias::Unbiased
    }
}

impl fmt::Display for Bias {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Bias::Unbiased => f.write_str("unbiased"),
            Bias::BiasedUnlessSupportsAgree => f.write_str("biased unless supports agree"),
        }
    }
}

/// A resampling MIS scheme.
pub trait MisScheme: Sync {
    fn name(&self) -> &'static str;
    fn bias(&self) -> Bias;
    /// Whether `weight(i, ..)` reads every `targets[j]`, or only `targets[0]` and `targets[i]`.
    fn needs_all_targets(&self, i: usize) -> bool;
    /// `m_i(y)`; `targets.len() == confidences.len()` = number of domains. Finite, in [0, 1].
    fn weight(&self, i: usize, targets: &[f32], confidences: &[f32]) -> f32;
}

impl MisKind {
    /// The scheme itself.
    pub fn scheme(&self) -> &'static dyn MisScheme {
        match self {
            MisKind::Gbh => &Gbh,
            MisKind::Pairwise => &Pairwise,
            MisKind::DefensivePairwise => &DefensivePairwise,
            MisKind::ConfidenceOnly => &ConfidenceOnly,
        }
    }
}

/// `num / den`, 0 when `den` is not positive (all domains have `p̂_{←j}(y) = 0`).
#[inline]
fn ratio(num: f32, den: f32) -> f32 {
    if den > 0.0 { num / den } else { 0.0 }
}

/// Generalized balance heuristic with confidence weights [001 Eq. 8]: O(M) per weight, O(M²)
/// back-shifts per resampling step.
#[derive(Clone, Copy, Debug, Default)]
pub struct Gbh;

impl MisScheme for Gbh {
    fn name(&self) -> &'static str {
        "GBH"
    }
    fn bias(&self) -> Bias {
        Bias::Unbiased
    }
    fn needs_all_targets(&self, _i: usize) -> bool {
        true
    }
    fn weight(&self, i: usize, targets: &[f32], confidences: &[f32]) -> f32 {
        // m_i = c_i p̂_{←i} / Σ_j c_j p̂_{←j}   [001 Eq. 8]
        let den: f32 = targets.iter().zip(confidences).map(|(t, c)| c * t).sum();
        ratio(confidences[i] * targets[i], den)
    }
}

/// Pairwise MIS with confidences: each neighbour pair (canonical, i) shares `1/k` by a
/// two-domain balance heuristic: `m_i = a_i / (a_i + b) / k`, `m_c = Σ_i b / (a_i + b) / k`
/// with `a_i = c_i p̂_{←i}`, `b = c_c p̂_c`. With no neighbour, `m_c = 1`.
#[derive(Clone, Copy, Debug, Default)]
pub struct Pairwise;

impl MisScheme for Pairwise {
    fn name(&self) -> &'static str {
        "pairwise"
    }
    fn bias(&self) -> Bias {
        Bias::Unbiased
    }
    fn needs_all_targets(&self, i: usize) -> bool {
        i == 0
    }
    fn weight(&self, i: usize, targets: &[f32], confidences: &[f32]) -> f32 {
        let k = targets.len() - 1;
        if k == 0 {
            return 1.0;
        }
        let b = confidences[0] * targets[0];
        if i == 0 {
            let pairs: f32 = (1..=k)
                .map(|j| {
                    let a = confidences[j] * targets[j];
                    if a + b > 0.0 { b / (a + b) } else { 1.0 }
                })
                .sum();
            pairs / k as f32
        } else {
            let a = confidences[i] * targets[i];
            ratio(a, a + b) / k as f32
        }
    }
}

/// Defensive pairwise MIS in streaming form, exactly as DESIGN §9: `a_i = c_i p̂_{←i}`,
/// `b = c_c p̂_c / k`; neighbour `m_i = a_i / (a_i + b) / (v + 1)`, canonical
/// `m_c = [1 + Σ_i b / (b + a_i)] / (v + 1)`. The driver passes only the neighbours actually
/// taken, so `k = v` = their number.
#[derive(Clone, Copy, Debug, Default)]
pub struct DefensivePairwise;

impl MisScheme for DefensivePairwise {
    fn name(&self) -> &'static str {
        "defensive pairwise"
    }
    fn bias(&self) -> Bias {
        Bias::Unbiased
    }
    fn needs_all_targets(&self, i: usize) -> bool {
        i == 0
    }
    fn weight(&self, i: usize, targets: &[f32], confidences: &[f32]) -> f32 {
        let v = targets.len() - 1;
        if v == 0 {
            return 1.0;
        }
        let b = confidences[0] * targets[0] / v as f32;
        let share = 1.0 / (v as f32 + 1.0);
        if i == 0 {
            let pairs: f32 = (1..=v)
                .map(|j| {
                    let a = confidences[j] * targets[j];
                    if a + b > 0.0 { b / (b + a) } else { 1.0 }
                })
                .sum();
            (1.0 + pairs) * share
        } else {
            let a = confidences[i] * targets[i];
            ratio(a, a + b) * share
        }
    }
}

/// `m_i = c_i / Σ_j c_j` ("1/M" with confidences). Ignores the targets, so a domain that cannot
/// produce `y` still takes its share: biased unless all supports agree.
#[derive(Clone, Copy, Debug, Default)]
pub struct ConfidenceOnly;

impl MisScheme for ConfidenceOnly {
    fn name(&self) -> &'static str {
        "1/M"
    }
    fn bias(&self) -> Bias {
        Bias::BiasedUnlessSupportsAgree
    }
    fn needs_all_targets(&self, _i: usize) -> bool {
        false
    }
    fn weight(&self, i: usize, _targets: &[f32], confidences: &[f32]) -> f32 {
        ratio(confidences[i], confidences.iter().sum())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::StreamKey;

    fn schemes() -> [&'static dyn MisScheme; 4] {
        [&Gbh, &Pairwise, &DefensivePairwise, &ConfidenceOnly]
    }

    /// Σ_j m_j(y) = 1 for random targets (some zero) and confidences, 1–8 domains, every scheme.
    #[test]
    fn weights_sum_to_one_and_stay_in_unit_interval() {
        let mut rng = StreamKey::new(0, 0, 0, 1).stream(3);
        for trial in 0..2000 {
            let n = 1 + trial % 8;
            let mut t = [0.0f32; MAX_DOMAINS];
            let mut c = [0.0f32; MAX_DOMAINS];
            t[0] = 0.01 + rng.next_f32();
            c[0] = 0.5 + 4.0 * rng.next_f32();
            for j in 1..n {
                t[j] = if rng.next_f32() < 0.3 {
                    0.0
                } else {
                    5.0 * rng.next_f32()
                };
                c[j] = 40.0 * rng.next_f32();
            }
            for s in schemes() {
                let sum: f32 = (0..n).map(|i| s.weight(i, &t[..n], &c[..n])).sum();
                assert!((sum - 1.0).abs() < 1e-5, "{}: Σm = {sum}", s.name());
                for i in 0..n {
                    let m = s.weight(i, &t[..n], &c[..n]);
                    assert!((0.0..=1.0 + 1e-6).contains(&m), "{}: m_{i} = {m}", s.name());
                }
            }
        }
    }

    /// The temporal formulas of DESIGN §9, written out, against the GBH plug-in.
    #[test]
    fn gbh_matches_the_two_domain_temporal_formulas() {
        let (c_c, c_p) = (2.0f32, 40.0f32);
        let (p_c_yc, p_from_p_yc) = (0.7f32, 0.3f32);
        let m_c = c_c * p_c_yc / (c_c * p_c_yc + c_p * p_from_p_yc);
        assert_eq!(Gbh.weight(0, &[p_c_yc, p_from_p_yc], &[c_c, c_p]), m_c);
        let (p_p_over_j, p_c_yp) = (0.9f32, 0.2f32);
        let m_p = c_p * p_p_over_j / (c_p * p_p_over_j + c_c * p_c_yp);
        assert_eq!(Gbh.weight(1, &[p_c_yp, p_p_over_j], &[c_c, c_p]), m_p);
    }

    #[test]
    fn defensive_pairwise_matches_design_formulas() {
        let t = [0.5f32, 0.2, 0.0, 1.5];
        let c = [1.0f32, 3.0, 2.0, 4.0];
        let k = 3.0f32;
        let b = c[0] * t[0] / k;
        let a = |i: usize| c[i] * t[i];
        let m_c = (1.0 + (1..4).map(|i| b / (b + a(i))).sum::<f32>()) / (k + 1.0);
        assert!((DefensivePairwise.weight(0, &t, &c) - m_c).abs() < 1e-7);
        for i in 1..4 {
            let m_i = a(i) / (a(i) + b) / (k + 1.0);
            assert!((DefensivePairwise.weight(i, &t, &c) - m_i).abs() < 1e-7);
        }
    }

    /// A domain with p̂_{←j}(y) = 0 gets weight 0 under the unbiased schemes, not under 1/M.
    #[test]
    fn only_confidence_only_gives_weight_to_a_domain_that_cannot_produce_y() {
        let t = [1.0f32, 0.0, 2.0];
        let c = [1.0f32, 5.0, 1.0];
        for s in [&Gbh as &dyn MisScheme, &Pairwise, &DefensivePairwise] {
            assert_eq!(s.weight(1, &t, &c), 0.0, "{}", s.name());
            assert!(s.bias().is_unbiased_when_supports_differ());
        }
        assert!(ConfidenceOnly.weight(1, &t, &c) > 0.0);
        assert!(!ConfidenceOnly.bias().is_unbiased_when_supports_differ());
    }

    #[test]
    fn zero_targets_and_zero_confidences_give_finite_weights() {
        for s in schemes() {
            for i in 0..3 {
                let m = s.weight(i, &[0.0; 3], &[0.0; 3]);
                assert!(m.is_finite(), "{}", s.name());
            }
        }
    }
}
