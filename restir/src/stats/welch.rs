//! Two-sample tests between replica summaries and family-wise corrections for many of them.

use super::special::student_t_cdf;
use super::summary::Summary;

/// Result of a two-sided Welch test of `mean_a = mean_b`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WelchTest {
    /// `(mean_a − mean_b) / √(se_a² + se_b²)`.
    pub t: f64,
    /// Welch–Satterthwaite degrees of freedom.
    pub dof: f64,
    /// Two-sided p-value.
    pub p_value: f64,
}

/// Welch's unequal-variance t-test. `b` may be [`Summary::exact`] (standard error 0): then it
/// is the one-sample t-test of `a` against that constant.
///
/// Edge cases (never NaN):
/// * a non-finite mean (a replica produced NaN/∞) is rejected outright: `t = ±∞` (+∞ for
///   NaN), `dof = 0`, `p = 0`; such an estimator is broken whatever its bias;
/// * an infinite standard error (fewer than two replicas) or a sample without spread
///   ([`Summary::no_spread`]: all replicas equal): no information, `t = 0`, `dof = 0`, `p = 1`;
/// * both standard errors 0: `p = 1`, `t = 0` if the means are equal, else `p = 0`,
///   `t = ±∞`; `dof = ∞`.
pub fn welch(a: &Summary, b: &Summary) -> WelchTest {
    let diff = a.mean - b.mean;
    if !diff.is_finite() {
        let t = if diff == f64::NEG_INFINITY {
            f64::NEG_INFINITY
        } else {
            f64::INFINITY
        };
        return WelchTest {
            t,
            dof: 0.0,
            p_value: 0.0,
        };
    }
    let (va, vb) = (a.std_err * a.std_err, b.std_err * b.std_err);
    if !(va + vb).is_finite() || a.no_spread() || b.no_spread() {
        return WelchTest {
            t: 0.0,
            dof: 0.0,
            p_value: 1.0,
        };
    }
    if va + vb == 0.0 {
        return if diff == 0.0 {
            WelchTest {
                t: 0.0,
                dof: f64::INFINITY,
                p_value: 1.0,
            }
        } else {
            WelchTest {
                t: diff.signum() * f64::INFINITY,
                dof: f64::INFINITY,
                p_value: 0.0,
            }
        };
    }
    let t = diff / (va + vb).sqrt();
    let dof = satterthwaite(&[(va, a.n), (vb, b.n)]);
    WelchTest {
        t,
        dof,
        p_value: 2.0 * student_t_cdf(-t.abs(), dof),
    }
}

/// Welch–Satterthwaite degrees of freedom of a sum of independent variance estimates
/// `(vᵢ, nᵢ)`, each with `nᵢ − 1` dof: `(Σvᵢ)² / Σ(vᵢ²/(nᵢ − 1))`, computed on `vᵢ/Σv` so it
/// cannot overflow. Terms with `vᵢ = 0` (exact constants) carry no dof; all zero → ∞; a
/// positive variance from fewer than two samples → 0.
pub(crate) fn satterthwaite(terms: &[(f64, usize)]) -> f64 {
    let total: f64 = terms.iter().map(|t| t.0).sum();
    if total == 0.0 {
        return f64::INFINITY;
    }
    let mut denominator = 0.0;
    for &(v, n) in terms.iter().filter(|t| t.0 > 0.0) {
        if n < 2 {
            return 0.0;
        }
        let share = v / total;
        denominator += share * share / (n - 1) as f64;
    }
    1.0 / denominator
}

/// Holm's step-down procedure (Holm 1979): sort the m p-values ascending and reject while
/// `p₍ₖ₎ ≤ α/(m − k)` (k from 0). Controls the family-wise error rate at `alpha` under any
/// dependence. Returns `true` = rejected, in input order; NaN p-values sort last, count in m
/// and are never rejected.
pub fn holm(p_values: &[f64], alpha: f64) -> Vec<bool> {
    let m = p_values.len();
    let mut order: Vec<usize> = (0..m).collect();
    order.sort_by(|&i, &j| {
        let (a, b) = (p_values[i], p_values[j]);
        a.is_nan().cmp(&b.is_nan()).then(a.total_cmp(&b))
    });
    let mut rejected = vec![false; m];
    for (k, &i) in order.iter().enumerate() {
        if p_values[i].is_nan() || p_values[i] > alpha / (m - k) as f64 {
            break;
        }
        rejected[i] = true;
    }
    rejected
}

