//! Checks 5–6 on the outputs of independent replicas of a chain (the unit of independence).
//! Inputs are replica-major: `rows[replica][cell]`.

use super::{CheckName, CheckReport};
use crate::stats::{Equivalence, Summary, Verdict, chi_square_from_z, equivalence, holm};

/// The summary of column `cell` over all replicas.
fn column(rows: &[Vec<f64>], cell: usize) -> Summary {
    let values: Vec<f64> = rows
        .iter()
        .map(|row| row.get(cell).copied().unwrap_or(0.0))
        .collect();
    Summary::from_samples(&values)
}

/// Check 5: `E[1_B(Y)·W_Y] = |B ∩ supp p̂|` for every cell (pixel × histogram bin).
/// `observations[replica][cell]` holds `1_B(Y)·W_Y`, `expected[cell]` the measure. Per-cell
/// z-scores over replicas are combined by `Σ z²` (chi-square, one dof per cell) and tested at
/// level `alpha`. A cell that never varies is skipped if its mean equals the expectation (an
/// empty cell outside the support) and otherwise fails the check.
pub fn ucw_histogram(observations: &[Vec<f64>], expected: &[f64], alpha: f64) -> CheckReport {
    let mut z = Vec::with_capacity(expected.len());
    let mut max_abs_z = 0.0f64;
    let mut note = String::new();
    for (cell, &want) in expected.iter().enumerate() {
        let s = column(observations, cell);
        let score = if s.std_err > 0.0 && s.std_err.is_finite() {
            (s.mean - want) / s.std_err
        } else if s.mean == want {
            continue;
        } else {
            f64::INFINITY
        };
        if score.abs() > max_abs_z {
            max_abs_z = score.abs();
            note = format!(
                "worst cell {cell}: mean {:.5} vs |B ∩ supp| {want:.5}",
                s.mean
            );
        }
        z.push(score);
    }
    let chi = chi_square_from_z(&z);
    CheckReport::new(
        CheckName::UcwHistogram,
        !z.is_empty() && chi.p_value >= alpha,
        &[
            ("replicas", observations.len() as f64),
            ("cells", z.len() as f64),
            ("chi_square", chi.statistic),
            ("p_value", chi.p_value),
            ("alpha", alpha),
            ("max_abs_z", max_abs_z),
        ],
        note,
    )
}

/// The equivalence test of the image total `Σ_pixels` per replica against `Σ reference`.
pub fn image_equivalence(
    estimates: &[Vec<f64>],
    reference: &[f64],
    delta: f64,
    confidence: f64,
) -> Equivalence {
    let totals: Vec<f64> = estimates.iter().map(|row| row.iter().sum()).collect();
    let reference_total: f64 = reference.iter().sum();
    equivalence(
        &Summary::from_samples(&totals),
        &Summary::exact(reference_total),
        delta,
        confidence,
    )
}

/// Check 6: end-to-end unbiasedness. Passes when (a) no pixel's zero-bias test is rejected
/// after Holm correction at family-wise level `alpha`, and (b) the image total is shown
/// equivalent to the reference: its `1 − alpha` CI of the relative bias lies inside ±`delta`.
pub fn unbiasedness(
    estimates: &[Vec<f64>],
    reference: &[f64],
    delta: f64,
    alpha: f64,
) -> CheckReport {
    let confidence = 1.0 - alpha;
    let p_values: Vec<f64> = (0..reference.len())
        .map(|p| {
            equivalence(
                &column(estimates, p),
                &Summary::exact(reference[p]),
                delta,
                confidence,
            )
            .p_zero_bias
        })
        .collect();
    let rejected = holm(&p_values, alpha).iter().filter(|&&r| r).count();
    let total = image_equivalence(estimates, reference, delta, confidence);
    let verdict = total.verdict.name();
    CheckReport::new(
        CheckName::Unbiasedness,
        rejected == 0 && total.verdict == Verdict::Equivalent,
        &[
            ("replicas", estimates.len() as f64),
            ("pixels", reference.len() as f64),
            ("holm_rejections", rejected as f64),
            ("relative_bias", total.relative_bias),
            ("ci_low", total.ci_low),
            ("ci_high", total.ci_high),
            ("delta", delta),
            ("alpha", alpha),
        ],
        format!("image total {verdict} ({total})"),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::StreamKey;

    /// `rows[replica][cell]` = `mean[cell] + shift + U(−½, ½)` from keyed streams.
    fn rows(means: &[f64], shift: f64, replicas: usize) -> Vec<Vec<f64>> {
        (0..replicas)
            .map(|r| {
                let mut rng = StreamKey::new(r as u32, 0, 0, 0x5C).stream(4);
                means
                    .iter()
                    .map(|m| m + shift + rng.next_f64() - 0.5)
                    .collect()
            })
            .collect()
    }

    /// Synthetic replicas with known means pass checks 5 and 6 (N = 2000, α = 1e-3, δ = 3%);
    /// negative controls: the same replicas shifted by +0.04 (≈ 6 standard errors per cell, ≈ 4%
    /// relative) fail both.
    #[test]
    fn checks_accept_exact_means_and_reject_shifted_ones() {
        let means: Vec<f64> = (0..20).map(|i| 0.8 + 0.02 * i as f64).collect();
        let good = rows(&means, 0.0, 2000);
        assert!(ucw_histogram(&good, &means, 1e-3).passed);
        assert!(unbiasedness(&good, &means, 0.03, 1e-3).passed);
        let bad = rows(&means, 0.04, 2000);
        let report = ucw_histogram(&bad, &means, 1e-3);
        assert!(!report.passed, "{report}");
        let report = unbiasedness(&bad, &means, 0.03, 1e-3);
        assert!(
            !report.passed && report.figure("holm_rejections").unwrap() > 0.0,
            "{report}"
        );
    }

    /// A constant cell equal to its expectation is skipped; a constant cell that differs fails.
    #[test]
    fn constant_cells_are_skipped_or_fail() {
        let zeros = vec![vec![0.0, 1.0]; 10];
        let report = ucw_histogram(&zeros, &[0.0, 1.0], 1e-3);
        assert!(
            !report.passed && report.figure("cells").unwrap() == 0.0,
            "nothing to test: {report}"
        );
        let mut mixed = rows(&[0.5], 0.0, 100);
        for row in &mut mixed {
            row.push(0.0);
        }
        assert!(ucw_histogram(&mixed, &[0.5, 0.0], 1e-3).passed);
        assert!(!ucw_histogram(&mixed, &[0.5, 0.1], 1e-3).passed);
    }
}
