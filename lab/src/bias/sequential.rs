//! The group-sequential bias test: the rows of a bias test are looked at K times as replicas
//! accumulate, and each row leaves the test as soon as it is decided ([`Schedule`], [`looks`]).
//!
//! * Looks at replicas `n_1 < … < n_K = N_max`, information fractions `t_k = n_k / N_max`.
//! * α is spent by the Lan–DeMets O'Brien–Fleming-type function
//!   `α(t) = 2 − 2Φ(z_{1−α/2} / √t)` [Lan & DeMets 1983, Eq. 2]; look k has the level
//!   `α_k = α(t_k) − α(t_{k−1})` (`Σ α_k = α`).
//! * At look k, Holm's procedure at level `α_k` runs on the Welch p-values of zero bias of
//!   **every** row (decided ones included: a family that shrank as rows left would depend on the
//!   earlier looks, and the rows that stay are the ones with the larger estimates). Each row
//!   still undecided is then
//!   - **equivalent** if its `1 − α_k` CI of the relative bias ([`equivalence`]) lies inside ±δ;
//!   - otherwise **biased** if Holm rejects its zero bias; a CI outside ±δ alone never calls a
//!     row biased.
//! * What is controlled: the probability that any row without bias is called biased at any look
//!   is at most `Σ_k α_k = α` (Holm controls the family-wise rate at look k at `α_k`; the looks
//!   are joined by the union bound, so the design is valid for any correlation between looks
//!   and conservative next to boundaries integrated over their joint law [Jennison & Turnbull
//!   2000, §7.2]). For each row, the probability of calling it equivalent when its bias is
//!   ±δ or beyond is at most `Σ_k α_k/2 = α/2` (each look's two one-sided tests at `α_k/2`).
//!
//! The looks themselves ([`looks`]) take the rows' summaries at each `n_k` from a function, so the
//! same code decides simulated rows (the tests below) and rendered ones (`budgeted`).

use restir::stats::{
    Equivalence, Summary, Verdict, equivalence, holm, normal_cdf, normal_quantile,
};

/// Looks of the sequential design.
pub const LOOKS: usize = 4;

/// α spent by information fraction `t ∈ (0, 1]`: `2 − 2Φ(z_{1−α/2}/√t)` [Lan & DeMets 1983,
/// Eq. 2], the O'Brien–Fleming-type spending function; `α(1) = α`, and 0 at `t = 0`.
pub fn spent(alpha: f64, t: f64) -> f64 {
    if t <= 0.0 {
        return 0.0;
    }
    let z = normal_quantile(1.0 - 0.5 * alpha);
    2.0 * (1.0 - normal_cdf(z / t.min(1.0).sqrt()))
}

/// The replicas at each look and the level each look spends.
#[derive(Clone, Debug, PartialEq)]
pub struct Schedule {
    /// Replicas at look k, increasing; the last is N_max.
    pub n: Vec<usize>,
    /// `α_k = α(t_k) − α(t_{k−1})`.
    pub levels: Vec<f64>,
}

impl Schedule {
    /// [`LOOKS`] equally spaced looks up to `n_max`, none before `first` replicas (at least 2),
    /// spending `alpha` by [`spent`] at the looks' information fractions.
    pub fn new(n_max: usize, first: usize, alpha: f64) -> Schedule {
        let first = first.max(2);
        let n_max = n_max.max(first);
        let mut n: Vec<usize> = (1..=LOOKS)
            .map(|k| (n_max * k).div_ceil(LOOKS).max(first))
            .collect();
        n.dedup();
        let levels = Schedule::levels(&n, alpha);
        Schedule { n, levels }
    }

    /// The levels of looks at `n` (the last being N_max).
    fn levels(n: &[usize], alpha: f64) -> Vec<f64> {
        let n_max = *n.last().expect("at least one look") as f64;
        let mut before = 0.0;
        n.iter()
            .map(|&n| {
                let now = spent(alpha, n as f64 / n_max);
                let level = now - before;
                before = now;
                level
            })
            .collect()
    }

    /// The level of the last look: what a plan of N_max must reach its power at.
    pub fn last_level(alpha: f64) -> f64 {
        let t = (LOOKS - 1) as f64 / LOOKS as f64;
        alpha - spent(alpha, t)
    }
}

/// One row's state after the looks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RowState {
    /// The test at the look that decided the row, or at the last look taken.
    pub test: Option<Equivalence>,
    pub estimate: Option<Summary>,
    /// Whether Holm rejected zero bias at that look.
    pub holm_rejected: bool,
    pub verdict: Verdict,
    /// The look (0-based) that decided the row.
    pub decided_at: Option<usize>,
}

/// What one look did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Look {
    pub n: usize,
    pub level: f64,
    pub equivalent: usize,
    pub biased: usize,
}

