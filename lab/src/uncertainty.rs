//! Confidence intervals of the lab's numbers: the delta method over replicas.
//!
//! Replicas are the unit of independence (the pixels of one replica are correlated by reuse).
//! Every number of a comparison is a smooth function `g` of means over the K replicas (per-replica
//! MSE, per-replica seconds per frame); linearised at the means,
//! `ĝ ≈ g + (1/K) Σ_k z_k` with replica k's *influence* `z_k = ∇g · x_k`. So
//!
//! `Var(ĝ) ≈ s_z² / K + v_extra`, and the interval is `ĝ ± t_{K−1}(1 − α/2) · √Var(ĝ)`,
//!
//! where `s_z²` is the sample variance of the influences and `v_extra` the variance of what the
//! replicas do not resample (the reference's noise, [`crate::metrics`]). An [`Estimate`] carries
//! `ĝ`, its influences and `v_extra`; its operations apply the chain rule to the influences.
//! Replica k of every method of a comparison runs with seed k, so estimates of two methods are
//! combined *paired* (influences add per seed), which accounts for any correlation through
//! shared random numbers and costs nothing when there is none. Ratios and products are formed on
//! the log scale ([`Estimate::ln`]) and mapped back with `exp`: their intervals stay positive and
//! do not depend on which method is the numerator. `lab/src/uncertainty.rs`'s tests measure the
//! coverage of the efficiency ratio's interval on synthetic replicas.

use restir::stats::student_t_quantile;
use serde::Serialize;

/// Confidence of every interval the lab reports except the bias (99%, [`crate::metrics`]).
pub const CONFIDENCE: f64 = 0.95;

/// How the intervals are computed, as written into `results.json`.
pub const INTERVAL_METHOD: &str = "delta method over replicas (the unit of independence), \
    Student-t with K-1 degrees of freedom; ratios and efficiencies on the log scale, paired by \
    replica seed; the reference's variance is subtracted from MSE and its uncertainty added to \
    the interval's variance";

/// A closed interval `[lo, hi]`; `hi` is `+∞` (written `null`) for an unbounded efficiency.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Interval {
    pub lo: f64,
    pub hi: f64,
}

impl Interval {
    /// The interval lies entirely below `x`.
    pub fn below(&self, x: f64) -> bool {
        self.hi < x
    }

    /// The interval lies entirely above `x`.
    pub fn above(&self, x: f64) -> bool {
        self.lo > x
    }

    /// `[1/hi, 1/lo]` of a positive interval (`1/0 = +∞`).
    pub fn reciprocal(&self) -> Interval {
        Interval {
            lo: 1.0 / self.hi,
            hi: 1.0 / self.lo,
        }
    }
}

/// A number estimated from K replicas, with what its interval needs (module documentation).
#[derive(Clone, Debug, PartialEq)]
pub struct Estimate {
    /// The point estimate `ĝ`.
    pub value: f64,
    /// `z_k` per replica, indexed by seed.
    influence: Vec<f64>,
    /// Variance not resampled by the replicas.
    extra_variance: f64,
}

impl Estimate {
    /// The mean of per-replica `samples` (indexed by seed).
    pub fn mean(samples: &[f64]) -> Estimate {
        Estimate {
            value: samples.iter().sum::<f64>() / samples.len().max(1) as f64,
            influence: samples.to_vec(),
            extra_variance: 0.0,
        }
    }

    /// `ĝ − c` for a constant `c` known with variance `variance` (independent of the replicas).
    pub fn minus_constant(mut self, c: f64, variance: f64) -> Estimate {
        self.value -= c;
        self.extra_variance += variance;
        self
    }

    pub fn replicas(&self) -> usize {
        self.influence.len()
    }

    /// The influences by seed: for [`Estimate::mean`], the per-replica samples.
    pub fn influences(&self) -> &[f64] {
        &self.influence
    }

    /// `√Var(ĝ)`; `None` with fewer than 2 replicas or a non-finite value.
    pub fn std_err(&self) -> Option<f64> {
        let k = self.influence.len();
        if k < 2 || !self.value.is_finite() {
            return None;
        }
        let mean = self.influence.iter().sum::<f64>() / k as f64;
        let ss: f64 = self.influence.iter().map(|z| (z - mean) * (z - mean)).sum();
        let variance = ss / ((k - 1) * k) as f64 + self.extra_variance;
        variance.is_finite().then(|| variance.sqrt())
    }

