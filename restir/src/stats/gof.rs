//! Goodness-of-fit tests: Pearson chi-square on binned counts, sums of squared z-scores, and
//! the one-sample Kolmogorov–Smirnov test.

use super::special::{chi_square_sf, kolmogorov_sf};

/// Result of a chi-square test.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChiSquare {
    pub statistic: f64,
    pub dof: usize,
    pub p_value: f64,
    /// Cells (after pooling) that enter the statistic.
    pub cells_used: usize,
    /// Input cells absorbed into a neighbour by pooling: `input cells − cells_used`.
    pub cells_pooled: usize,
}

/// Pearson's goodness of fit of `observed` counts to the `expected` shape.
///
/// * `expected` may be counts or probabilities: it is rescaled to the observed total, so the
///   test is about the shape only and `dof = cells_used − 1` (test totals with z-scores and
///   [`chi_square_from_z`]).
/// * Pooling depends on `expected` only (so the test stays valid): adjacent cells are merged
///   left to right until the merged expected count reaches `min_expected`; a short remainder
///   at the end joins the last merged cell.
/// * Slices of different lengths are padded with empty cells. An observation in a cell of
///   zero expectation that is not pooled (`min_expected ≤ 0`) gives `statistic = ∞`, `p = 0`.
/// * Negative or non-finite entries, or a positive observed total against a zero expected
///   total: `statistic = ∞`, `p = 0`, `cells_used = 0`. No observations, or a single cell
///   after pooling: `statistic = 0`, `dof = 0`, `p = 1` (nothing to test).
pub fn chi_square_gof(observed: &[f64], expected: &[f64], min_expected: f64) -> ChiSquare {
    let cells = observed.len().max(expected.len());
    let cell = |xs: &[f64], i: usize| xs.get(i).copied().unwrap_or(0.0);
    let valid = |x: f64| x >= 0.0 && x.is_finite();
    let total_observed: f64 = observed.iter().sum();
    let total_expected: f64 = expected.iter().sum();
    let rejected = ChiSquare {
        statistic: f64::INFINITY,
        dof: 0,
        p_value: 0.0,
        cells_used: 0,
        cells_pooled: 0,
    };
    if !(observed.iter().all(|&x| valid(x)) && expected.iter().all(|&x| valid(x))) {
        return rejected;
    }
    if total_observed == 0.0 {
        return ChiSquare {
            statistic: 0.0,
            dof: 0,
            p_value: 1.0,
            cells_used: 0,
            cells_pooled: 0,
        };
    }
    if total_expected == 0.0 {
        return rejected;
    }
    let scale = total_observed / total_expected;
    let mut pooled: Vec<(f64, f64)> = Vec::new();
    let (mut o, mut e, mut open) = (0.0, 0.0, false);
    for i in 0..cells {
        o += cell(observed, i);
        e += cell(expected, i) * scale;
        open = true;
        if e >= min_expected {
            pooled.push((o, e));
            (o, e, open) = (0.0, 0.0, false);
        }
    }
    if open {
        match pooled.last_mut() {
            Some(last) => (last.0, last.1) = (last.0 + o, last.1 + e),
            None => pooled.push((o, e)),
        }
    }
    let statistic = pooled
        .iter()
        .map(|&(o, e)| match (e > 0.0, o > 0.0) {
            (true, _) => (o - e) * (o - e) / e,
            (false, true) => f64::INFINITY,
            (false, false) => 0.0,
        })
        .sum();
    let cells_used = pooled.len();
    chi_square_result(statistic, cells_used - 1, cells_used, cells - cells_used)
}

/// `Σ zᵢ²` over independent z-scores: chi-square with `k = z.len()` dof, e.g. per-bin mean
/// tests such as `E[1_B W] = |B|`. A non-finite z gives `statistic = ∞`, `p = 0`; no z-scores
/// give `p = 1`.
pub fn chi_square_from_z(z: &[f64]) -> ChiSquare {
    let statistic = if z.iter().all(|z| z.is_finite()) {
        z.iter().map(|z| z * z).sum()
    } else {
        f64::INFINITY
    };
    chi_square_result(statistic, z.len(), z.len(), 0)
}

fn chi_square_result(
    statistic: f64,
    dof: usize,
    cells_used: usize,
    cells_pooled: usize,
) -> ChiSquare {
    let p_value = if dof == 0 {
        1.0
    } else {
        chi_square_sf(statistic, dof as f64)
    };
    ChiSquare {
        statistic,
        dof,
        p_value,
        cells_used,
        cells_pooled,
    }
}

/// Result of a one-sample Kolmogorov–Smirnov test.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ks {
    /// `D_n = sup |F_n(x) − F(x)|`.
    pub statistic: f64,
    pub n: usize,
    pub p_value: f64,
}

