//! The bias of an estimator B known through a chain: A's bias against the reference, measured
//! with many replicas, and B's paired difference from A, measured with few (DESIGN §3
//! "Statistics"). The use: B is the Vulkan backend, whose replicas cost a hundred times the
//! CPU's on lavapipe, and A the CPU backend, which runs the same seeds.
//!
//! * Estimand, per region and channel: `β_B = (1 + β_A)(1 + b) − 1`, with `β_A` the relative
//!   bias of A ([`crate::bias::bias_rows`]) and `b` the relative difference of the expectations
//!   B − A ([`crate::bias::paired_rows`]).
//! * Interval: `[(1 + l_A)(1 + l_b) − 1, (1 + h_A)(1 + h_b) − 1]` from the two CIs (the map is
//!   increasing in both factors where they are positive). Both statements hold together with
//!   probability at least `1 − α_A − α_b` (Bonferroni, whatever their dependence: the pairs reuse
//!   A's first replicas), so the interval's confidence is `1 − α_A − α_b`.
//! * Verdict: `Equivalent` ⇔ the interval lies inside ±δ; `Biased` ⇔ it lies outside [−δ, δ];
//!   `Inconclusive` otherwise. The chain has no zero-bias p-value (`p_zero_bias` is 1 and Holm
//!   rejects nothing): a bias is called only when its whole interval is beyond δ.

use restir::stats::{Equivalence, Summary, Verdict};

use crate::bias::{BiasRow, Protocol};

/// The chained rows of `method`: for every row of `first` (A against the reference) the row of
/// `then` (B − A, paired) with the same region and channel; a row without its partner is
/// `Inconclusive` with an unbounded interval. δ is `first`'s.
pub fn chained_rows(method: &str, first: &[BiasRow], then: &[BiasRow]) -> Vec<BiasRow> {
    first
        .iter()
        .map(|a| {
            let b = then
                .iter()
                .find(|b| b.region == a.region && b.channel == a.channel);
            let (ea, delta) = (&a.equivalence, a.equivalence.delta);
            let (relative_bias, ci_low, ci_high, confidence, estimate) = match b {
                Some(b) => {
                    let eb = &b.equivalence;
                    let chain = |x: f64, y: f64| (1.0 + x) * (1.0 + y) - 1.0;
                    (
                        chain(ea.relative_bias, eb.relative_bias),
                        chain(ea.ci_low, eb.ci_low),
                        chain(ea.ci_high, eb.ci_high),
                        ea.confidence + eb.confidence - 1.0,
                        b.estimate,
                    )
                }
                None => (
                    f64::INFINITY,
                    f64::NEG_INFINITY,
                    f64::INFINITY,
                    ea.confidence,
                    Summary::from_samples(&[]),
                ),
            };
            let protocol = Protocol {
                delta,
                alpha: 1.0 - confidence,
            };
            let mut equivalence = Equivalence {
                n: estimate.n,
                relative_bias,
                ci_low,
                ci_high,
                delta,
                confidence,
                p_zero_bias: 1.0,
                verdict: Verdict::Inconclusive,
            };
            equivalence.verdict = protocol.verdict(&equivalence, false);
            BiasRow {
                method: method.to_string(),
                region: a.region,
                channel: a.channel,
                pixels: a.pixels,
                estimate,
                reference: a.reference,
                verdict: equivalence.verdict,
                equivalence,
                holm_rejected: false,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bias::Channel;
    use crate::regions::Region;

    /// A row with relative bias `b` and CI `[lo, hi]` at `confidence`, δ = 2%.
    fn row(channel: Channel, b: f64, lo: f64, hi: f64, confidence: f64) -> BiasRow {
        let summary = Summary::from_samples(&[1.0, 2.0]);
        BiasRow {
            method: "m".into(),
            region: Region::Lit,
            channel,
            pixels: 10,
            estimate: summary,
            reference: summary,
            equivalence: Equivalence {
                n: 2,
                relative_bias: b,
                ci_low: lo,
                ci_high: hi,
                delta: 0.02,
                confidence,
                p_zero_bias: 0.5,
                verdict: Verdict::Inconclusive,
            },
            holm_rejected: false,
            verdict: Verdict::Inconclusive,
        }
    }

    #[test]
    fn the_interval_is_the_product_of_the_two_and_its_confidence_their_bonferroni_bound() {
        let a = [row(Channel::Red, 0.01, 0.005, 0.015, 0.991)];
        let b = [row(Channel::Red, 0.001, -0.001, 0.003, 0.999)];
        let c = &chained_rows("chain", &a, &b)[0];
        let e = &c.equivalence;
        assert!((e.relative_bias - (1.01 * 1.001 - 1.0)).abs() < 1e-15);
        assert!((e.ci_low - (1.005 * 0.999 - 1.0)).abs() < 1e-15);
        assert!((e.ci_high - (1.015 * 1.003 - 1.0)).abs() < 1e-15);
        assert!((e.confidence - 0.99).abs() < 1e-12);
        assert_eq!(c.verdict, Verdict::Equivalent);
        assert!(!c.holm_rejected);
    }

    /// Each factor alone inside ±δ does not make the chain equivalent: the two add up.
    #[test]
    fn two_intervals_inside_delta_can_chain_to_one_outside() {
        let a = [row(Channel::Blue, 0.015, 0.012, 0.018, 0.991)];
        let b = [row(Channel::Blue, 0.004, 0.003, 0.005, 0.999)];
        let c = &chained_rows("chain", &a, &b)[0];
        assert_eq!(c.verdict, Verdict::Inconclusive, "{:?}", c.equivalence);
        let b = [row(Channel::Blue, 0.02, 0.015, 0.025, 0.999)];
        assert_eq!(chained_rows("chain", &a, &b)[0].verdict, Verdict::Biased);
    }

    #[test]
    fn a_row_without_its_partner_is_inconclusive() {
        let a = [row(Channel::Green, 0.0, -0.001, 0.001, 0.991)];
        let b = [row(Channel::Red, 0.0, -0.001, 0.001, 0.999)];
        let c = &chained_rows("chain", &a, &b)[0];
        assert_eq!(c.verdict, Verdict::Inconclusive);
        assert_eq!(c.equivalence.ci_low, f64::NEG_INFINITY);
    }
}
