//! The equivalence test: the only test that may call an estimator's bias negligible, by showing it
//! lies within ±δ (DESIGN §3).

use std::fmt;

use super::special::student_t_quantile;
use super::summary::Summary;
use super::welch::{satterthwaite, welch};

/// Outcome of [`equivalence`].
///
/// With `CI` the two-sided `confidence` interval of the relative bias and
/// `p_zero_bias` the Welch p-value of "no bias" (α = 1 − confidence):
/// * `Equivalent` ⇔ `CI ⊂ (−δ, +δ)`: the bias is shown to lie within ±δ at that confidence,
///   which is all a finite number of replicas can show (not "unbiased");
/// * `Biased` ⇔ not `Equivalent`, and `CI ∩ [−δ, δ] = ∅` or `p_zero_bias < α`
///   (a significant bias that is not shown to be within tolerance);
/// * `Inconclusive` otherwise (too few replicas, too much variance, or none at all to decide).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    Equivalent,
    Biased,
    Inconclusive,
}

impl Verdict {
    /// `equivalent`, `biased` or `inconclusive` (the word of JSON outputs).
    pub fn name(self) -> &'static str {
        match self {
            Verdict::Equivalent => "equivalent",
            Verdict::Biased => "biased",
            Verdict::Inconclusive => "inconclusive",
        }
    }

    /// What the verdict claims, e.g. `equivalent within ±2% at 99%`, `biased`, `inconclusive`.
    pub fn describe(self, delta: f64, confidence: f64) -> String {
        match self {
            Verdict::Equivalent => format!(
                "equivalent within ±{}% at {}%",
                percent(delta),
                percent(confidence)
            ),
            v => v.name().to_string(),
        }
    }
}

/// Equivalence test of the relative bias `(estimate − reference)/reference`; see [`Verdict`]
/// for the decision rule and [`equivalence`] for the interval.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Equivalence {
    /// Replicas of the estimate.
    pub n: usize,
    pub relative_bias: f64,
    pub ci_low: f64,
    pub ci_high: f64,
    /// Tolerance δ on the relative bias.
    pub delta: f64,
    pub confidence: f64,
    pub p_zero_bias: f64,
    pub verdict: Verdict,
}

/// Tests the relative bias of `estimate` against `reference` with tolerance `delta` at
/// `confidence` (e.g. 0.99).
///
/// The interval is `b ± t_{(1+c)/2, ν} · s` with `b = ē/r̄ − 1` and the delta-method variance
/// `s² = se_e²/r̄² + (ē·se_r/r̄²)²`, which propagates the reference's own standard error;
/// `ν` is the Welch–Satterthwaite dof of those two terms.
///
/// Edge cases (never NaN):
/// * a reference mean of 0 or ±∞ has no relative scale: `relative_bias` is ±∞ (0 if the
///   means are equal), the CI is (−∞, ∞), so the verdict is `Biased` if Welch rejects zero
///   bias and `Inconclusive` otherwise;
/// * a non-finite estimate mean (a NaN/∞ replica): bias and CI +∞ (or −∞), `Biased`;
/// * `confidence` outside (0, 1) gives an unbounded CI, hence never `Equivalent`;
/// * fewer than two replicas, or replicas that are all equal on either side
///   ([`Summary::no_spread`], e.g. a region black in every replica): the spread is unknown, so
///   the CI is unbounded, `p_zero_bias = 1` and the verdict `Inconclusive`, never `Biased`.
pub fn equivalence(
    estimate: &Summary,
    reference: &Summary,
    delta: f64,
    confidence: f64,
) -> Equivalence {
    let p_zero_bias = welch(estimate, reference).p_value;
    let (relative_bias, ci_low, ci_high) = relative_ci(estimate, reference, confidence);
    let verdict = if ci_low > -delta && ci_high < delta {
        Verdict::Equivalent
    } else if ci_low >= delta || ci_high <= -delta || p_zero_bias < 1.0 - confidence {
        Verdict::Biased
    } else {
        Verdict::Inconclusive
    };
    Equivalence {
        n: estimate.n,
        relative_bias,
        ci_low,
        ci_high,
        delta,
        confidence,
        p_zero_bias,
        verdict,
    }
}