/// Runs the looks of `schedule` on the rows of `aim` with tolerance `delta`. `summaries(n)`
/// gives every row's (estimate, reference) summaries over the first `n` replicas, or `None` when
/// `n` cannot be afforded (the looks end there). A decided row keeps its verdict (and the test
/// that gave it); the looks end when every row whose `aim` is true (the rows the schedule was
/// planned for) is decided.
pub fn looks(
    schedule: &Schedule,
    delta: f64,
    aim: &[bool],
    mut summaries: impl FnMut(usize) -> Option<Vec<(Summary, Summary)>>,
) -> (Vec<RowState>, Vec<Look>) {
    let rows = aim.len();
    let mut state = vec![
        RowState {
            test: None,
            estimate: None,
            holm_rejected: false,
            verdict: Verdict::Inconclusive,
            decided_at: None,
        };
        rows
    ];
    let mut taken = Vec::new();
    for (k, (&n, &level)) in schedule.n.iter().zip(&schedule.levels).enumerate() {
        let open: Vec<usize> = (0..rows)
            .filter(|&r| state[r].decided_at.is_none())
            .collect();
        if open.iter().all(|&r| !aim[r]) {
            break;
        }
        let Some(all) = summaries(n) else { break };
        let tests: Vec<Equivalence> = all
            .iter()
            .map(|(e, r)| equivalence(e, r, delta, 1.0 - level))
            .collect();
        let p: Vec<f64> = tests.iter().map(|t| t.p_zero_bias).collect();
        let rejected = holm(&p, level);
        let mut look = Look {
            n,
            level,
            equivalent: 0,
            biased: 0,
        };
        for r in open {
            let test = tests[r];
            let verdict = if test.ci_low > -delta && test.ci_high < delta {
                look.equivalent += 1;
                Verdict::Equivalent
            } else if rejected[r] {
                look.biased += 1;
                Verdict::Biased
            } else {
                Verdict::Inconclusive
            };
            state[r] = RowState {
                test: Some(test),
                estimate: Some(all[r].0),
                holm_rejected: rejected[r],
                verdict,
                decided_at: (verdict != Verdict::Inconclusive).then_some(k),
            };
        }
        taken.push(look);
    }
    (state, taken)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bias::tests::normal;
    use restir::rng::{Stream, StreamKey};
    use restir::stats::{EquivalencePlan, binomial_interval, replicas_for};

    /// δ = 2%, α = 0.05 (large enough for the simulated error rates to be measured with M runs).
    const DELTA: f64 = 0.02;
    const ALPHA: f64 = 0.05;
    /// Per-replica coefficient of variation of every toy row.
    const CV: f64 = 0.1;
    /// Rows of the toy.
    const ROWS: usize = 4;
    /// Simulated runs per case.
    const M: usize = 2000;
    /// Reference batches, and the CV of one (relative s.e. of the reference 0.25%).
    const BATCHES: usize = 400;
    const BATCH_CV: f64 = 0.05;

    fn stream(run: u64, row: usize, reference: bool) -> Stream {
        StreamKey {
            pixel: row as u32,
            frame: reference as u32,
            pass: 0x5E0,
            purpose: 0,
        }
        .stream(run)
    }

    /// The toy's plan: N_max for power 0.9 that every row is equivalent without bias, at the
    /// last look's level, against a reference of [`BATCHES`] batches.
    fn plan() -> (EquivalencePlan, usize) {
        let plan = EquivalencePlan {
            delta: DELTA,
            alpha: Schedule::last_level(ALPHA),
            reference_rel_se: BATCH_CV / (BATCHES as f64).sqrt(),
            reference_n: BATCHES,
        };
        let n = replicas_for(&vec![(plan, CV); ROWS], 0.9, 1 << 20).expect("plannable");
        (plan, n)
    }

    /// One simulated run: row r's replicas are `(1 + bias[r])(1 + CV·z)` against a reference of
    /// mean 1; `levels` overrides the schedule's levels (the naive control).
    fn simulate(run: u64, bias: [f64; ROWS], schedule: &Schedule) -> Vec<RowState> {
        let n_max = *schedule.n.last().unwrap();
        let replicas: Vec<Vec<f64>> = (0..ROWS)
            .map(|r| {
                let mut s = stream(run, r, false);
                (0..n_max)
                    .map(|_| (1.0 + bias[r]) * (1.0 + CV * normal(&mut s)))
                    .collect()
            })
            .collect();
        let reference: Vec<Summary> = (0..ROWS)
            .map(|r| {
                let mut s = stream(run, r, true);
                let xs: Vec<f64> = (0..BATCHES)
                    .map(|_| 1.0 + BATCH_CV * normal(&mut s))
                    .collect();
                Summary::from_samples(&xs)
            })
            .collect();
        let at = |n: usize| {
            let rows = (0..ROWS).map(|r| (Summary::from_samples(&replicas[r][..n]), reference[r]));
            Some(rows.collect())
        };
        looks(schedule, DELTA, &[true; ROWS], at).0
    }

    /// Per event, how many of M runs satisfy it.
    type Event<'a> = &'a dyn Fn(&[RowState]) -> bool;
    fn count(bias: [f64; ROWS], schedule: &Schedule, events: &[Event]) -> Vec<usize> {
        let mut counts = vec![0; events.len()];
        for run in 0..M as u64 {
            let rows = simulate(run, bias, schedule);
            for (count, event) in counts.iter_mut().zip(events) {
                *count += event(&rows) as usize;
            }
        }
        counts
    }

    /// The spending function spends α in all and little early; the schedule's levels sum to α.
    #[test]
    fn obrien_fleming_spending() {
        assert_eq!(spent(0.01, 0.0), 0.0);
        assert!((spent(0.01, 1.0) - 0.01).abs() < 1e-12);
        // z_{0.995} = 2.5758; at t = 1/4 the boundary is 2·2.5758 = 5.15, 2 − 2Φ(5.15) ≈ 2.6e-7.
        assert!(
            (spent(0.01, 0.25) - 2.6e-7).abs() < 0.1e-7,
            "{}",
            spent(0.01, 0.25)
        );
        let schedule = Schedule::new(1000, 2, 0.01);
        assert_eq!(Schedule::new(1000, 600, 0.01).n, vec![600, 750, 1000]);
        assert_eq!(schedule.n, vec![250, 500, 750, 1000]);
        assert!((schedule.levels.iter().sum::<f64>() - 0.01).abs() < 1e-12);
        assert!(schedule.levels.windows(2).all(|w| w[0] < w[1]));
        assert!((schedule.levels[LOOKS - 1] - Schedule::last_level(0.01)).abs() < 1e-15);
    }

    /// The toy with known bias, M = 2000 runs per case, 4 rows, CV 0.1, δ = 2%, α = 0.05,
    /// reference s.e. 0.25%, N_max from the power plan at the last look's level:
    /// * no bias: runs with any row called biased ≤ α (the count at most the upper end of the
    ///   binomial 99.9% interval at α), runs with every row equivalent ≥ the planned 0.9 (at
    ///   least the lower end of its interval);
    /// * one row at +δ (the boundary): called equivalent in at most α/2 of runs (the equivalence
    ///   test's error), and called biased at least as often as planned (Welch at the last look's
    ///   level over Holm's first step: a lower bound on the power);
    /// * one row at +1.5δ: decided biased before the last look in most runs (the design stops
    ///   early for clearly biased rows).
    ///
    /// Negative control: every look at the full α (no spending) calls some unbiased row biased in
    /// more than α of runs.
    #[test]
    fn sequential_error_rates_match_the_design() {
        let (plan, n_max) = plan();
        let schedule = Schedule::new(n_max, 2, ALPHA);
        let biased = |rows: &[RowState]| rows.iter().any(|r| r.verdict == Verdict::Biased);
        let all_equivalent =
            |rows: &[RowState]| rows.iter().all(|r| r.verdict == Verdict::Equivalent);
        let first_is = |verdict| move |rows: &[RowState]| rows[0].verdict == verdict;
        let (_, alpha_bound) = binomial_interval(M, ALPHA, 0.999);

        let unbiased = count([0.0; ROWS], &schedule, &[&biased, &all_equivalent]);
        let (false_biased, equivalent) = (unbiased[0], unbiased[1]);
        assert!(
            false_biased <= alpha_bound,
            "type I: {false_biased}/{M}, bound {alpha_bound}"
        );
        let (lo, _) = binomial_interval(M, 0.9, 0.999);
        assert!(
            equivalent >= lo,
            "power: {equivalent}/{M} all equivalent, planned 0.9 ({lo})"
        );

        let at_delta = count(
            [DELTA, 0.0, 0.0, 0.0],
            &schedule,
            &[&first_is(Verdict::Equivalent), &first_is(Verdict::Biased)],
        );
        let (_, hi) = binomial_interval(M, ALPHA / 2.0, 0.999);
        assert!(
            at_delta[0] <= hi,
            "equivalent at +δ: {}/{M}, bound {hi}",
            at_delta[0]
        );
        let planned = plan.rejection_power(CV, n_max, DELTA, plan.alpha / ROWS as f64);
        let (lo, _) = binomial_interval(M, planned, 0.999);
        assert!(
            at_delta[1] >= lo,
            "+δ: {}/{M} biased, planned ≥ {planned:.3}",
            at_delta[1]
        );

        let early = |rows: &[RowState]| {
            rows[0].verdict == Verdict::Biased && rows[0].decided_at.is_some_and(|k| k < LOOKS - 1)
        };
        let early = count([1.5 * DELTA, 0.0, 0.0, 0.0], &schedule, &[&early])[0];
        assert!(
            2 * early > M,
            "+1.5δ decided biased before the last look in {early}/{M}"
        );

        let naive = Schedule {
            levels: vec![ALPHA; LOOKS],
            ..schedule
        };
        let naive_biased = count([0.0; ROWS], &naive, &[&biased])[0];
        assert!(
            naive_biased > alpha_bound,
            "control: {naive_biased}/{M} ≤ {alpha_bound}"
        );
        println!(
            "N_max {n_max}: false biased {false_biased}/{M}, all equivalent {equivalent}/{M}; \
             at +δ equivalent {}/{M}, biased {}/{M} (planned ≥ {planned:.3}); +1.5δ biased \
             before the last look {early}/{M}; naive looks: false biased {naive_biased}/{M}",
            at_delta[0], at_delta[1]
        );
    }
}
