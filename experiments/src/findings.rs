//! Paper 001's qualitative findings and whether measured numbers reproduce them, decided by
//! confidence intervals, never by point estimates: each experiment states its findings as
//! [`Finding`]s and writes them as a table ([`markdown`]).
//!
//! A finding is a claim that each of n quantities lies on one side of a threshold (a ratio of
//! two methods' MSE or cost below 1, a difference above 0). Its intervals are taken at
//! confidence `1 − (1 − CONFIDENCE)/n` (Bonferroni), so the family is decided at [`CONFIDENCE`]:
//! it **holds** when every interval lies on the claimed side, **fails** when some interval lies
//! entirely on the other side, and is **inconclusive** otherwise.

use lab::method_result::MethodResult;
use lab::metrics::Area;
use lab::regions::Region;
use lab::report::tables::sig;
use lab::uncertainty::{CONFIDENCE, Estimate};

/// What the measurements say of a claim.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    Holds,
    Fails,
    /// An interval contains the threshold.
    Inconclusive,
    /// A quantity cannot be measured (an empty region, an MSE not above the reference noise,
    /// replicas that do not pair).
    NotApplicable,
}

/// One qualitative finding of paper 001 and what the measured numbers say of it.
#[derive(Clone, Debug, PartialEq)]
pub struct Finding {
    pub claim: String,
    pub verdict: Verdict,
    /// The quantities with their intervals.
    pub measured: String,
}

/// One quantity of a claim, on the log scale for ratios: `(label, estimate)`.
pub type Quantity = (String, Option<Estimate>);

/// The claim that every quantity lies below `threshold` (on the scale of the estimates: 0 for
/// log ratios), decided by Bonferroni-corrected intervals (module documentation); a measured
/// failure decides even when another quantity cannot be measured. `log`: the estimates are
/// logarithms, reported as ratios.
pub fn all_below(claim: String, quantities: &[Quantity], threshold: f64, log: bool) -> Finding {
    decide(claim, quantities, threshold, log, -1.0)
}

/// The claim that every quantity lies above `threshold` (see [`all_below`]).
pub fn all_above(claim: String, quantities: &[Quantity], threshold: f64, log: bool) -> Finding {
    decide(claim, quantities, threshold, log, 1.0)
}

/// [`all_below`] (`side` −1) or [`all_above`] (`side` +1).
fn decide(claim: String, quantities: &[Quantity], threshold: f64, log: bool, side: f64) -> Finding {
    let n = quantities.len().max(1) as f64;
    let confidence = 1.0 - (1.0 - CONFIDENCE) / n;
    let show = |v: f64| sig(if log { v.exp() } else { v });
    let (mut failed, mut missing, mut open) = (false, false, false);
    let mut measured = Vec::new();
    for (label, estimate) in quantities {
        match estimate
            .as_ref()
            .and_then(|e| Some((e.value, e.interval(confidence)?)))
        {
            None => {
                missing = true;
                measured.push(format!("{label} n/a"));
            }
            Some((value, i)) => {
                // The interval on the claimed side, on the other side, or across the threshold.
                let (claimed, other) = if side < 0.0 {
                    (i.below(threshold), i.above(threshold))
                } else {
                    (i.above(threshold), i.below(threshold))
                };
                failed |= other;
                open |= !claimed;
                measured.push(format!(
                    "{label} {} [{}, {}]",
                    show(value),
                    show(i.lo),
                    show(i.hi)
                ));
            }
        }
    }
    let verdict = match (failed, missing, open) {
        (true, _, _) => Verdict::Fails,
        (false, true, _) => Verdict::NotApplicable,
        (false, false, true) => Verdict::Inconclusive,
        (false, false, false) => Verdict::Holds,
    };
    Finding {
        claim,
        verdict,
        measured: format!(
            "{} ({:.1}% intervals, {:.0}% family-wise)",
            measured.join("; "),
            100.0 * confidence,
            100.0 * CONFIDENCE
        ),
    }
}

/// The row of `method`.
pub fn row<'a>(rows: &'a [MethodResult], method: &str) -> Option<&'a MethodResult> {
    rows.iter().find(|r| r.method == method)
}

/// `ln(MSE(a) / MSE(b))` in `region` (paired): below 0 when `a` has the lower error.
pub fn log_mse_ratio(rows: &[MethodResult], a: &str, b: &str, region: Region) -> Option<Estimate> {
    row(rows, a)?.log_mse_ratio(row(rows, b)?, Area::Region(region))
}

/// `ln((MSE·s)(a) / (MSE·s)(b))` in `region` (paired): below 0 when `a` is more efficient.
pub fn log_cost_ratio(rows: &[MethodResult], a: &str, b: &str, region: Region) -> Option<Estimate> {
    row(rows, a)?.log_cost_ratio(row(rows, b)?, Area::Region(region))
}