/// `(b, ci_low, ci_high)` for the relative bias; see [`equivalence`].
fn relative_ci(estimate: &Summary, reference: &Summary, confidence: f64) -> (f64, f64, f64) {
    let (e, r) = (estimate.mean, reference.mean);
    let diff = e - r;
    if !diff.is_finite() {
        let b = if diff == f64::NEG_INFINITY {
            f64::NEG_INFINITY
        } else {
            f64::INFINITY
        };
        return (b, b, b);
    }
    if r == 0.0 || !r.is_finite() {
        let b = if diff == 0.0 {
            0.0
        } else {
            diff.signum() * f64::INFINITY
        };
        return (b, f64::NEG_INFINITY, f64::INFINITY);
    }
    let b = diff / r;
    if !b.is_finite() {
        return (b, b, b);
    }
    let v_estimate = (estimate.std_err / r).powi(2);
    let v_reference = (e * reference.std_err / (r * r)).powi(2);
    let variance = v_estimate + v_reference;
    let spread_unknown = estimate.no_spread() || reference.no_spread();
    let half = if spread_unknown || !(confidence > 0.0 && confidence < 1.0 && variance.is_finite())
    {
        f64::INFINITY
    } else if variance == 0.0 {
        0.0
    } else {
        let dof = satterthwaite(&[(v_estimate, estimate.n), (v_reference, reference.n)]);
        student_t_quantile(0.5 * (1.0 + confidence), dof) * variance.sqrt()
    };
    (b, b - half, b + half)
}

impl fmt::Display for Equivalence {
    /// E.g. `equivalent within ±1% at 99% (N = 64): bias +0.12% [-0.31%, +0.55%], p(bias = 0)
    /// = 0.412`, or `biased (δ = ±1%, 99% CI, N = 64): …`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let p = if self.p_zero_bias >= 1e-3 {
            format!("{:.3}", self.p_zero_bias)
        } else {
            format!("{:.1e}", self.p_zero_bias)
        };
        let design = match self.verdict {
            Verdict::Equivalent => format!(
                "{} (N = {})",
                self.verdict.describe(self.delta, self.confidence),
                self.n
            ),
            v => format!(
                "{} (δ = ±{}%, {}% CI, N = {})",
                v.name(),
                percent(self.delta),
                percent(self.confidence),
                self.n
            ),
        };
        write!(
            f,
            "{design}: bias {:+.2}% [{:+.2}%, {:+.2}%], p(bias = 0) = {p}",
            100.0 * self.relative_bias,
            100.0 * self.ci_low,
            100.0 * self.ci_high,
        )
    }
}