/// Šidák's per-test level for `m` independent tests at family-wise error `alpha`:
/// `1 − (1 − α)^{1/m}` (computed with `expm1`/`ln_1p`). `m = 0` → `alpha`.
pub fn sidak_alpha(alpha: f64, m: usize) -> f64 {
    if m == 0 {
        return alpha;
    }
    -((-alpha).ln_1p() / m as f64).exp_m1()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stats::special::{binomial_interval, normal_cdf, student_t_quantile};
    use crate::stats::testing::{normal, stream};

    /// α = 0.05, M = 2000 null experiments (a: n = 5, σ = 1; b: n = 8, σ = 2, same mean): the
    /// rejection count must lie in the binomial 99.9% interval of M·α. Negative control: the
    /// same statistic with normal instead of t tails (a z-test) over-rejects at these sizes.
    #[test]
    fn welch_null_rejection_rate_is_alpha() {
        const M: usize = 2000;
        const ALPHA: f64 = 0.05;
        let mut s = stream(2, 1);
        let (mut welch_rejects, mut z_rejects) = (0, 0);
        for _ in 0..M {
            let a: Vec<f64> = (0..5).map(|_| 3.0 + normal(&mut s)).collect();
            let b: Vec<f64> = (0..8).map(|_| 3.0 + 2.0 * normal(&mut s)).collect();
            let w = welch(&Summary::from_samples(&a), &Summary::from_samples(&b));
            welch_rejects += (w.p_value < ALPHA) as usize;
            z_rejects += (2.0 * normal_cdf(-w.t.abs()) < ALPHA) as usize;
        }
        let (lo, hi) = binomial_interval(M, ALPHA, 0.999);
        assert!(
            (lo..=hi).contains(&welch_rejects),
            "Welch: {welch_rejects}/{M} rejections at α = {ALPHA}, 99.9% interval [{lo}, {hi}]"
        );
        assert!(
            z_rejects > hi,
            "z-test control: {z_rejects}/{M} rejections, should exceed {hi}"
        );
    }

    /// Power: a shift of 0.5σ between two samples of N = 64 replicas, α = 0.05, M = 1000
    /// experiments. The rejection count must lie in the 99.9% binomial interval of the power
    /// predicted by the normal approximation `Φ(δ/se − t_crit) + Φ(−δ/se − t_crit)` (≈ 0.80),
    /// and each rejection must have the sign of the shift.
    #[test]
    fn welch_detects_half_sigma_shift() {
        const M: usize = 1000;
        const N: usize = 64;
        const ALPHA: f64 = 0.05;
        let mut s = stream(2, 2);
        let mut rejects = 0;
        for _ in 0..M {
            let a: Vec<f64> = (0..N).map(|_| 0.5 + normal(&mut s)).collect();
            let b: Vec<f64> = (0..N).map(|_| normal(&mut s)).collect();
            let w = welch(&Summary::from_samples(&a), &Summary::from_samples(&b));
            if w.p_value < ALPHA {
                assert!(w.t > 0.0, "rejected with the wrong sign: {w:?}");
                rejects += 1;
            }
        }
        let ncp = 0.5 / (2.0 / N as f64).sqrt();
        let t_crit = student_t_quantile(1.0 - ALPHA / 2.0, (2 * N - 2) as f64);
        let power = normal_cdf(ncp - t_crit) + normal_cdf(-ncp - t_crit);
        let (lo, hi) = binomial_interval(M, power, 0.999);
        assert!(
            (lo..=hi).contains(&rejects),
            "power {rejects}/{M} at α = {ALPHA}, N = {N}; expected ≈ {power:.3}, interval [{lo}, {hi}]"
        );
    }

    /// One-sample form: against an exact constant the dof are n − 1 and t is the one-sample t.
    #[test]
    fn one_sample_against_exact() {
        let a = Summary::from_samples(&[1.0, 2.0, 3.0, 4.0]);
        let w = welch(&a, &Summary::exact(1.0));
        assert_eq!(w.dof, 3.0);
        assert!((w.t - 1.5 / a.std_err).abs() < 1e-14);
        // t = 1.5/√(5/12) = 2.3238: two-sided p at 3 dof = I_{3/(3+t²)}(3/2, 1/2) (mpmath, 30 digits).
        assert!((w.p_value - 0.102_728_078_858_399).abs() < 1e-12, "{w:?}");
    }

    #[test]
    fn degenerate_cases_are_defined() {
        let (two, three) = (Summary::exact(2.0), Summary::exact(3.0));
        assert_eq!(
            welch(&two, &two),
            WelchTest {
                t: 0.0,
                dof: f64::INFINITY,
                p_value: 1.0
            }
        );
        let w = welch(&two, &three);
        assert_eq!((w.t, w.p_value), (f64::NEG_INFINITY, 0.0));
        let empty = Summary::from_samples(&[]);
        assert_eq!(
            welch(&empty, &three),
            WelchTest {
                t: 0.0,
                dof: 0.0,
                p_value: 1.0
            }
        );
        let broken = Summary::from_samples(&[1.0, f64::NAN]);
        assert_eq!(
            welch(&broken, &three),
            WelchTest {
                t: f64::INFINITY,
                dof: 0.0,
                p_value: 0.0
            }
        );
        let same = Summary::from_samples(&[5.0, 5.0, 5.0]);
        assert_eq!(welch(&same, &Summary::exact(5.0)).p_value, 1.0);
        // All replicas equal is no evidence of a difference, however far the constant is.
        let no_information = WelchTest {
            t: 0.0,
            dof: 0.0,
            p_value: 1.0,
        };
        assert_eq!(welch(&same, &three), no_information);
        let noisy = Summary::from_samples(&[2.9, 3.0, 3.1]);
        assert_eq!(
            welch(&noisy, &Summary::from_samples(&[0.0; 2])),
            no_information
        );
    }

    /// Textbook example (Wikipedia, "Holm–Bonferroni method"): p = 0.01, 0.04, 0.03, 0.005 at
    /// α = 0.05 rejects H1 and H4. Second case: 0.01, 0.015, 0.02 are all rejected by Holm,
    /// while Bonferroni (α/m = 0.0167 each) would reject only the first.
    #[test]
    fn holm_textbook() {
        assert_eq!(
            holm(&[0.01, 0.04, 0.03, 0.005], 0.05),
            vec![true, false, false, true]
        );
        assert_eq!(holm(&[0.02, 0.01, 0.015], 0.05), vec![true, true, true]);
        assert_eq!(
            holm(&[0.02, -f64::NAN, 0.01], 0.05),
            vec![true, false, true]
        );
        assert!(holm(&[], 0.05).is_empty());
    }

    /// Family-wise error under the global null, m = 10 independent uniform p-values,
    /// α = 0.05, M = 2000 families: Holm's FWER is P(min p ≤ α/m) = 1 − (1 − α/m)^m, Šidák's is
    /// α exactly; both counts must lie in their binomial 99.9% intervals. Negative control:
    /// no correction (each p < α) gives FWER 1 − 0.95¹⁰ ≈ 0.40.
    #[test]
    fn family_wise_error_rates() {
        const M: usize = 2000;
        const FAMILY: usize = 10;
        const ALPHA: f64 = 0.05;
        let sidak = sidak_alpha(ALPHA, FAMILY);
        assert!((1.0 - (1.0 - sidak).powi(FAMILY as i32) - ALPHA).abs() < 1e-15);
        let mut s = stream(2, 3);
        let (mut holm_errors, mut sidak_errors, mut raw_errors) = (0, 0, 0);
        for _ in 0..M {
            let p: Vec<f64> = (0..FAMILY).map(|_| s.next_f64()).collect();
            holm_errors += holm(&p, ALPHA).contains(&true) as usize;
            sidak_errors += p.iter().any(|&p| p < sidak) as usize;
            raw_errors += p.iter().any(|&p| p < ALPHA) as usize;
        }
        let holm_fwer = 1.0 - (1.0 - ALPHA / FAMILY as f64).powi(FAMILY as i32);
        let (lo, hi) = binomial_interval(M, holm_fwer, 0.999);
        assert!(
            (lo..=hi).contains(&holm_errors),
            "Holm FWER {holm_errors}/{M}, interval [{lo}, {hi}]"
        );
        let (lo, hi) = binomial_interval(M, ALPHA, 0.999);
        assert!(
            (lo..=hi).contains(&sidak_errors),
            "Šidák FWER {sidak_errors}/{M}, interval [{lo}, {hi}]"
        );
        assert!(
            raw_errors > hi,
            "uncorrected control: {raw_errors}/{M} family errors, should exceed {hi}"
        );
        assert_eq!(sidak_alpha(ALPHA, 0), ALPHA);
    }
}
