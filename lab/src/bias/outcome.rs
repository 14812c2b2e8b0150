//! What a bias test ([`super::run`]) found, as typed data that serialises to the JSON of
//! `reshift bias --json` (schema [`SCHEMA`], docs/results-schema.md): one source for the program's
//! output and its documentation. Non-finite numbers are written as `null`, never NaN; keys are
//! written in sorted order ([`BiasOutcome::to_json`]).

use restir::stats::Verdict;
use serde::{Serialize, Serializer};

use super::{BiasRow, Protocol, Unplannable};

/// The schema name written into [`BiasOutcome::schema`].
pub const SCHEMA: &str = "reshift-bias/4";

/// The power for which a bias test plans the replicas a method needs ([`super::replicas_needed`]).
pub const PLANNED_POWER: f64 = 0.9;

/// A finished (or stopped) bias test: the plan it ran, its rows and verdicts.
#[derive(Clone, Debug, Serialize)]
pub struct BiasOutcome {
    pub schema: &'static str,
    pub scene: String,
    /// The method under test, as requested.
    pub method: String,
    /// `WxH`.
    pub resolution: String,
    /// Frames of the camera trajectory; the last one is tested.
    pub frames: u32,
    /// Replicas rendered: fewer than planned when a stop request ended the test.
    pub replicas: usize,
    /// The seed of the first replica: replica k ran with seed `first_seed + k`.
    pub first_seed: u64,
    pub delta: f64,
    pub alpha: f64,
    /// `1 − alpha`, each CI's confidence.
    pub confidence: f64,
    pub reference: ReferenceEntry,
    pub nonfinite: NonFinite,
    /// Whether a stop request ended the replicas before every one was rendered.
    pub interrupted: bool,
    /// Over all rows ([`super::overall`]).
    #[serde(serialize_with = "verdict_name")]
    pub verdict: Verdict,
    pub planned: Planned,
    /// Per non-empty region and channel, in table order.
    pub rows: Vec<BiasRow>,
    /// The group-sequential design of a budgeted test; `null` for a fixed N.
    pub sequential: Option<SequentialEntry>,
}

/// How a budgeted test ([`super::Replicas::Budget`]) spent its budget and looked at its rows.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SequentialEntry {
    /// The α spending function: `lan-demets-obrien-fleming` (`super::sequential::spent`).
    pub spending: &'static str,
    /// What the budget and the times count: `process CPU time` or `wall time`.
    pub clock: &'static str,
    pub budget_seconds: f64,
    /// Seconds used by the whole test (regions, reference, replicas).
    pub used_seconds: f64,
    /// Measured cost of one replica and of one reference batch.
    pub seconds_per_replica: f64,
    pub seconds_per_reference_batch: f64,
    /// Replicas rendered before the design was planned (part of the sample).
    pub pilot: usize,
    /// The bound on the reference's share of a planned row's CI half-width,
    /// `z_{1−α/2}·se_r/r̄ ≤ δ/4`.
    pub reference_target: f64,
    /// Replicas at the last planned look (0 when no row is planned for).
    pub n_max: usize,
    /// The planned looks, in order.
    pub looks: Vec<LookEntry>,
    /// Per row of [`BiasOutcome::rows`], in the same order.
    pub rows: Vec<RowDesign>,
}

/// One planned look of the sequential design.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct LookEntry {
    /// Replicas at the look.
    pub n: usize,
    /// The level it spends, `α(t_k) − α(t_{k−1})`.
    pub level: f64,
    /// Whether it was taken (not if every row was decided before, or the budget ran out).
    pub taken: bool,
    /// Rows it decided.
    pub equivalent: usize,
    pub biased: usize,
}

/// How the sequential design treated one row.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct RowDesign {
    pub region: &'static str,
    pub channel: &'static str,
    /// Whether `n_max` and the reference were planned to decide this row; a row whose reference
    /// or replicas would not fit the budget is not (it is tested all the same).
    pub planned: bool,
    /// The look (1-based) that decided the row.
    pub look: Option<usize>,
    /// For a row not decided: what a test of it alone would need.
    pub needs: Option<Needs>,
}

/// What a test deciding one row would need, with power [`PLANNED_POWER`] if it had no bias;
/// `null` fields when it cannot be planned (no spread, or more than `crate::limits::MAX_REPLICAS`
/// replicas or reference batches).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Needs {
    pub replicas: Option<usize>,
    pub reference_batches: Option<u32>,
    /// On the budget's clock, from the measured seconds per replica and per batch.
    pub minutes: Option<f64>,
}

/// The path-traced reference the replicas were tested against.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ReferenceEntry {
    /// Independent batches.
    pub batches: u32,
    pub spp_per_batch: u32,
    /// The SSS profile of the path tracer: the method's own (`methods::Method::reference`).
    pub profile: String,
    pub seed: u64,
}

/// Shaded values that were NaN or infinite (a bias either way, which the test must not hide).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct NonFinite {
    pub replicas: u64,
    pub reference: u64,
}

/// The replicas a run like this one would need ([`super::replicas_needed`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Planned {
    /// [`PLANNED_POWER`].
    pub power: f64,
    /// `null` in the JSON when there is no answer; the reason stays here for the table.
    #[serde(serialize_with = "ok_or_null")]
    pub replicas: Result<usize, Unplannable>,
}

impl BiasOutcome {
    /// The tolerance and level the rows were tested at.
    pub fn protocol(&self) -> Protocol {
        Protocol {
            delta: self.delta,
            alpha: self.alpha,
        }
    }

    /// The outcome as a JSON value (object keys sorted).
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::to_value(self).expect("plain data serializes")
    }

    /// [`BiasOutcome::to_json`] pretty-printed, as `reshift bias --json` prints it.
    pub fn to_json_pretty(&self) -> String {
        serde_json::to_string_pretty(&self.to_json()).expect("JSON values")
    }
}

/// One row of the JSON: a [`BiasRow`] without its method (the outcome's).
#[derive(Serialize)]
struct RowEntry {
    region: &'static str,
    channel: &'static str,
    pixels: usize,
    n: usize,
    mean: f64,
    reference_mean: f64,
    reference_std_err: f64,
    relative_bias: f64,
    ci_low: f64,
    ci_high: f64,
    ci_half_width: f64,
    p_zero_bias: f64,
    holm_rejected: bool,
    verdict: &'static str,
}

impl Serialize for BiasRow {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let e = &self.equivalence;
        RowEntry {
            region: self.region.name(),
            channel: self.channel.name(),
            pixels: self.pixels,
            n: e.n,
            mean: self.estimate.mean,
            reference_mean: self.reference.mean,
            reference_std_err: self.reference.std_err,
            relative_bias: e.relative_bias,
            ci_low: e.ci_low,
            ci_high: e.ci_high,
            ci_half_width: self.ci_half_width(),
            p_zero_bias: e.p_zero_bias,
            holm_rejected: self.holm_rejected,
            verdict: self.verdict.name(),
        }
        .serialize(serializer)
    }
}

fn verdict_name<S: Serializer>(verdict: &Verdict, serializer: S) -> Result<S::Ok, S::Error> {
    serializer.serialize_str(verdict.name())
}

fn ok_or_null<S: Serializer>(
    planned: &Result<usize, Unplannable>,
    serializer: S,
) -> Result<S::Ok, S::Error> {
    planned.as_ref().ok().serialize(serializer)
}
