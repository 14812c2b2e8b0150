//! Runs the conformance kit (`restir::check`, checks 1–6) on a shift over the toy scene: the
//! glue a user copies when checking their own shift (see `docs/adding-a-shift.md`).

use super::chain::{ChainConfig, ReplicaOutputs, ToyScene, run_replicas, ucw_expected};
use super::{LinearSampler, ToyPixel};
use crate::check::{
    CheckReport, MisCase, ShiftCase, finite_difference_jacobian, partition_of_unity,
    reciprocal_jacobian, round_trip, ucw_histogram, unbiasedness,
};
use crate::mis::MisScheme;
use crate::resample::ResampleError;
use crate::shift::Shift;

/// Round-trip tolerance in local coordinates (the samples are `f32` points of [0, 1]²).
pub const ROUND_TRIP_TOLERANCE: f64 = 1e-4;
/// Relative tolerance of `J_{s→d} · J_{d→s} = 1` (f32 Jacobians).
pub const RECIPROCAL_TOLERANCE: f64 = 1e-4;
/// Finite differences: relative step and relative tolerance (DESIGN §3: 1e-3).
pub const FD_RELATIVE_STEP: f64 = 2e-2;
pub const FD_TOLERANCE: f64 = 1e-3;
/// `|Σ m_j − 1|` tolerance (f32 weights).
pub const PARTITION_TOLERANCE: f64 = 1e-5;

/// Sizes and levels of a kit run.
#[derive(Clone, Copy, Debug)]
pub struct KitConfig {
    pub chain: ChainConfig,
    /// Independent replicas for checks 5–6.
    pub replicas: usize,
    pub seed: u64,
    /// The UCW histogram uses `bins × bins` cells per pixel.
    pub bins: usize,
    /// Equivalence tolerance δ on the relative bias of the image total (check 6).
    pub delta: f64,
    /// Level α of checks 5 and 6 (Holm family-wise in check 6; CI confidence 1 − α).
    pub alpha: f64,
    /// Points per pair and direction for checks 1–3, and per receiver for check 4.
    pub geometry_samples: usize,
}

impl Default for KitConfig {
    fn default() -> Self {
        Self {
            chain: ChainConfig::default(),
            replicas: 4000,
            seed: 1,
            bins: 3,
            delta: 0.03,
            alpha: 1e-3,
            geometry_samples: 300,
        }
    }
}

/// Pairs of domains the geometric checks use: spatial neighbours in the last frame and the
/// temporal pair (previous frame → last frame) of every fifth pixel.
fn pairs(scene: &ToyScene) -> Vec<(&ToyPixel, &ToyPixel)> {
    let last = scene.last_frame();
    let count = last.len();
    let previous = &scene.frames[scene.frames.len().saturating_sub(2)];
    (0..count)
        .step_by(5)
        .flat_map(|p| [(&last[p], &last[(p + 1) % count]), (&previous[p], &last[p])])
        .collect()
}

/// Checks 1–3 of `shift` on the scene.
pub fn geometry_reports(
    shift: &dyn Shift<ToyPixel>,
    scene: &ToyScene,
    cfg: &KitConfig,
) -> Vec<CheckReport> {
    let case = ShiftCase {
        pairs: pairs(scene),
        sampler: &LinearSampler,
        samples_per_pair: cfg.geometry_samples,
        seed: cfg.seed,
    };
    vec![
        round_trip(shift, &case, ROUND_TRIP_TOLERANCE),
        reciprocal_jacobian(shift, &case, RECIPROCAL_TOLERANCE),
        finite_difference_jacobian(shift, &case, FD_RELATIVE_STEP, FD_TOLERANCE),
    ]
}

