//! Checks 1–3: properties of a shift alone, on sampled points of pairs of domains.

use super::{CheckName, CheckReport, PASS_CHECK};
use crate::rng::StreamKey;
use crate::shift::{CandidateSampler, LocalCoords, Shift};

/// Most local coordinates the finite-difference check handles.
const MAX_DIM: usize = 8;

/// Pairs of domains to test a shift on, in both directions, with points drawn by `sampler`.
pub struct ShiftCase<'a, D: LocalCoords> {
    pub pairs: Vec<(&'a D, &'a D)>,
    pub sampler: &'a dyn CandidateSampler<D>,
    pub samples_per_pair: usize,
    pub seed: u64,
}

impl<D: LocalCoords> ShiftCase<'_, D> {
    /// Calls `visit(src, dst, x)` for every drawn point `x` of `src`, both directions of every pair.
    fn for_each_point(&self, check: u32, mut visit: impl FnMut(&D, &D, &D::Sample)) {
        for (index, &(a, b)) in self.pairs.iter().enumerate() {
            for (direction, (src, dst)) in [(a, b), (b, a)].into_iter().enumerate() {
                let key = StreamKey::new(index as u32, direction as u32, PASS_CHECK, check);
                let mut rng = key.stream(self.seed);
                for _ in 0..self.samples_per_pair {
                    if let Some((x, _)) = self.sampler.sample(src, &mut rng) {
                        visit(src, dst, &x);
                    }
                }
            }
        }
    }
}

fn local<D: LocalCoords>(domain: &D, x: &D::Sample) -> [f64; MAX_DIM] {
    let mut out = [0.0; MAX_DIM];
    domain.to_local(x, &mut out[..domain.dim().min(MAX_DIM)]);
    out
}

