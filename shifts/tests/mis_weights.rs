//! The resampling MIS weights of the inverting reconnection with the exact intersection index,
//! per pixel and exactly as the driver (`restir::resample`) computes them, on `far-knot`, the
//! scene where re-traced probe chords miss x2 for several percent of inversions.
//!
//! GRIS is unbiased when, for every sample `y` of the receiver `r` with `p̂_r(y) > 0`, the weights
//! the driver would give `y` summed over the domains that can *produce* it equal 1: `m_0(y)`
//! for `r`'s own (canonical) sample, and `m_i(y)` for each neighbour `i` whose forward shift
//! `T_{i→r}` yields `y`. The driver computes `m_i` of a sample arriving from `i` with
//! `p̂_{←i}(y) = p̂_i(x)/J` from that forward shift, and every other `p̂_{←j}(y)` through the
//! back-shift `T_{r→j}(y)`; the sum is 1 only if each back-shift fails exactly where the forward
//! shift into `r` fails. `restir::check::partition_of_unity` (check 4) evaluates every weight
//! through back-shifts, so it cannot see a forward shift that disagrees with its back-shift;
//! the round trip (check 1) sees one half of it (forward succeeds, back-shift fails).
//!
//! The inverting reconnection reads only the path of its input (x2, x3 and the light), so `y`
//! itself stands for every sample of `i` with `y`'s path: `i` produces `y` iff `T_{i→r}(y)`
//! succeeds (the test asserts that the image has `y`'s path).
//!
//! Negative control: the policy before paper 001's extended-space argument was applied to both
//! ends, `ReceiverOnlyIndex`, which re-traces the chord only at the receiving end of each shift
//! (each direction with its own γ), so `T_{i→r}` and `T_{r→i}` fail on different events.

mod common;

use common::{SEED, UNSHADOWED, fixture, refs};
use restir::check::{MisCase, ShiftCase, partition_of_unity, round_trip};
use restir::mis::{DefensivePairwise, Gbh, MAX_DOMAINS, MisScheme};
use restir::rng::StreamKey;
use restir::shift::{CandidateSampler, Domain, Fail, Shift, Shifted};
use shifts::{IndexPolicy, InvertingReconnection, SssDomain, SssSample, resolve_deferred_index};

/// `|Σ m − 1|` for f32 weights of at most 5 domains.
const TOLERANCE: f64 = 1e-5;
/// Spatial neighbourhoods (receiver + `NEIGHBOURS`, defensive pairwise like the presets' spatial
/// passes), temporal pairs (GBH, previous confidence `TEMPORAL_CONFIDENCE`), and samples of the
/// receiver per neighbourhood or pair.
const NEIGHBOURHOODS: usize = 64;
const NEIGHBOURS: usize = 4;
const TEMPORAL_PAIRS: usize = 64;
const TEMPORAL_CONFIDENCE: f32 = 20.0;
const SAMPLES: usize = 64;
/// Least (sample, pixel pair) cases with an index re-trace failure the test must see: the point
/// of the scene. About 15% of the cases fail (the printout has the counts).
const MIN_INDEX_FAILURES: usize = 500;

const EXACT: InvertingReconnection = InvertingReconnection {
    policy: IndexPolicy::Exact,
};

/// The exact policy with the index re-traced only at the receiving end of each shift, each
/// direction with its receiver's γ: the deferred policy followed at once by its resolution,
/// failing where x2 is not found (the equality of the two is `failures.rs`'s
/// `deferred_index_is_resolved_for_the_selected_sample_only_when_found`).
struct ReceiverOnlyIndex;

impl Shift<SssDomain<'_>> for ReceiverOnlyIndex {
    fn shift(
        &self,
        x: &SssSample,
        src: &SssDomain,
        dst: &SssDomain,
    ) -> Result<Shifted<SssSample>, Fail> {
        let deferred = InvertingReconnection {
            policy: IndexPolicy::Deferred,
        };
        let mut shifted = deferred.shift(x, src, dst)?;
        resolve_deferred_index(dst, &mut shifted.y);
        shifted.y.index().ok_or(Fail::NotInvertible)?;
        Ok(shifted)
    }
}

/// One resampling step: the receiver, its neighbours, the confidences (`[0]` = receiver's) and
/// the MIS scheme of the pass.
struct Step<'a, 's> {
    receiver: &'a SssDomain<'s>,
    neighbours: Vec<&'a SssDomain<'s>>,
    confidences: Vec<f32>,
    mis: &'a dyn MisScheme,
}

/// What the driver-level sums of one shift showed.
#[derive(Debug, Default)]
struct Tally {
    /// Samples `y` with `p̂_r(y) > 0`.
    samples: usize,
    /// (sample, neighbour) cases, and those where the shift or its back-shift failed with
    /// `NotInvertible` (the index re-trace).
    cases: usize,
    index_failures: usize,
    /// Samples whose weights over the producing domains do not sum to 1, and the worst error.
    violations: usize,
    max_error: f64,
}

/// `m_i(y)` as `restir::resample` computes it for `y` arriving from domain `i` (0 = receiver):
/// `targets[0] = p̂_r(y)`, `targets[i] = own` (`p̂_i(x)/J` of the forward shift), the other
/// `targets[j] = Shift::target_from(y, r, j)` when the scheme reads them.
fn driver_weight<T: for<'s> Shift<SssDomain<'s>>>(
    shift: &T,
    step: &Step,
    y: &SssSample,
    i: usize,
    own: f32,
) -> f32 {
    let n = step.neighbours.len() + 1;
    let mut targets = [0.0f32; MAX_DOMAINS];
    targets[0] = step.receiver.target(y);
    if i > 0 {
        targets[i] = own;
    }
    if step.mis.needs_all_targets(i) {
        for (j, other) in step.neighbours.iter().enumerate().map(|(j, d)| (j + 1, d)) {
            if j != i {
                targets[j] = shift.target_from(y, step.receiver, other);
            }
        }
    }
    step.mis.weight(i, &targets[..n], &step.confidences)
}