/// The quantity "MSE a/b" of [`log_mse_ratio`].
pub fn mse_below(rows: &[MethodResult], a: &str, b: &str, region: Region) -> Quantity {
    (
        format!("MSE {}/{}", short(a), short(b)),
        log_mse_ratio(rows, a, b, region),
    )
}

/// The quantity "MSE·s a/b" of [`log_cost_ratio`].
pub fn cost_below(rows: &[MethodResult], a: &str, b: &str, region: Region) -> Quantity {
    (
        format!("MSE·s {}/{}", short(a), short(b)),
        log_cost_ratio(rows, a, b, region),
    )
}

/// The quantities "MSE best/other" in `region` for every other method of `methods`: all below 1
/// when `best` has the lowest error of them.
pub fn lowest_of(
    rows: &[MethodResult],
    best: &str,
    methods: &[&str],
    region: Region,
) -> Vec<Quantity> {
    methods
        .iter()
        .filter(|&&m| m != best)
        .map(|m| mse_below(rows, best, m, region))
        .collect()
}

/// A method name without the `restir:` prefix.
pub fn short(method: &str) -> &str {
    method.trim_start_matches("restir:")
}

/// The findings as a Markdown table.
pub fn markdown(findings: &[Finding]) -> String {
    let mut out = String::from(
        "| finding of paper 001 | reproduces | measured (ratio or difference [interval]) |\n|---|---|---|\n",
    );
    for f in findings {
        let verdict = match f.verdict {
            Verdict::Holds => "yes",
            Verdict::Fails => "**no**",
            Verdict::Inconclusive => "inconclusive",
            Verdict::NotApplicable => "n/a",
        };
        out.push_str(&format!("| {} | {verdict} | {} |\n", f.claim, f.measured));
    }
    out.push_str(&format!(
        "\nVerdicts by {:.0}% family-wise intervals over replicas (Bonferroni within a finding): \
         yes = every interval on the claimed side, **no** = one entirely on the other side, \
         inconclusive = otherwise; n/a = not measurable (empty region).\n",
        100.0 * CONFIDENCE
    ));
    if findings.iter().any(|f| f.verdict == Verdict::Fails) {
        out.push_str(
            "\nFindings marked **no** are discussed in docs/experiments.md (equal-time rows: a CPU \
             ReSTIR frame costs several path-traced frames, unlike paper 001's GPU implementation).\n",
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Log ratios from 8 replicas around `centre` with spread ±0.05.
    fn around(centre: f64) -> Option<Estimate> {
        let spread = [-0.05, 0.05, -0.03, 0.03, -0.01, 0.01, -0.02, 0.02];
        Some(Estimate::mean(&spread.map(|d| centre + d)))
    }

    #[test]
    fn a_claim_is_decided_by_its_intervals() {
        let q = |c| vec![("r".to_string(), around(c))];
        let decide = |c| all_below("c".into(), &q(c), 0.0, true).verdict;
        assert_eq!(decide(-0.5), Verdict::Holds);
        assert_eq!(decide(0.5), Verdict::Fails);
        assert_eq!(
            decide(0.0),
            Verdict::Inconclusive,
            "a point estimate of 0 decides nothing"
        );
        assert_eq!(
            decide(-0.01),
            Verdict::Inconclusive,
            "below, but not by its interval"
        );
        assert_eq!(
            all_above("c".into(), &q(0.5), 0.0, true).verdict,
            Verdict::Holds
        );
        assert_eq!(
            all_above("c".into(), &q(-0.5), 0.0, true).verdict,
            Verdict::Fails
        );
        // A family: one failure decides, even beside an unmeasurable member; otherwise an
        // unmeasurable member leaves it n/a.
        let family = vec![
            ("a".to_string(), around(-0.5)),
            ("b".to_string(), around(0.5)),
        ];
        assert_eq!(
            all_below("c".into(), &family, 0.0, true).verdict,
            Verdict::Fails
        );
        let failing = vec![("a".to_string(), around(0.5)), ("b".to_string(), None)];
        assert_eq!(
            all_below("c".into(), &failing, 0.0, true).verdict,
            Verdict::Fails
        );
        let missing = vec![("a".to_string(), around(-0.5)), ("b".to_string(), None)];
        let f = all_below("c".into(), &missing, 0.0, true);
        assert_eq!(f.verdict, Verdict::NotApplicable);
        assert!(
            f.measured.contains("b n/a") && f.measured.contains("97.5% intervals"),
            "{}",
            f.measured
        );
    }

    #[test]
    fn a_failed_finding_points_to_the_discussion() {
        let finding = |verdict| Finding {
            claim: "a".into(),
            verdict,
            measured: "m".into(),
        };
        let ok = markdown(&[finding(Verdict::Holds), finding(Verdict::Inconclusive)]);
        assert!(ok.contains("| a | yes | m |") && ok.contains("| a | inconclusive | m |"));
        assert!(!ok.contains("docs/experiments.md"));
        let failed = markdown(&[finding(Verdict::Fails)]);
        assert!(failed.contains("**no**") && failed.contains("docs/experiments.md"));
    }
}