/// One-sample KS test of `samples` against the continuous CDF `cdf` (a sorted copy is made).
/// p-value: the Kolmogorov limit law with Stephens' small-sample correction,
/// `Q_KS((√n + 0.12 + 0.11/√n)·D)` (Stephens 1970; Numerical Recipes §14.3), accurate to a
/// few percent of p for n ≥ 5. CDF values are clamped to [0, 1]; a NaN sample or CDF value
/// gives `D = 1`. No samples: `D = 0`, `p = 1`.
pub fn ks_one_sample(samples: &[f64], cdf: impl Fn(f64) -> f64) -> Ks {
    let n = samples.len();
    if n == 0 {
        return Ks {
            statistic: 0.0,
            n,
            p_value: 1.0,
        };
    }
    let mut sorted = samples.to_vec();
    sorted.sort_by(f64::total_cmp);
    let nf = n as f64;
    let mut d: f64 = 0.0;
    for (i, &x) in sorted.iter().enumerate() {
        let f = cdf(x);
        if f.is_nan() {
            d = 1.0;
            break;
        }
        let f = f.clamp(0.0, 1.0);
        d = d.max(f - i as f64 / nf).max((i + 1) as f64 / nf - f);
    }
    let sqrt_n = nf.sqrt();
    Ks {
        statistic: d,
        n,
        p_value: kolmogorov_sf((sqrt_n + 0.12 + 0.11 / sqrt_n) * d),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stats::special::binomial_interval;
    use crate::stats::testing::stream;

    const BINS: usize = 10;

    /// Counts of `n` draws `sample(u)` in `BINS` equal bins of [0, 1).
    fn histogram(s: &mut crate::rng::Stream, n: usize, sample: impl Fn(f64) -> f64) -> Vec<f64> {
        let mut counts = vec![0.0; BINS];
        for _ in 0..n {
            let x = sample(s.next_f64());
            counts[((x * BINS as f64) as usize).min(BINS - 1)] += 1.0;
        }
        counts
    }

    /// Expected bin probabilities of the density 2x on [0, 1): `F(b) − F(a)` with `F = x²`.
    fn expected_linear() -> Vec<f64> {
        (0..BINS)
            .map(|i| ((i + 1) as f64 / BINS as f64).powi(2) - (i as f64 / BINS as f64).powi(2))
            .collect()
    }

    /// α = 0.05, M = 1000 experiments of n = 100 draws from the density 2x (x = √u) in 10 bins,
    /// min expected 5 (the low bins pool): the rejection count must lie in the binomial 99.9%
    /// interval of M·α. Negative control: draws from 3x² (x = u^⅓) tested against 2x.
    #[test]
    fn chi_square_calibration_and_wrong_pdf() {
        const M: usize = 1000;
        const N: usize = 100;
        const ALPHA: f64 = 0.05;
        let expected = expected_linear();
        let mut s = stream(4, 1);
        let (mut null_rejects, mut wrong_rejects) = (0, 0);
        for _ in 0..M {
            let right = chi_square_gof(&histogram(&mut s, N, f64::sqrt), &expected, 5.0);
            null_rejects += (right.p_value < ALPHA) as usize;
            let wrong = chi_square_gof(&histogram(&mut s, N, f64::cbrt), &expected, 5.0);
            wrong_rejects += (wrong.p_value < ALPHA) as usize;
        }
        let (lo, hi) = binomial_interval(M, ALPHA, 0.999);
        assert!(
            (lo..=hi).contains(&null_rejects),
            "{null_rejects}/{M} null rejections, interval [{lo}, {hi}]"
        );
        assert!(
            wrong_rejects > hi,
            "3x² vs 2x: {wrong_rejects}/{M} rejections, should exceed {hi}"
        );
    }

    /// With n = 100 and min expected 5, the bins of 2x with expected 1, 3, 5, … pool: bins 0–1
    /// (1 + 3 = 4 < 5) pool with bin 2 (total 9); the other 7 stand alone.
    #[test]
    fn pooling_counts_cells() {
        let expected: Vec<f64> = expected_linear().iter().map(|p| 100.0 * p).collect();
        let r = chi_square_gof(&expected, &expected, 5.0);
        assert_eq!((r.cells_used, r.cells_pooled, r.dof), (8, 2, 7));
        assert_eq!((r.statistic, r.p_value), (0.0, 1.0));
        // A short remainder at the end joins the last pooled cell: 6 | 6 | 2 → 6 | 8.
        let r = chi_square_gof(&[6.0, 6.0, 2.0], &[6.0, 6.0, 2.0], 5.0);
        assert_eq!((r.cells_used, r.cells_pooled), (2, 1));
        // Probabilities are rescaled to the observed total.
        let r = chi_square_gof(&[30.0, 70.0], &[0.3, 0.7], 5.0);
        assert_eq!((r.statistic, r.dof, r.p_value), (0.0, 1, 1.0));
    }

    #[test]
    fn degenerate_inputs_are_defined() {
        assert_eq!(chi_square_gof(&[], &[], 5.0).p_value, 1.0);
        assert_eq!(
            chi_square_gof(&[1.0, f64::NAN], &[1.0, 1.0], 5.0).p_value,
            0.0
        );
        assert_eq!(chi_square_gof(&[3.0], &[0.0], 5.0).p_value, 0.0);
        // An observation beyond the expected support (padded with zero expectation).
        let r = chi_square_gof(&[50.0, 50.0, 1.0], &[50.0, 50.0], 0.0);
        assert_eq!((r.statistic, r.p_value), (f64::INFINITY, 0.0));
        let empty = chi_square_from_z(&[]);
        assert_eq!((empty.statistic, empty.dof, empty.p_value), (0.0, 0, 1.0));
        assert_eq!(chi_square_from_z(&[1.0, f64::NAN]).p_value, 0.0);
        assert_eq!(ks_one_sample(&[], |x| x).p_value, 1.0);
        assert_eq!(ks_one_sample(&[0.5, f64::NAN], |x| x).statistic, 1.0);
    }

    /// k = 20 z-scores per experiment, M = 1000, α = 0.05: standard normal z (Box–Muller)
    /// must reject at rate α within the binomial 99.9% interval; z-scores computed with a
    /// standard error 20% too small (z·1.25) must be caught.
    #[test]
    fn chi_square_from_z_calibration() {
        const M: usize = 1000;
        const K: usize = 20;
        const ALPHA: f64 = 0.05;
        let mut s = stream(4, 2);
        let (mut null_rejects, mut wrong_rejects) = (0, 0);
        for _ in 0..M {
            let z: Vec<f64> = (0..K)
                .map(|_| crate::stats::testing::normal(&mut s))
                .collect();
            null_rejects += (chi_square_from_z(&z).p_value < ALPHA) as usize;
            let inflated: Vec<f64> = z.iter().map(|z| 1.25 * z).collect();
            wrong_rejects += (chi_square_from_z(&inflated).p_value < ALPHA) as usize;
        }
        let (lo, hi) = binomial_interval(M, ALPHA, 0.999);
        assert!(
            (lo..=hi).contains(&null_rejects),
            "{null_rejects}/{M} null rejections, interval [{lo}, {hi}]"
        );
        assert!(
            wrong_rejects > hi,
            "inflated z: {wrong_rejects}/{M} rejections, should exceed {hi}"
        );
    }

    /// α = 0.05, M = 1000 experiments of n = 200 uniform draws against F(x) = x: rejection
    /// count in the binomial 99.9% interval of M·α. Negative control: draws from 3x² tested
    /// against the CDF x² of 2x.
    #[test]
    fn ks_calibration_and_wrong_pdf() {
        const M: usize = 1000;
        const N: usize = 200;
        const ALPHA: f64 = 0.05;
        let mut s = stream(4, 3);
        let (mut null_rejects, mut wrong_rejects) = (0, 0);
        for _ in 0..M {
            let uniform: Vec<f64> = (0..N).map(|_| s.next_f64()).collect();
            null_rejects += (ks_one_sample(&uniform, |x| x).p_value < ALPHA) as usize;
            let cubic: Vec<f64> = (0..N).map(|_| s.next_f64().cbrt()).collect();
            wrong_rejects += (ks_one_sample(&cubic, |x| x * x).p_value < ALPHA) as usize;
        }
        let (lo, hi) = binomial_interval(M, ALPHA, 0.999);
        assert!(
            (lo..=hi).contains(&null_rejects),
            "{null_rejects}/{M} null rejections, interval [{lo}, {hi}]"
        );
        assert!(
            wrong_rejects > hi,
            "3x² vs 2x: {wrong_rejects}/{M} rejections, should exceed {hi}"
        );
    }

    /// D for a tiny sample by hand: {0.1, 0.6} against F(x) = x: max(0.1, 0.5 − 0.1,
    /// 0.6 − 0.5, 1 − 0.6) = 0.4.
    #[test]
    fn ks_statistic_by_hand() {
        let r = ks_one_sample(&[0.6, 0.1], |x| x);
        assert!((r.statistic - 0.4).abs() < 1e-15);
        assert_eq!(r.n, 2);
    }
}