    /// `ĝ ± t_{K−1}((1 + confidence)/2) · √Var(ĝ)`.
    pub fn interval(&self, confidence: f64) -> Option<Interval> {
        let se = self.std_err()?;
        let t = student_t_quantile(0.5 + 0.5 * confidence, (self.replicas() - 1) as f64);
        Some(Interval {
            lo: self.value - t * se,
            hi: self.value + t * se,
        })
    }

    /// The interval of `exp(ĝ)` from that of `ĝ` (for estimates on the log scale).
    pub fn exp_interval(&self, confidence: f64) -> Option<Interval> {
        let i = self.interval(confidence)?;
        Some(Interval {
            lo: i.lo.exp(),
            hi: i.hi.exp(),
        })
    }

    /// `ln ĝ` (influences `z_k / ĝ`); `None` unless `ĝ` is positive and finite.
    pub fn ln(&self) -> Option<Estimate> {
        let g = self.value;
        (g > 0.0 && g.is_finite()).then(|| Estimate {
            value: g.ln(),
            influence: self.influence.iter().map(|z| z / g).collect(),
            extra_variance: self.extra_variance / (g * g),
        })
    }

    /// `ĝ₁ + ĝ₂`, paired by seed; `None` when the replica counts differ.
    pub fn plus(&self, other: &Estimate) -> Option<Estimate> {
        self.combine(other, 1.0)
    }

    /// `ĝ₁ − ĝ₂`, paired by seed; `None` when the replica counts differ.
    pub fn minus(&self, other: &Estimate) -> Option<Estimate> {
        self.combine(other, -1.0)
    }

    fn combine(&self, other: &Estimate, sign: f64) -> Option<Estimate> {
        (self.replicas() == other.replicas()).then(|| Estimate {
            value: self.value + sign * other.value,
            influence: self
                .influence
                .iter()
                .zip(&other.influence)
                .map(|(a, b)| a + sign * b)
                .collect(),
            extra_variance: self.extra_variance + other.extra_variance,
        })
    }
}