/// Check 4 of `shift` with `mis`: one receiver of the last frame, five spatial domains spread
/// over the image and its previous-frame twin, with confidences from 1 to 40.
pub fn mis_report(
    shift: &dyn Shift<ToyPixel>,
    mis: &dyn MisScheme,
    scene: &ToyScene,
    cfg: &KitConfig,
) -> CheckReport {
    let last = scene.last_frame();
    let count = last.len();
    let previous = &scene.frames[scene.frames.len().saturating_sub(2)];
    let receiver = count / 2;
    let mut others: Vec<&ToyPixel> = [1, 2, count / 3, count - 1, 0]
        .iter()
        .map(|&p| &last[(receiver + p) % count])
        .collect();
    others.push(&previous[receiver]);
    let case = MisCase {
        receiver: &last[receiver],
        confidences: vec![2.0, 8.0, 1.0, 40.0, 3.0, 0.5, 20.0][..others.len() + 1].to_vec(),
        others,
        sampler: &LinearSampler,
        samples: 4 * cfg.geometry_samples,
        seed: cfg.seed,
    };
    partition_of_unity(shift, mis, &case, PARTITION_TOLERANCE)
}

/// Replica outputs of the chain with `shift` and spatial scheme `mis`.
pub fn chain_outputs(
    shift: &dyn Shift<ToyPixel>,
    mis: &dyn MisScheme,
    scene: &ToyScene,
    cfg: &KitConfig,
) -> Result<ReplicaOutputs, ResampleError> {
    run_replicas(scene, shift, mis, cfg.replicas, cfg.seed, cfg.bins)
}

/// Checks 5–6 on chain outputs.
pub fn chain_reports(
    outputs: &ReplicaOutputs,
    scene: &ToyScene,
    cfg: &KitConfig,
) -> Vec<CheckReport> {
    let reference: Vec<f64> = scene
        .last_frame()
        .iter()
        .map(ToyPixel::integrand_integral)
        .collect();
    vec![
        ucw_histogram(
            &outputs.ucw_cells,
            &ucw_expected(scene, outputs.bins),
            cfg.alpha,
        ),
        unbiasedness(&outputs.estimates, &reference, cfg.delta, cfg.alpha),
    ]
}

