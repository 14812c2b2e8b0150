//! How many replicas an equivalence test needs (DESIGN §3, "Statistics"): the power of
//! [`equivalence`](super::equivalence()) and of Welch's zero-bias test, planned from the spread
//! of one replica before the replicas are run.
//!
//! Model: the relative bias `b = ē/r̄ − 1` is normal around the true bias β with the
//! delta-method variance of [`equivalence`](super::equivalence()) at the planned spreads,
//! `s² = (1 + β)²·(cv²/N + ρ²)`, where `cv` is the coefficient of variation of one replica (σ/μ
//! of the quantity tested, e.g. a region's mean red radiance) and `ρ` the reference's relative
//! standard error. The CI's half-width is `t_{1−α/2, ν}·s` with the Welch–Satterthwaite ν of the
//! two terms, its estimate taken as exact: accurate from a few dozen replicas on (the tests below
//! check it by simulation).

use super::special::{normal_cdf, student_t_quantile};
use super::welch::satterthwaite;

/// The design of an equivalence test of a relative bias, before its replicas are run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EquivalencePlan {
    /// Tolerance δ on the relative bias.
    pub delta: f64,
    /// The CI has confidence `1 − alpha`.
    pub alpha: f64,
    /// Relative standard error of the reference mean, `se_r / r̄` (0 for an exact reference).
    pub reference_rel_se: f64,
    /// Independent samples (e.g. batches) behind `reference_rel_se`.
    pub reference_n: usize,
}

impl EquivalencePlan {
    /// The variances of the estimate's and the reference's terms of the relative bias, and
    /// their Welch–Satterthwaite dof, for N replicas of per-replica CV `cv`; `bias_scale` is
    /// `(1 + β)²` where the term carries it.
    fn terms(&self, cv: f64, n: usize, [scale_e, scale_r]: [f64; 2]) -> (f64, f64) {
        let v_estimate = scale_e * cv * cv / n as f64;
        let v_reference = scale_r * self.reference_rel_se * self.reference_rel_se;
        let dof = satterthwaite(&[(v_estimate, n), (v_reference, self.reference_n)]);
        (v_estimate + v_reference, dof)
    }

    /// Probability that [`equivalence`](super::equivalence()) calls N replicas of per-replica CV
    /// `cv` equivalent within ±δ when the true relative bias is `bias`:
    /// `Φ((δ − h − β)/s) − Φ((−δ + h − β)/s)` with the half-width `h = t_{1−α/2, ν}·s`, and 0
    /// when `h ≥ δ` (the interval cannot fit inside ±δ).
    pub fn equivalence_power(&self, cv: f64, n: usize, bias: f64) -> f64 {
        let scale = (1.0 + bias) * (1.0 + bias);
        let (variance, dof) = self.terms(cv, n, [scale, scale]);
        let s = variance.sqrt();
        let half = student_t_quantile(1.0 - 0.5 * self.alpha, dof) * s;
        // A NaN half-width (no dof) cannot fit either.
        if half.partial_cmp(&self.delta) != Some(std::cmp::Ordering::Less) {
            return 0.0;
        }
        if s == 0.0 {
            return f64::from(u8::from(bias.abs() < self.delta));
        }
        let inside = self.delta - half;
        (normal_cdf((inside - bias) / s) - normal_cdf((-inside - bias) / s)).max(0.0)
    }

    /// Probability that Welch's two-sided test rejects zero bias at `level` when the true
    /// relative bias is `bias`; with `level = α/m` it bounds from below the power of Holm's
    /// procedure over m tests to reject this one. With `λ = β/√((1 + β)²cv²/N + ρ²)` and
    /// `q = t_{1−level/2, ν}`: `Φ(λ − q) + Φ(−λ − q)`.
    pub fn rejection_power(&self, cv: f64, n: usize, bias: f64, level: f64) -> f64 {
        let (variance, dof) = self.terms(cv, n, [(1.0 + bias) * (1.0 + bias), 1.0]);
        let lambda = bias / variance.sqrt();
        let q = student_t_quantile(1.0 - 0.5 * level, dof);
        normal_cdf(lambda - q) + normal_cdf(-lambda - q)
    }
}

