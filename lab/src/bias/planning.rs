//! How many replicas a bias test needs for every row to be decided equivalent within ±δ
//! ([`replicas_needed`]), planned from a finished run's spreads.

use std::fmt;

use restir::stats::{EquivalencePlan, Summary, replicas_for};

use super::{BiasRow, Channel, Protocol};
use crate::regions::Region;

/// Why [`replicas_needed`] has no answer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Unplannable {
    /// The row's replicas are all equal or its mean is 0: its per-replica CV is unknown.
    NoSpread { region: Region, channel: Channel },
    /// The reference's own relative error in this row (its largest) leaves no room for ±δ
    /// however many replicas run.
    Reference {
        region: Region,
        channel: Channel,
        rel_se: f64,
    },
}

impl fmt::Display for Unplannable {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Unplannable::NoSpread { region, channel } => {
                write!(f, "no per-replica CV in {region} {channel} (no spread)")
            }
            Unplannable::Reference {
                region,
                channel,
                rel_se,
            } => write!(
                f,
                "the reference's own error ({:.2}% in {region} {channel}) leaves no room; more reference samples",
                100.0 * rel_se
            ),
        }
    }
}

/// The replicas a run like this one would need for every row to be equivalent within ±δ with
/// probability at least `power` if the method had no bias (Bonferroni over the rows), planned
/// ([`replicas_for`]) from each row's per-replica CV and its reference's relative standard
/// error.
pub fn replicas_needed(
    rows: &[BiasRow],
    protocol: &Protocol,
    power: f64,
) -> Result<usize, Unplannable> {
    let relative = |s: &Summary, spread: f64| {
        let rel = spread / s.mean.abs();
        (rel.is_finite() && !s.no_spread()).then_some(rel)
    };
    let no_spread = |r: &BiasRow| Unplannable::NoSpread {
        region: r.region,
        channel: r.channel,
    };
    let tests: Vec<(EquivalencePlan, f64)> = rows
        .iter()
        .map(|r| {
            let cv = relative(&r.estimate, r.estimate.variance.sqrt()).ok_or(no_spread(r))?;
            let plan = EquivalencePlan {
                delta: protocol.delta,
                alpha: protocol.alpha,
                reference_rel_se: relative(&r.reference, r.reference.std_err)
                    .ok_or(no_spread(r))?,
                reference_n: r.reference.n,
            };
            Ok((plan, cv))
        })
        .collect::<Result<_, _>>()?;
    replicas_for(&tests, power, 1 << 30).ok_or_else(|| {
        let (row, (plan, _)) = rows
            .iter()
            .zip(&tests)
            .max_by(|a, b| a.1.0.reference_rel_se.total_cmp(&b.1.0.reference_rel_se))
            .expect("replicas_for has an answer for no rows");
        Unplannable::Reference {
            region: row.region,
            channel: row.channel,
            rel_se: plan.reference_rel_se,
        }
    })
}