/// Checks 1–6 of `shift` with spatial scheme `mis` on a toy scene built from `cfg.chain`.
pub fn run_kit(
    shift: &dyn Shift<ToyPixel>,
    mis: &dyn MisScheme,
    cfg: &KitConfig,
) -> Result<Vec<CheckReport>, ResampleError> {
    let scene = ToyScene::new(cfg.chain);
    let mut reports = geometry_reports(shift, &scene, cfg);
    reports.push(mis_report(shift, mis, &scene, cfg));
    let outputs = chain_outputs(shift, mis, &scene, cfg)?;
    reports.extend(chain_reports(&outputs, &scene, cfg));
    Ok(reports)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::check::{CheckName, negative_control};
    use crate::mis::{ConfidenceOnly, DefensivePairwise, Gbh, Pairwise};
    use crate::toy::Supports;
    use crate::toy::shifts::{
        AsymmetricRejection, BackShiftBug, NoBackShift, Replay, Scaling, ScalingUnitJacobian,
        ShortcutBug, Translation, WrongShortcut,
    };

    fn correct_shifts() -> [(&'static str, &'static dyn Shift<ToyPixel>); 3] {
        [
            ("translation", &Translation),
            ("scaling", &Scaling),
            ("replay", &Replay),
        ]
    }

    fn differing() -> KitConfig {
        KitConfig {
            chain: ChainConfig {
                supports: Supports::Differing,
                ..ChainConfig::default()
            },
            ..KitConfig::default()
        }
    }

    /// Checks 1–6 pass for every correct shift × unbiased scheme, on pixel-dependent supports.
    /// Check 5: α = 0.01, N = 3000 replicas, 36 pixels × 9 bins. Check 6: Holm at α = 0.01 over
    /// 36 pixels and the image total's 99% CI inside δ = ±2%, N = 3000. Negative controls:
    /// `broken_shifts_are_caught_by_named_checks` runs the same checks.
    #[test]
    fn correct_shifts_pass_every_check_under_every_unbiased_scheme() {
        let cfg = differing();
        let scene = ToyScene::new(cfg.chain);
        for (name, shift) in correct_shifts() {
            for report in geometry_reports(shift, &scene, &cfg) {
                assert!(report.passed, "{name}: {report}");
            }
            for mis in [&Gbh as &dyn MisScheme, &Pairwise, &DefensivePairwise] {
                let mut reports = vec![mis_report(shift, mis, &scene, &cfg)];
                let outputs = chain_outputs(shift, mis, &scene, &cfg).unwrap();
                reports.extend(chain_reports(&outputs, &scene, &cfg));
                for report in reports {
                    assert!(report.passed, "{name} + {}: {report}", mis.name());
                }
            }
        }
    }

    /// Check 7: each broken shift fails at least one named check of the same kit (same N, α, δ).
    #[test]
    fn broken_shifts_are_caught_by_named_checks() {
        let cfg = differing();
        let broken: [(&str, &dyn Shift<ToyPixel>, &[CheckName]); 6] = [
            (
                "scaling with J = 1",
                &ScalingUnitJacobian,
                &[CheckName::FiniteDifferenceJacobian],
            ),
            (
                "MIS at the un-shifted point",
                &NoBackShift {
                    inner: Translation,
                    bug: BackShiftBug::Unshifted,
                },
                &[CheckName::PartitionOfUnity],
            ),
            (
                "MIS without the back-shift Jacobian",
                &NoBackShift {
                    inner: Scaling,
                    bug: BackShiftBug::NoJacobian,
                },
                &[CheckName::Unbiasedness],
            ),
            (
                "asymmetric rejection",
                &AsymmetricRejection,
                &[CheckName::RoundTrip],
            ),
            (
                "batched back-shift without the shift",
                &WrongShortcut(ShortcutBug::UnshiftedBatch),
                &[CheckName::PartitionOfUnity],
            ),
            (
                "source target of the shifted point",
                &WrongShortcut(ShortcutBug::SourceTargetOfShifted),
                &[CheckName::PartitionOfUnity],
            ),
        ];
        for (name, shift, must_catch) in broken {
            let reports = run_kit(shift, &DefensivePairwise, &cfg).unwrap();
            let control = negative_control(name, &reports);
            println!("{control}");
            assert!(control.passed, "{control}\n{reports:#?}");
            for check in must_catch {
                let report = reports.iter().find(|r| r.check == *check).unwrap();
                assert!(!report.passed, "{name} not caught by {check}: {report}");
            }
        }
    }

    /// `1/M` declares itself biased unless supports agree: with replay (a bijection of Ω) on equal
    /// supports it passes checks 4–6; on differing supports checks 4 and 6 reject it and the
    /// image total's 99% CI lies below −δ (darkening). N = 3000, α = 0.01, δ = 2%.
    #[test]
    fn confidence_only_is_biased_exactly_when_supports_differ() {
        assert!(!ConfidenceOnly.bias().is_unbiased_when_supports_differ());
        let equal = KitConfig::default();
        let scene = ToyScene::new(equal.chain);
        let mut reports = vec![mis_report(&Replay, &ConfidenceOnly, &scene, &equal)];
        reports.extend(chain_reports(
            &chain_outputs(&Replay, &ConfidenceOnly, &scene, &equal).unwrap(),
            &scene,
            &equal,
        ));
        for report in &reports {
            assert!(report.passed, "1/M, equal supports: {report}");
        }
        let cfg = differing();
        let reports = run_kit(&Replay, &ConfidenceOnly, &cfg).unwrap();
        for check in [CheckName::PartitionOfUnity, CheckName::Unbiasedness] {
            let report = reports.iter().find(|r| r.check == check).unwrap();
            assert!(!report.passed, "1/M on differing supports passed {report}");
        }
        let unbiasedness = reports
            .iter()
            .find(|r| r.check == CheckName::Unbiasedness)
            .unwrap();
        assert!(
            unbiasedness.figure("ci_high").unwrap() < -cfg.delta,
            "{unbiasedness}"
        );
    }
}