/// Adds `SAMPLES` samples of `step`'s receiver to `tally`: for each, the driver's weights summed
/// over the domains that produce it.
fn sum_weights<T: for<'s> Shift<SssDomain<'s>>>(
    shift: &T,
    step: &Step,
    purpose: u32,
    tally: &mut Tally,
) {
    let r = step.receiver;
    let mut rng = StreamKey::new(r.pixel(), r.frame(), 0, purpose).stream(SEED);
    for _ in 0..SAMPLES {
        let Some((y, _)) = UNSHADOWED.sample(r, &mut rng) else {
            continue;
        };
        tally.samples += 1;
        let mut sum = driver_weight(shift, step, &y, 0, 0.0) as f64;
        for (i, source) in step.neighbours.iter().enumerate().map(|(j, d)| (j + 1, d)) {
            tally.cases += 1;
            let forward = shift.shift(&y, source, r);
            let back = shift.shift(&y, r, source);
            if forward == Err(Fail::NotInvertible) || back == Err(Fail::NotInvertible) {
                tally.index_failures += 1;
            }
            let Ok(forward) = forward else { continue };
            let image = forward.y;
            assert_eq!(
                (image.prim(), image.bary(), image.x3(), image.light()),
                (y.prim(), y.bary(), y.x3(), y.light()),
                "the inverting reconnection keeps the path"
            );
            let own = source.target(&y) / forward.jacobian;
            sum += driver_weight(shift, step, &y, i, own) as f64;
        }
        let error = (sum - 1.0).abs();
        tally.max_error = tally.max_error.max(error);
        tally.violations += (error > TOLERANCE) as usize;
    }
}

/// The driver-level sums of `shift` over every step of `far-knot`.
fn tally<T: for<'s> Shift<SssDomain<'s>>>(shift: &T) -> Tally {
    let fx = fixture("far-knot");
    let mut tally = Tally::default();
    for k in 0..NEIGHBOURHOODS {
        let (receiver, neighbours) = fx.neighbourhood(NEIGHBOURS, 100 + k as u32);
        let step = Step {
            receiver: &receiver,
            neighbours: neighbours.iter().collect(),
            confidences: vec![1.0; NEIGHBOURS + 1],
            mis: &DefensivePairwise,
        };
        sum_weights(shift, &step, 300 + k as u32, &mut tally);
    }
    for (k, (previous, current)) in fx.temporal_pairs(TEMPORAL_PAIRS, 200).iter().enumerate() {
        let step = Step {
            receiver: current,
            neighbours: vec![previous],
            confidences: vec![1.0, TEMPORAL_CONFIDENCE],
            mis: &Gbh,
        };
        sum_weights(shift, &step, 400 + k as u32, &mut tally);
    }
    tally
}

#[test]
fn exact_index_weights_partition_unity_for_every_sample() {
    let tally = tally(&EXACT);
    println!("exact index, both ends: {tally:?}");
    assert!(
        tally.index_failures >= MIN_INDEX_FAILURES,
        "too few index failures to test: {tally:?}"
    );
    assert_eq!(tally.violations, 0, "{tally:?}");
    assert!(tally.max_error <= TOLERANCE, "{tally:?}");
}

/// The same sums catch the receiver-only index: its forward shifts and back-shifts disagree.
#[test]
fn receiver_only_index_is_caught_by_the_driver_weights() {
    let tally = tally(&ReceiverOnlyIndex);
    println!("receiver-only index: {tally:?}");
    assert!(
        tally.violations > 0,
        "negative control undetected: {tally:?}"
    );
}

/// The kit on the same scene: check 1 passes the exact policy and catches the receiver-only
/// index (a forward shift whose back-shift fails); check 4 passes both, which is why the
/// driver-level sums above are needed.
#[test]
fn round_trip_separates_the_policies_and_check_4_cannot() {
    let fx = fixture("far-knot");
    let pairs: Vec<_> = fx
        .spatial_pairs(24, 500)
        .into_iter()
        .chain(fx.temporal_pairs(24, 501))
        .collect();
    let case = ShiftCase {
        pairs: refs(&pairs),
        sampler: &UNSHADOWED,
        samples_per_pair: 32,
        seed: SEED,
    };
    let (receiver, neighbours) = fx.neighbourhood(NEIGHBOURS, 502);
    let mis_case = MisCase {
        receiver: &receiver,
        others: neighbours.iter().collect(),
        confidences: vec![1.0; NEIGHBOURS + 1],
        sampler: &UNSHADOWED,
        samples: 512,
        seed: SEED,
    };
    let exact = round_trip(&EXACT, &case, 1e-4);
    let control = round_trip(&ReceiverOnlyIndex, &case, 1e-4);
    println!("check 1, exact: {exact}\ncheck 1, receiver-only: {control}");
    assert!(exact.passed, "{exact}");
    assert!(!control.passed, "{control}");
    assert!(control.figure("asymmetric_failures").unwrap_or(0.0) > 0.0);
    for (name, report) in [
        (
            "exact",
            partition_of_unity(&EXACT, &DefensivePairwise, &mis_case, TOLERANCE),
        ),
        (
            "receiver-only",
            partition_of_unity(&ReceiverOnlyIndex, &DefensivePairwise, &mis_case, TOLERANCE),
        ),
    ] {
        println!("check 4, {name}: {report}");
        assert!(report.passed, "{name}: {report}");
    }
}
