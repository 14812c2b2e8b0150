//! Check 4: the resampling MIS weights of a shift + scheme form a partition of unity.

use super::{CheckName, CheckReport, PASS_CHECK};
use crate::mis::{Bias, MAX_DOMAINS, MisScheme};
use crate::rng::StreamKey;
use crate::shift::{CandidateSampler, Domain, Evaluated, Fail, Shift};

/// A receiver, the domains it reuses from, their confidences (`confidences[0]` = receiver's),
/// and the points of the receiver to test, drawn by `sampler`.
pub struct MisCase<'a, D: Domain> {
    pub receiver: &'a D,
    pub others: Vec<&'a D>,
    pub confidences: Vec<f32>,
    pub sampler: &'a dyn CandidateSampler<D>,
    pub samples: usize,
    pub seed: u64,
}

/// Check 4: at every sampled `y` with `p̂_r(y) > 0`,
/// (a) `m_j(y) = 0` for every domain `j` whose back-shift `T_{r→j}(y)` fails, and
/// (b) `Σ_j m_j(y) = 1` within `tolerance`, summed over the domains that can produce `y`
///     (`p̂_{←j}(y) > 0`): weight given to a domain that cannot produce `y` is lost, so the
///     estimate darkens. This is how `1/M` fails on differing supports.
/// (c) The shortcuts resampling takes agree bit for bit with the plain evaluations:
///     [`Shift::targets_from`] with [`Shift::target_from`] per domain, and
///     [`Shift::shift_with_targets`] with [`Shift::shift_supported`], `p̂_j(T(y))` and
///     `p̂_r(y)` wherever the shift succeeds (the targets resampling reads are what the MIS
///     weights above were computed from); and [`Shift::shifts_with_targets`] into all the
///     other domains with `shift_with_targets` into each, whose `p̂_j(T(y)) · J` is
///     [`Shift::target_from`]: a reciprocal pair uses one shift as the partner's forward shift
///     and as its own MIS back-shift.
pub fn partition_of_unity<D, T, M>(
    shift: &T,
    mis: &M,
    case: &MisCase<'_, D>,
    tolerance: f64,
) -> CheckReport
where
    D: Domain,
    T: Shift<D> + ?Sized,
    M: MisScheme + ?Sized,
{
    let n = case.others.len() + 1;
    if n > MAX_DOMAINS || case.confidences.len() != n {
        let note = format!(
            "{n} domains with {} confidences (at most {MAX_DOMAINS})",
            case.confidences.len()
        );
        return CheckReport::new(
            CheckName::PartitionOfUnity,
            false,
            &[("domains", n as f64)],
            note,
        );
    }
    let key = StreamKey::new(0, 0, PASS_CHECK, 4);
    let mut rng = key.stream(case.seed);
    let (mut tested, mut weight_where_failed, mut max_error) = (0usize, 0usize, 0.0f64);
    let mut shortcuts_disagree = 0usize;
    let mut note = String::new();
    for _ in 0..case.samples {
        let Some((y, _)) = case.sampler.sample(case.receiver, &mut rng) else {
            continue;
        };
        let mut targets = [0.0f32; MAX_DOMAINS];
        targets[0] = case.receiver.target(&y);
        if targets[0] <= 0.0 {
            continue;
        }
        tested += 1;
        let mut failed = [false; MAX_DOMAINS];
        shift.targets_from(&y, case.receiver, &case.others, &mut targets[1..n]);
        let mut batched: [Result<Evaluated<D>, Fail>; MAX_DOMAINS] =
            [Err(Fail::Rejected); MAX_DOMAINS];
        shift.shifts_with_targets(&y, case.receiver, &case.others, &mut batched[..n - 1]);
        for (j, other) in case.others.iter().enumerate() {
            let one = shift.target_from(&y, case.receiver, other);
            failed[j + 1] = shift.shift(&y, case.receiver, other).is_err();
            let forward = shift
                .shift_supported(&y, case.receiver, other)
                .ok()
                .map(|s| (s.jacobian, other.target(&s.y), case.receiver.target(&y)));
            let shortcut = shift
                .shift_with_targets(&y, case.receiver, other)
                .ok()
                .map(|e| (e.shifted.jacobian, e.target, e.source_target));
            let same = |a: f32, b: f32| a.to_bits() == b.to_bits();
            let from_batch = batched[j]
                .as_ref()
                .ok()
                .map(|e| (e.shifted.jacobian, e.target, e.source_target));
            let paired = shortcut.map_or(0.0, |(jacobian, target, _)| target * jacobian);
            let agrees = same(one, targets[j + 1])
                && same(one, paired)
                && match (forward, shortcut, from_batch) {
                    (Some(a), Some(b), Some(c)) => [(a, b), (b, c)]
                        .iter()
                        .all(|(a, b)| same(a.0, b.0) && same(a.1, b.1) && same(a.2, b.2)),
                    (None, None, None) => true,
                    _ => false,
                };
            if !agrees {
                shortcuts_disagree += 1;
                if note.is_empty() {
                    note = format!("to domain {}: the shortcuts' targets differ", j + 1);
                }
            }
        }
        let mut covered_sum = 0.0f64;
        for j in 0..n {
            let m = mis.weight(j, &targets[..n], &case.confidences);
            if failed[j] && m != 0.0 {
                weight_where_failed += 1;
                if note.is_empty() {
                    note = format!("m_{j} = {m:.4e} although T_(r→{j}) fails");
                }
            }
            if targets[j] > 0.0 {
                covered_sum += m as f64;
            }
        }
        let error = (covered_sum - 1.0).abs();
        if error > max_error {
            max_error = error;
            if error > tolerance && weight_where_failed == 0 {
                note = format!("Σ m_j over domains that can produce y = {covered_sum:.6}");
            }
        }
    }
    if tested == 0 {
        note = "no sample with p̂_r > 0: nothing was tested".into();
    }
    if mis.bias() != Bias::Unbiased {
        note = format!("[{} declares: {}] {note}", mis.name(), mis.bias());
    }
    CheckReport::new(
        CheckName::PartitionOfUnity,
        tested > 0 && weight_where_failed == 0 && shortcuts_disagree == 0 && max_error <= tolerance,
        &[
            ("tested", tested as f64),
            ("weight_where_shift_fails", weight_where_failed as f64),
            ("shortcuts_disagree", shortcuts_disagree as f64),
            ("max_sum_error", max_error),
            ("tolerance", tolerance),
        ],
        note,
    )
}