/// A fraction as a percentage with at most four decimals and no trailing zeros (0.01 → "1").
fn percent(x: f64) -> String {
    let s = format!("{:.4}", 100.0 * x);
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stats::special::binomial_interval;
    use crate::stats::testing::{normal, stream};

    /// `n` replicas of `mean · (1 + cv·√n · z)`: a summary whose standard error is ≈ `cv·mean`.
    fn replicas(seed: u64, n: usize, mean: f64, cv: f64) -> Summary {
        let mut s = stream(3, seed);
        let sigma = cv * mean * (n as f64).sqrt();
        let xs: Vec<f64> = (0..n).map(|_| mean + sigma * normal(&mut s)).collect();
        Summary::from_samples(&xs)
    }

    /// δ = 1%, 99% confidence, N = 200 replicas with s.e. ≈ 0.1% against an exact reference:
    /// a true bias of +0.1% is Equivalent, +5% (negative control) Biased, and the same +0.1%
    /// with s.e. ≈ 2% Inconclusive (no claim without evidence).
    #[test]
    fn verdicts_equivalent_biased_inconclusive() {
        let reference = Summary::exact(2.0);
        let small = equivalence(&replicas(1, 200, 2.002, 0.001), &reference, 0.01, 0.99);
        assert_eq!(small.verdict, Verdict::Equivalent, "{small}");
        assert!(small.ci_low < 0.001 && 0.001 < small.ci_high, "{small}");
        let large = equivalence(&replicas(2, 200, 2.1, 0.001), &reference, 0.01, 0.99);
        assert_eq!(large.verdict, Verdict::Biased, "{large}");
        assert!(large.ci_low > 0.01, "{large}");
        let noisy = equivalence(&replicas(3, 200, 2.002, 0.02), &reference, 0.01, 0.99);
        assert_eq!(noisy.verdict, Verdict::Inconclusive, "{noisy}");
        assert_eq!(small.n, 200);
        assert!(
            small
                .to_string()
                .starts_with("equivalent within ±1% at 99% (N = 200): bias +0."),
            "{small}"
        );
    }

    /// A significant bias inside a loose tolerance is Equivalent (equivalence, not difference);
    /// the same bias with a tight tolerance is Biased although the CI overlaps ±δ.
    #[test]
    fn significant_but_tolerable_bias() {
        let estimate = replicas(4, 400, 1.02, 0.002);
        let loose = equivalence(&estimate, &Summary::exact(1.0), 0.05, 0.99);
        assert_eq!(loose.verdict, Verdict::Equivalent, "{loose}");
        assert!(loose.p_zero_bias < 0.01, "{loose}");
        let tight = equivalence(&estimate, &Summary::exact(1.0), 0.02, 0.99);
        assert!(tight.ci_low < 0.02 && tight.ci_high > 0.02, "{tight}");
        assert_eq!(tight.verdict, Verdict::Biased, "{tight}");
    }

    /// Coverage of the 99% CI when the reference has its own noise (estimate: 50 replicas,
    /// s.e. 0.7%; reference: 30 replicas, s.e. 1.5%; true relative bias +2%), M = 1000
    /// experiments: the count of intervals missing +2% must lie in the binomial 99.9% interval
    /// of M·0.01. Negative control: the same interval treating the reference as exact misses
    /// far more often.
    #[test]
    fn ci_coverage_with_noisy_reference() {
        const M: usize = 1000;
        const CONFIDENCE: f64 = 0.99;
        let truth = 0.02;
        let (mut misses, mut misses_exact_reference) = (0, 0);
        for k in 0..M as u64 {
            let estimate = replicas(100 + 2 * k, 50, 1.0 + truth, 0.007);
            let reference = replicas(101 + 2 * k, 30, 1.0, 0.015);
            let (_, lo, hi) = relative_ci(&estimate, &reference, CONFIDENCE);
            misses += !(lo <= truth && truth <= hi) as usize;
            let pretend_exact = Summary {
                std_err: 0.0,
                ..reference
            };
            let (_, lo, hi) = relative_ci(&estimate, &pretend_exact, CONFIDENCE);
            misses_exact_reference += !(lo <= truth && truth <= hi) as usize;
        }
        let (lo, hi) = binomial_interval(M, 1.0 - CONFIDENCE, 0.999);
        assert!(
            (lo..=hi).contains(&misses),
            "{misses}/{M} misses of a 99% CI, interval [{lo}, {hi}]"
        );
        assert!(
            misses_exact_reference > hi,
            "control: {misses_exact_reference}/{M} misses, should exceed {hi}"
        );
    }

    /// Replicas that are all equal have no spread to test against: a region black in both of
    /// two replicas against a reference that is not black, or a constant estimate against a
    /// noisy reference, is Inconclusive with an unbounded CI, never Biased; so is a noisy
    /// estimate against a reference without spread. Control: the same means with spread are
    /// Biased.
    #[test]
    fn zero_variance_is_inconclusive_never_biased() {
        let black = Summary::from_samples(&[0.0, 0.0]);
        let reference = Summary::from_samples(&[0.010, 0.012, 0.011, 0.009]);
        let constant = Summary::from_samples(&[2.0; 50]);
        for (estimate, reference) in [
            (black, reference),
            (black, Summary::exact(0.011)),
            (constant, Summary::from_samples(&[1.0, 1.01, 0.99])),
            (Summary::from_samples(&[1.0, 1.01, 0.99]), constant),
        ] {
            let e = equivalence(&estimate, &reference, 0.02, 0.99);
            assert_eq!(e.verdict, Verdict::Inconclusive, "{e}");
            assert_eq!((e.ci_low, e.ci_high), (f64::NEG_INFINITY, f64::INFINITY));
            assert_eq!(e.p_zero_bias, 1.0, "{e}");
        }
        let spread = Summary::from_samples(&[1.99, 2.0, 2.01]);
        let control = equivalence(
            &spread,
            &Summary::from_samples(&[1.0, 1.01, 0.99]),
            0.02,
            0.99,
        );
        assert_eq!(control.verdict, Verdict::Biased, "{control}");
    }

    #[test]
    fn edge_cases_are_defined() {
        let zeros = Summary::from_samples(&[0.0; 8]);
        let at_zero = equivalence(&zeros, &Summary::exact(0.0), 0.01, 0.99);
        assert_eq!(
            (at_zero.relative_bias, at_zero.verdict),
            (0.0, Verdict::Inconclusive)
        );
        let off_zero = equivalence(
            &Summary::from_samples(&[1.0, 1.1, 0.9]),
            &Summary::exact(0.0),
            0.01,
            0.99,
        );
        assert_eq!(
            (off_zero.relative_bias, off_zero.verdict),
            (f64::INFINITY, Verdict::Biased)
        );
        let broken = equivalence(
            &Summary::from_samples(&[1.0, f64::NAN]),
            &Summary::exact(1.0),
            0.01,
            0.99,
        );
        assert_eq!(broken.verdict, Verdict::Biased);
        let one = equivalence(
            &Summary::from_samples(&[1.0]),
            &Summary::exact(1.0),
            0.01,
            0.99,
        );
        assert_eq!(one.verdict, Verdict::Inconclusive);
        let exact = equivalence(&Summary::exact(1.0), &Summary::exact(1.0), 0.01, 1.5);
        assert_eq!(exact.verdict, Verdict::Inconclusive);
        for e in [at_zero, off_zero, broken, one, exact] {
            let fields = [e.relative_bias, e.ci_low, e.ci_high, e.p_zero_bias];
            assert!(fields.iter().all(|x| !x.is_nan()), "{e:?}");
        }
    }
}