/// A cost `MSE · seconds per frame` on the log scale: `ln M + ln T`, the denominator of the
/// efficiency `1 / (MSE · s)`; `None` unless both are positive.
pub fn log_cost(mse: &Estimate, seconds: &Estimate) -> Option<Estimate> {
    mse.ln()?.plus(&seconds.ln()?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use restir::rng::{Stream, StreamKey};

    /// Hand-computed: samples {1, 2, 3, 6} have mean 3, sample variance 14/3, s.e. √(14/12);
    /// t_3(0.975) = 3.182446305284263.
    #[test]
    fn a_mean_has_the_student_t_interval() {
        let e = Estimate::mean(&[1.0, 2.0, 3.0, 6.0]);
        assert_eq!(e.value, 3.0);
        let se = (14.0f64 / 12.0).sqrt();
        assert!((e.std_err().unwrap() - se).abs() < 1e-12);
        let i = e.interval(0.95).unwrap();
        assert!((i.hi - 3.0 - 3.182446305284263 * se).abs() < 1e-9, "{i:?}");
        assert!((i.lo + i.hi - 6.0).abs() < 1e-12);
        // A constant known with variance v widens it: Var = 14/12 + v.
        let shifted = e.clone().minus_constant(1.0, 0.5);
        assert_eq!(shifted.value, 2.0);
        assert!((shifted.std_err().unwrap() - (14.0f64 / 12.0 + 0.5).sqrt()).abs() < 1e-12);
        assert_eq!(Estimate::mean(&[2.0]).interval(0.95), None, "one replica");
        assert!(Estimate::mean(&[-1.0, 1.0]).ln().is_none());
        assert!(e.plus(&Estimate::mean(&[1.0, 2.0])).is_none(), "unpaired");
    }

    /// Pairing: the difference of two estimates that share their noise replica by replica has
    /// no variance, while the sum has twice the spread.
    #[test]
    fn paired_estimates_cancel_shared_noise() {
        let a = Estimate::mean(&[1.0, 2.0, 4.0, 5.0]);
        let b = Estimate::mean(&[11.0, 12.0, 14.0, 15.0]);
        let d = b.minus(&a).unwrap();
        assert_eq!(d.value, 10.0);
        assert_eq!(d.std_err(), Some(0.0));
        let s = a.plus(&b).unwrap();
        assert!((s.std_err().unwrap() - 2.0 * a.std_err().unwrap()).abs() < 1e-12);
    }

    fn normal(s: &mut Stream) -> f64 {
        let radius = (-2.0 * (1.0 - s.next_f64()).ln()).sqrt();
        radius * (std::f64::consts::TAU * s.next_f64()).cos()
    }

    /// K synthetic replicas of one method: MSE `μ · χ²_ν/ν` (ν = 16, CV 0.35, the spread of a
    /// ReSTIR region's MSE over replicas) and seconds `τ · exp(σN − σ²/2)` (σ = 0.3, a loaded
    /// machine), whose means are μ and τ.
    fn replicas(s: &mut Stream, k: usize, mu: f64, tau: f64) -> (Vec<f64>, Vec<f64>) {
        const NU: usize = 16;
        const SIGMA: f64 = 0.3;
        (0..k)
            .map(|_| {
                let chi2: f64 = (0..NU).map(|_| normal(s).powi(2)).sum();
                let t = tau * (SIGMA * normal(s) - 0.5 * SIGMA * SIGMA).exp();
                (mu * chi2 / NU as f64, t)
            })
            .unzip()
    }

    /// How often the 95% interval of the efficiency ratio `(M_b T_b)/(M_m T_m)` covers the
    /// true ratio in `n` synthetic comparisons of K = 8 replicas; `with_timing = false` is the
    /// negative control that treats the measured times as exact.
    fn coverage(n: usize, with_timing: bool) -> usize {
        let mut s = StreamKey::new(0, 0, 0x434F_5645, 0).stream(5);
        let (mu_b, tau_b, mu_m, tau_m): (f64, f64, f64, f64) = (0.13, 0.002, 0.07, 0.02);
        let truth = (mu_b * tau_b / (mu_m * tau_m)).ln();
        (0..n)
            .filter(|_| {
                let (eb, tb) = replicas(&mut s, 8, mu_b, tau_b);
                let (em, tm) = replicas(&mut s, 8, mu_m, tau_m);
                let time = |t: &[f64]| {
                    if with_timing {
                        Estimate::mean(t)
                    } else {
                        Estimate::mean(&vec![t.iter().sum::<f64>() / t.len() as f64; t.len()])
                    }
                };
                let b = log_cost(&Estimate::mean(&eb), &time(&tb)).unwrap();
                let m = log_cost(&Estimate::mean(&em), &time(&tm)).unwrap();
                let i = b.minus(&m).unwrap().interval(CONFIDENCE).unwrap();
                i.lo <= truth && truth <= i.hi
            })
            .count()
    }

    /// Calibration of the efficiency ratio's 95% interval (α = 0.05) on synthetic replicas:
    /// the claim is coverage ≥ 0.95 − δ, δ = 0.02. Decision: the count of covering intervals in
    /// N trials must reach the lower end of the 99.8% acceptance region of Binomial(N, 0.93), so
    /// a procedure with exactly 0.93 coverage fails with probability ≤ 0.001. N = 4000 from the
    /// power calculation N ≥ ((z·√(0.93·0.07) + z·√(0.90·0.10)) / 0.03)² ≈ 3270 (z = z_0.999
    /// = 3.09): a procedure with coverage 0.90 passes with probability ≤ 0.001. The negative
    /// control near δ, which ignores the spread of the timings, must fail (its coverage here is
    /// 0.88; the interval's is 0.944), and the interval must not be uselessly wide (coverage
    /// below 0.99).
    #[test]
    fn the_efficiency_ratio_interval_covers_at_its_level() {
        const N: usize = 4000;
        let (lo, _) = restir::stats::binomial_interval(N, 0.93, 0.998);
        let (_, hi) = restir::stats::binomial_interval(N, 0.99, 0.998);
        let covered = coverage(N, true);
        assert!(
            (lo..=hi).contains(&covered),
            "coverage {covered}/{N}, accepted {lo}..={hi}"
        );
        let control = coverage(N, false);
        assert!(
            control < lo,
            "negative control covered {control}/{N} ≥ {lo}"
        );
    }
}