/// Check 1: `T_{d→s}(T_{s→d}(x)) = x` within `tolerance` (max norm in local coordinates), and
/// failures are symmetric: whenever `T_{s→d}(x)` succeeds, `T_{d→s}` of the image succeeds too.
/// Both directions of each pair are sampled, so "fails one way ⇔ fails the other" is covered.
pub fn round_trip<D, T>(shift: &T, case: &ShiftCase<'_, D>, tolerance: f64) -> CheckReport
where
    D: LocalCoords,
    T: Shift<D> + ?Sized,
{
    let (mut shifted, mut failed, mut asymmetric, mut max_error) = (0usize, 0usize, 0usize, 0.0f64);
    let mut note = String::new();
    case.for_each_point(1, |src, dst, x| match shift.shift(x, src, dst) {
        Err(_) => failed += 1,
        Ok(fwd) => {
            shifted += 1;
            match shift.shift(&fwd.y, dst, src) {
                Err(fail) => {
                    asymmetric += 1;
                    if note.is_empty() {
                        note = format!("forward succeeded but the inverse failed ({fail:?})");
                    }
                }
                Ok(back) => {
                    let (a, b) = (local(src, x), local(src, &back.y));
                    let error = (0..src.dim())
                        .map(|k| (a[k] - b[k]).abs())
                        .fold(0.0, f64::max);
                    max_error = max_error.max(error);
                }
            }
        }
    });
    if shifted == 0 {
        note = "no point could be shifted: nothing was tested".into();
    }
    CheckReport::new(
        CheckName::RoundTrip,
        shifted > 0 && asymmetric == 0 && max_error <= tolerance,
        &[
            ("shifted", shifted as f64),
            ("failed", failed as f64),
            ("asymmetric_failures", asymmetric as f64),
            ("max_error", max_error),
            ("tolerance", tolerance),
        ],
        note,
    )
}

/// Check 2: `J_{s→d}(x) · J_{d→s}(T x) = 1` within relative `tolerance`.
pub fn reciprocal_jacobian<D, T>(shift: &T, case: &ShiftCase<'_, D>, tolerance: f64) -> CheckReport
where
    D: LocalCoords,
    T: Shift<D> + ?Sized,
{
    let (mut tested, mut max_error) = (0usize, 0.0f64);
    case.for_each_point(2, |src, dst, x| {
        if let Ok(fwd) = shift.shift(x, src, dst)
            && let Ok(back) = shift.shift(&fwd.y, dst, src)
        {
            tested += 1;
            let product = fwd.jacobian as f64 * back.jacobian as f64;
            max_error = max_error.max((product - 1.0).abs());
        }
    });
    let note = if tested == 0 {
        "no round trip succeeded: nothing was tested".into()
    } else {
        String::new()
    };
    CheckReport::new(
        CheckName::ReciprocalJacobian,
        tested > 0 && max_error <= tolerance,
        &[
            ("tested", tested as f64),
            ("max_relative_error", max_error),
            ("tolerance", tolerance),
        ],
        note,
    )
}

/// Check 3: the analytic `J` against `|det ∂T/∂x|` from central differences in local
/// coordinates, Richardson-extrapolated (`(4 D(h/2) − D(h)) / 3`), with the per-coordinate step
/// `h = relative_step · max(|x_k|, 0.01)` measured after the round trip through the sample type.
/// Skipped and counted: points whose stencil leaves the domain or makes the shift fail, and
/// points where the plain differences at `h` and `h/2` disagree by more than `tolerance` (the
/// map is not resolved there, e.g. next to a singularity). At least half the shifted points
/// must be tested.
pub fn finite_difference_jacobian<D, T>(
    shift: &T,
    case: &ShiftCase<'_, D>,
    relative_step: f64,
    tolerance: f64,
) -> CheckReport
where
    D: LocalCoords,
    T: Shift<D> + ?Sized,
{
    let (mut tested, mut skipped, mut max_error) = (0usize, 0usize, 0.0f64);
    let mut worst = String::new();
    case.for_each_point(3, |src, dst, x| {
        let Ok(fwd) = shift.shift(x, src, dst) else {
            return;
        };
        match numeric_jacobian(shift, src, dst, x, relative_step, tolerance) {
            None => skipped += 1,
            Some(det) => {
                tested += 1;
                let analytic = fwd.jacobian as f64;
                let error = (det - analytic).abs() / analytic.abs().max(f64::MIN_POSITIVE);
                if error > max_error {
                    max_error = error;
                    worst =
                        format!("worst: analytic J = {analytic:.6e}, finite differences {det:.6e}");
                }
            }
        }
    });
    if tested == 0 {
        worst = "no stencil fitted: nothing was tested".into();
    }
    CheckReport::new(
        CheckName::FiniteDifferenceJacobian,
        tested > 0 && tested >= skipped && max_error <= tolerance,
        &[
            ("tested", tested as f64),
            ("skipped", skipped as f64),
            ("max_relative_error", max_error),
            ("tolerance", tolerance),
        ],
        worst,
    )
}

/// `|det ∂T/∂x|` at `x`, or `None` when a stencil point is outside the domain or fails, or the
/// differences at `h` and `h/2` differ by more than `resolution` (relative, in the determinant).
fn numeric_jacobian<D, T>(
    shift: &T,
    src: &D,
    dst: &D,
    x: &D::Sample,
    relative_step: f64,
    resolution: f64,
) -> Option<f64>
where
    D: LocalCoords,
    T: Shift<D> + ?Sized,
{
    let n = src.dim();
    if n == 0 || n > MAX_DIM || dst.dim() != n {
        return None;
    }
    let centre = local(src, x);
    let mut matrix = [0.0f64; MAX_DIM * MAX_DIM];
    let mut coarse_matrix = matrix;
    let mut fine_matrix = matrix;
    for k in 0..n {
        let h = relative_step * centre[k].abs().max(0.01);
        let derivative = |step: f64| -> Option<[f64; MAX_DIM]> {
            let mut plus = centre;
            let mut minus = centre;
            plus[k] += step;
            minus[k] -= step;
            let (xp, xm) = (
                src.sample_at_local(&plus[..n])?,
                src.sample_at_local(&minus[..n])?,
            );
            let actual = local(src, &xp)[k] - local(src, &xm)[k];
            let (yp, ym) = (
                shift.shift(&xp, src, dst).ok()?,
                shift.shift(&xm, src, dst).ok()?,
            );
            let (a, b) = (local(dst, &yp.y), local(dst, &ym.y));
            let mut column = [0.0; MAX_DIM];
            for i in 0..n {
                column[i] = (a[i] - b[i]) / actual;
            }
            Some(column)
        };
        let (coarse, fine) = (derivative(h)?, derivative(h / 2.0)?);
        for i in 0..n {
            matrix[i * n + k] = (4.0 * fine[i] - coarse[i]) / 3.0;
            coarse_matrix[i * n + k] = coarse[i];
            fine_matrix[i * n + k] = fine[i];
        }
    }
    let coarse = determinant(&mut coarse_matrix[..n * n], n).abs();
    let fine = determinant(&mut fine_matrix[..n * n], n).abs();
    if (coarse - fine).abs() > resolution * fine {
        return None;
    }
    Some(determinant(&mut matrix[..n * n], n).abs())
}

/// Determinant of the row-major `n × n` matrix by Gaussian elimination with partial pivoting.
fn determinant(m: &mut [f64], n: usize) -> f64 {
    let mut det = 1.0;
    for col in 0..n {
        let pivot = (col..n).max_by(|&a, &b| m[a * n + col].abs().total_cmp(&m[b * n + col].abs()));
        let Some(pivot) = pivot else { return 0.0 };
        if m[pivot * n + col] == 0.0 {
            return 0.0;
        }
        if pivot != col {
            for j in 0..n {
                m.swap(pivot * n + j, col * n + j);
            }
            det = -det;
        }
        det *= m[col * n + col];
        for row in col + 1..n {
            let factor = m[row * n + col] / m[col * n + col];
            for j in col..n {
                m[row * n + j] -= factor * m[col * n + j];
            }
        }
    }
    det
}

#[cfg(test)]
mod tests {
    use super::determinant;

    #[test]
    fn determinant_of_known_matrices() {
        assert_eq!(determinant(&mut [2.0, 0.0, 0.0, 3.0], 2), 6.0);
        assert_eq!(determinant(&mut [0.0, 1.0, 1.0, 0.0], 2), -1.0);
        let mut m = [2.0, -3.0, 1.0, 2.0, 0.0, -1.0, 1.0, 4.0, 5.0];
        assert!((determinant(&mut m, 3) - 49.0).abs() < 1e-12);
    }
}
