//! What `reshift bias` prints: the overall verdict in words and the JSON of the test
//! (schema `reshift-bias/2`, docs/results-schema.md).

use lab::bias::{BiasRow, Protocol, overall};
use lab::reference_cache::REFERENCE_SEED;
use restir::stats::Verdict;
use serde_json::{Value, json};

use super::bias::{BiasArgs, PLANNED_POWER};
use super::common::json_number;

/// The overall verdict in words: `equivalent within ±δ at 99% in every region and channel`,
/// `biased (in k of n rows)` or `inconclusive (k of n rows not decided)`.
pub(super) fn verdict_line(rows: &[BiasRow], protocol: &Protocol) -> String {
    let count = |v| rows.iter().filter(|r| r.verdict == v).count();
    let verdict = overall(rows);
    match verdict {
        Verdict::Equivalent => {
            format!("{} in every region and channel", protocol.describe(verdict))
        }
        Verdict::Biased => format!("biased (in {} of {} rows)", count(verdict), rows.len()),
        Verdict::Inconclusive => format!(
            "inconclusive ({} of {} rows not decided)",
            count(verdict),
            rows.len()
        ),
    }
}

/// JSON of the bias test (schema `reshift-bias/2`, docs/results-schema.md).
pub(super) fn bias_json(
    args: &BiasArgs,
    scene: &str,
    rows: &[BiasRow],
    planned: Option<usize>,
    profile: &str,
    [replica_nonfinite, reference_nonfinite]: [u64; 2],
    replicas: usize,
    interrupted: bool,
) -> Value {
    let verdict = overall(rows);
    let rows: Vec<Value> = rows
        .iter()
        .map(|r| {
            let e = &r.equivalence;
            json!({
                "region": r.region.name(),
                "channel": r.channel.name(),
                "pixels": r.pixels,
                "n": e.n,
                "mean": json_number(r.estimate.mean),
                "reference_mean": json_number(r.reference.mean),
                "reference_std_err": json_number(r.reference.std_err),
                "relative_bias": json_number(e.relative_bias),
                "ci_low": json_number(e.ci_low),
                "ci_high": json_number(e.ci_high),
                "ci_half_width": json_number(r.ci_half_width()),
                "p_zero_bias": json_number(e.p_zero_bias),
                "holm_rejected": r.holm_rejected,
                "verdict": r.verdict.name(),
            })
        })
        .collect();
    json!({
        "schema": "reshift-bias/2",
        "scene": scene,
        "method": args.method,
        "resolution": args.resolution,
        "frames": args.frames,
        "replicas": replicas,
        "delta": args.delta,
        "alpha": args.alpha,
        "confidence": 1.0 - args.alpha,
        "reference": {
            "batches": args.reference_batches,
            "spp_per_batch": args.reference_batch_spp,
            "profile": profile,
            "seed": REFERENCE_SEED,
        },
        "nonfinite": { "replicas": replica_nonfinite, "reference": reference_nonfinite },
        "interrupted": interrupted,
        "verdict": verdict.name(),
        "planned": { "power": PLANNED_POWER, "replicas": planned },
        "rows": rows,
    })
}