/// Lower bound on the probability that every test of a family is called equivalent with N
/// replicas each when nothing is biased: Bonferroni's `1 − Σ(1 − Pᵢ)`, at least 0. Each test is
/// its plan and its per-replica CV.
pub fn family_power(tests: &[(EquivalencePlan, f64)], n: usize) -> f64 {
    let misses: f64 = tests
        .iter()
        .map(|(plan, cv)| 1.0 - plan.equivalence_power(*cv, n, 0.0))
        .sum();
    (1.0 - misses).max(0.0)
}

/// The smallest N ≥ 2 with [`family_power`]`(tests, N) ≥ power`, or `None` when no N ≤ `max_n`
/// reaches it (a reference's own error alone may forbid it). The family power grows with N, so
/// the search brackets N by doubling and then bisects.
pub fn replicas_for(tests: &[(EquivalencePlan, f64)], power: f64, max_n: usize) -> Option<usize> {
    let enough = |n: usize| family_power(tests, n) >= power;
    if max_n < 2 || !enough(max_n) {
        return None;
    }
    let (mut lo, mut hi) = (1, 2);
    while !enough(hi) {
        lo = hi;
        hi = (2 * hi).min(max_n);
    }
    while hi - lo > 1 {
        let mid = lo + (hi - lo) / 2;
        if enough(mid) { hi = mid } else { lo = mid }
    }
    Some(hi)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stats::special::binomial_interval;
    use crate::stats::testing::{normal, stream};
    use crate::stats::{Summary, Verdict, equivalence, welch};

    /// δ = 2%, α = 0.01 against a reference of B = 64 batches with relative s.e. ρ = 0.2%.
    const PLAN: EquivalencePlan = EquivalencePlan {
        delta: 0.02,
        alpha: 0.01,
        reference_rel_se: 0.002,
        reference_n: 64,
    };
    /// Per-replica coefficient of variation of the simulated estimator.
    const CV: f64 = 0.1;

    /// `n` normal samples of mean `mean` and relative standard deviation `cv`.
    fn sample(seed: u64, n: usize, mean: f64, cv: f64) -> Summary {
        let mut s = stream(4, seed);
        let xs: Vec<f64> = (0..n).map(|_| mean * (1.0 + cv * normal(&mut s))).collect();
        Summary::from_samples(&xs)
    }

    /// M experiments of N replicas (true relative bias `bias`) against a fresh reference each:
    /// how many are called Equivalent, and how many Welch rejects at `level`.
    fn simulate(m: usize, n: usize, bias: f64, level: f64, seed: u64) -> (usize, usize) {
        let batch_cv = PLAN.reference_rel_se * (PLAN.reference_n as f64).sqrt();
        let (mut equivalent, mut rejected) = (0, 0);
        for k in 0..m as u64 {
            let estimate = sample(seed + 2 * k, n, 1.0 + bias, CV);
            let reference = sample(seed + 2 * k + 1, PLAN.reference_n, 1.0, batch_cv);
            let e = equivalence(&estimate, &reference, PLAN.delta, 1.0 - PLAN.alpha);
            equivalent += (e.verdict == Verdict::Equivalent) as usize;
            rejected += (welch(&estimate, &reference).p_value < level) as usize;
        }
        (equivalent, rejected)
    }

    /// The planned powers against simulation, M = 1000 experiments each, CV = 0.1, δ = 2%,
    /// α = 0.01, ρ = 0.2% (B = 64): at N = 300 and 600 without bias and at N = 600 with +1%
    /// bias, the count called Equivalent lies in the binomial 99.9% interval of the planned
    /// equivalence power; with +3% bias at N = 300 the count Welch rejects at α/12 (Holm's first
    /// step among 12 tests) lies in that of the planned rejection power. Negative control: the
    /// plan that ignores the reference's error (ρ = 0) predicts a power outside the interval.
    #[test]
    fn planned_power_matches_simulation() {
        const M: usize = 1000;
        let level = PLAN.alpha / 12.0;
        let exact_reference = EquivalencePlan {
            reference_rel_se: 0.0,
            ..PLAN
        };
        for (case, (n, bias)) in [(300, 0.0), (600, 0.0), (600, 0.01)]
            .into_iter()
            .enumerate()
        {
            let planned = PLAN.equivalence_power(CV, n, bias);
            let (equivalent, _) = simulate(M, n, bias, level, 1000 * case as u64);
            let (lo, hi) = binomial_interval(M, planned, 0.999);
            assert!(
                (lo..=hi).contains(&equivalent),
                "N = {n}, bias {bias}: {equivalent}/{M} equivalent, planned {planned:.3}, \
                 interval [{lo}, {hi}]"
            );
            let naive = exact_reference.equivalence_power(CV, n, bias);
            let (lo, hi) = binomial_interval(M, naive, 0.999);
            assert!(
                !(lo..=hi).contains(&equivalent),
                "control: ρ = 0 plans {naive:.3}, interval [{lo}, {hi}] holds {equivalent}"
            );
        }
        let planned = PLAN.rejection_power(CV, 300, 0.03, level);
        let (_, rejected) = simulate(M, 300, 0.03, level, 7000);
        let (lo, hi) = binomial_interval(M, planned, 0.999);
        assert!(
            (lo..=hi).contains(&rejected),
            "+3%: {rejected}/{M} rejected at {level}, planned {planned:.3}, interval [{lo}, {hi}]"
        );
    }

    /// `replicas_for` returns the smallest N that reaches the family power; more tests or a
    /// larger CV need more replicas; a reference whose own CI is wider than ±δ makes every N
    /// fail (None), as does a `max_n` below the answer.
    #[test]
    fn replicas_for_is_the_smallest_sufficient_n() {
        let family = |plan: EquivalencePlan, cvs: &[f64]| -> Vec<(EquivalencePlan, f64)> {
            cvs.iter().map(|&cv| (plan, cv)).collect()
        };
        let tests = family(PLAN, &[0.05, 0.08, CV]);
        let n = replicas_for(&tests, 0.95, 100_000).expect("reachable");
        assert!(family_power(&tests, n) >= 0.95);
        assert!(
            family_power(&tests, n - 1) < 0.95,
            "N = {n} is not the smallest"
        );
        let wider = replicas_for(&family(PLAN, &[0.05, 0.08, 0.12]), 0.95, 100_000).unwrap();
        let more = replicas_for(&family(PLAN, &[0.05, 0.08, CV, CV]), 0.95, 100_000).unwrap();
        assert!(wider > n && more > n, "{n} {wider} {more}");
        assert_eq!(replicas_for(&tests, 0.95, n - 1), None);
        let noisy_reference = EquivalencePlan {
            reference_rel_se: 0.008,
            ..PLAN
        };
        let noisy = [(PLAN, 0.05), (noisy_reference, 0.05)];
        assert_eq!(replicas_for(&noisy, 0.5, 1 << 40), None);
        assert_eq!(noisy_reference.equivalence_power(0.0, 10, 0.0), 0.0);
    }

    /// Closed forms: an exact reference with N → ∞ is decided by the normal quantile alone, and
    /// the powers are probabilities.
    #[test]
    fn limits_and_ranges() {
        let exact = EquivalencePlan {
            reference_rel_se: 0.0,
            ..PLAN
        };
        // s = 0.1/√10⁶ = 1e-4: the CI ±2.58e-4 fits ±2% with certainty unless β is near ±δ.
        assert!(exact.equivalence_power(CV, 1_000_000, 0.0) > 1.0 - 1e-12);
        assert!(exact.equivalence_power(CV, 1_000_000, 0.03) < 1e-12);
        assert_eq!(exact.equivalence_power(0.0, 10, 0.01), 1.0);
        for n in [2, 10, 100, 1000] {
            for bias in [-0.05, 0.0, 0.01, 0.05] {
                let p = PLAN.equivalence_power(CV, n, bias);
                let r = PLAN.rejection_power(CV, n, bias, 0.01);
                assert!(
                    (0.0..=1.0).contains(&p) && (0.0..=1.0).contains(&r),
                    "{p} {r}"
                );
            }
        }
        // Without bias Welch rejects at its level (t at 10⁶ dof is within 1e-6 of normal).
        assert!((exact.rejection_power(CV, 1_000_000, 0.0, 0.01) - 0.01).abs() < 1e-6);
    }
}
