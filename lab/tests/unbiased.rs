//! Unbiasedness, measured (issue #4; DESIGN §3 "Statistics", §7 regions): N independent replicas
//! of each ReSTIR SSS preset against a path-traced reference, per region, with the protocol of
//! `lab::bias`.
//!
//! * Scene: `bumpy` with its 16-frame trajectory, framed on the shadow edge across the top of the
//!   translucent object ([`scene`]), 32 × 32 pixels.
//! * Estimate: frame 15 of replicas `0..N` (seed = replica index); per region the mean luminance.
//! * Reference: the path tracer at frame 15, [`REFERENCE_BATCHES`] batches of
//!   [`SPP_PER_BATCH`] spp under [`REFERENCE_SEED`] (no replica uses it); s.e. from the batches.
//! * Test: 99% CI of the relative bias inside ±δ per region (equivalence), Holm across the four
//!   regions at α = 0.01 for "biased"; δ = [`PROTOCOL`]`.delta`, N = [`REPLICAS`].
//! * Negative controls (delayed reconnection without its Jacobian, without the y2↔x3 visibility
//!   test, a hybrid that ignores the criterion on the offset path) must be Biased in at least one
//!   region under the same protocol; the visibility control runs at seed 001's temporal cap 20
//!   ([`SEED_001_TEMPORAL_CAP`] says why).
//!
//! * Backends: the four unbiased presets run on the CPU backend and again on the Vulkan backend
//!   (`vulkan_*`) against the same CPU reference; without Vulkan the `vulkan_*` tests print why
//!   and pass, unless `RESHIFT_REQUIRE_VULKAN=1`, which makes them fail. The deferred-index
//!   measurement and the controls run on the CPU only: a preset costs ~150 s on lavapipe (2
//!   cores) against ~20 s on the CPU backend. The protocol's power is the controls' (CPU) result;
//!   the controls' GPU twins agree with the CPU's shift for shift (`vulkan_reuse.rs`, 0
//!   mismatches), so they would be detected on the device as well.
//!
//! * Rao-Blackwellised shading (`Shade::AllInputs`): per channel and region, paired against the
//!   selected shading of the same replicas ([`PAIRED`]), with its own negative control.
//!
//! Run with `--nocapture` to see the tables (bias, CI, half-width, p-value, Holm, verdict).

use std::sync::OnceLock;
use std::time::Instant;

use engine::vulkan::testing::backend_or_skip;
use engine::{Backend, Preset, RunConfig, Shade, ShiftKind};
use glam::Vec3;
use lab::bias::{
    BiasRow, Protocol, RegionSummary, Table, bias_rows, reference_images, replica_images, summarize,
};
use lab::regions::{Region, Regions};
use rayon::prelude::*;
use restir::stats::{Summary, Verdict};
use shifts::preset::TEMPORAL_CAP;
use sss::integrator::pt::{self, PtSettings};
use sss::scene::{Camera, FRAMES, GBuffer, Scene};

/// Image side in pixels.
const SIDE: u32 = 32;
/// The frame whose bias is measured: the last of the trajectory.
const FRAME: u32 = FRAMES - 1;
/// Replicas per method (the same for presets and controls).
const REPLICAS: u64 = 192;
/// δ = 10% on the relative bias of each region mean; α = 0.01 (99% CIs, Holm across regions).
///
/// Power: δ must exceed the 99% CI half-width of a correct preset and lie below the bias a
/// control shows. The shadowed region decides both: its mean is ~3.5% of the lit one and its
/// per-replica relative spread 0.2–0.3, so at N = 192 its CI half-width is 3.5–5.2% (the other
/// regions 1.1–2.8%), while visibility leaking through delayed reconnection adds ~+9% there.
/// δ = 15% was tried first and called that control "unbiased" (its CI lay inside ±15%).
const PROTOCOL: Protocol = Protocol {
    delta: 0.10,
    alpha: 0.01,
};
/// The temporal cap of the visibility control: seed 001's. With the presets' cap 3 the history
/// carries the leak into fewer frames and the control's shadowed bias falls to +5.3%, 99% CI
/// [+0.03%, +10.5%] at N = 192 (Inconclusive, Holm not rejecting): this protocol's power
/// against a visibility leak is shown at cap 20 (+9%) only; at cap 3 a leak of that kind stays
/// below δ = 10%.
const SEED_001_TEMPORAL_CAP: f32 = 20.0;
const REFERENCE_BATCHES: u32 = 64;
const SPP_PER_BATCH: u32 = 32;
/// Far above every replica seed, so reference and replicas draw from disjoint streams.
const REFERENCE_SEED: u64 = 1 << 40;
/// Keys the light samples of the region classification.
const REGIONS_SEED: u64 = 0x5E61;

/// `bumpy` (scenes/bumpy.toml) with its eye trajectory, the targets raised by 0.25 and the
/// field of view narrowed from 35° to 14°: the view holds the top of the object, where the
/// occluder's shadow edge crosses it (lit left, penumbra middle, shadowed right).
fn scene() -> Scene {
    let bumpy = Scene::builtin("bumpy").expect("built-in scene");
    let lift = Vec3::new(0.0, 0.25, 0.0);
    let camera = Camera::new(
        [SIDE, SIDE],
        14.0,
        [Vec3::new(0.0, 1.1, 3.0), Vec3::new(0.25, 1.15, 2.9)],
        [
            Vec3::new(0.0, 0.5, 0.0) + lift,
            Vec3::new(0.02, 0.5, 0.0) + lift,
        ],
        Vec3::Y,
        bumpy.camera.jittered(),
    );
    Scene { camera, ..bumpy }
}

/// What every test shares, computed once per test run.
struct Setup {
    scene: Scene,
    regions: Regions,
    reference: Vec<RegionSummary>,
}

fn setup() -> &'static Setup {
    static SETUP: OnceLock<Setup> = OnceLock::new();
    SETUP.get_or_init(|| {
        let start = Instant::now();
        let scene = scene();
        let regions = Regions::classify(&scene, &GBuffer::render(&scene, FRAME), REGIONS_SEED);
        let reference = reference_images(
            &scene,
            FRAME,
            REFERENCE_BATCHES,
            SPP_PER_BATCH,
            REFERENCE_SEED,
        )
        .expect("reference settings");
        assert_eq!(reference.nonfinite, 0, "non-finite reference samples");
        let reference = summarize(&reference.luminance, &regions);
        let regions_present: Vec<Region> = reference.iter().map(|r| r.region).collect();
        assert_eq!(
            regions_present,
            Region::ALL,
            "the framing must show every region"
        );
        println!(
            "reference: path tracer, frame {FRAME}, {REFERENCE_BATCHES} batches × {SPP_PER_BATCH} spp, {:.1} s",
            start.elapsed().as_secs_f64()
        );
        for r in &reference {
            println!(
                "  {:<11} {:>4} px  mean {:.5} ± {:.5} ({:.2}%)",
                r.region,
                r.pixels,
                r.summary.mean,
                r.summary.std_err,
                100.0 * r.summary.std_err / r.summary.mean
            );
        }
        Setup {
            scene,
            regions,
            reference,
        }
    })
}

/// The bias table of `preset` over [`REPLICAS`] replicas on `backend` (printed).
fn measure(backend: &Backend, preset: &Preset) -> Vec<BiasRow> {
    let setup = setup();
    let start = Instant::now();
    let images =
        replica_images(backend, &setup.scene, preset, REPLICAS, FRAMES).expect("preset runs");
    assert_eq!(
        images.nonfinite, 0,
        "{}: non-finite shaded values",
        preset.name
    );
    let rows = bias_rows(
        &preset.name,
        &summarize(&images.luminance, &setup.regions),
        &setup.reference,
        &PROTOCOL,
    );
    println!(
        "{} on {backend} — N = {REPLICAS}, δ = {}%, α = {} ({:.1} s)\n{}",
        preset.name,
        100.0 * PROTOCOL.delta,
        PROTOCOL.alpha,
        start.elapsed().as_secs_f64(),
        Table(&rows)
    );
    assert_eq!(rows.len(), Region::ALL.len(), "{}", Table(&rows));
    rows
}

/// Every region Unbiased: the 99% CI of the relative bias inside ±δ.
fn assert_unbiased(backend: &Backend, name: &str) {
    let preset = Preset::named(name).expect("registered preset");
    let rows = measure(backend, &preset);
    let failing: Vec<&BiasRow> = rows
        .iter()
        .filter(|r| r.verdict != Verdict::Unbiased)
        .collect();
    assert!(
        failing.is_empty(),
        "{name} on {backend} not shown unbiased (δ = {}, α = {}, N = {REPLICAS}) in {:?}:\n{}",
        PROTOCOL.delta,
        PROTOCOL.alpha,
        failing.iter().map(|r| r.region).collect::<Vec<_>>(),
        Table(&rows)
    );
}

/// A negative control: Biased in at least one region under the same protocol, with the temporal
/// confidence cap `cap`.
fn assert_detected(backend: &Backend, shift: ShiftKind, cap: f32) {
    let preset = Preset::single_shift(shift.name(), shift).with_temporal_cap(cap);
    let rows = measure(backend, &preset);
    assert!(
        rows.iter().any(|r| r.verdict == Verdict::Biased),
        "negative control {} on {backend} not detected (δ = {}, α = {}, N = {REPLICAS}):\n{}",
        shift.name(),
        PROTOCOL.delta,
        PROTOCOL.alpha,
        Table(&rows)
    );
}

/// The deferred intersection index is seed 001's documented, slightly biased choice: its bias is
/// measured and printed, not asserted away; the run itself must be sound (no NaN, every region).
fn measure_sequential_deferred(backend: &Backend) {
    let rows = measure(
        backend,
        &Preset::named("sequential").expect("registered preset"),
    );
    let within: Vec<Region> = rows
        .iter()
        .filter(|r| r.verdict == Verdict::Unbiased)
        .map(|r| r.region)
        .collect();
    println!(
        "sequential (deferred index) on {backend}: within δ = {}% in {within:?}",
        100.0 * PROTOCOL.delta
    );
}

/// `$cpu` runs `$check` on the CPU backend, `$vulkan` on the Vulkan backend (or skips).
macro_rules! on_both_backends {
    ($cpu:ident, $vulkan:ident, $check:expr) => {
        #[test]
        fn $cpu() {
            let check: fn(&Backend) = $check;
            check(&Backend::Cpu);
        }

        #[test]
        fn $vulkan() {
            let check: fn(&Backend) = $check;
            if let Some(backend) = backend_or_skip(stringify!($vulkan)) {
                check(&backend);
            }
        }
    };
}

on_both_backends!(
    reconnection_is_unbiased_per_region,
    vulkan_reconnection_is_unbiased_per_region,
    |b| assert_unbiased(b, "reconnection")
);
on_both_backends!(
    delayed_is_unbiased_per_region,
    vulkan_delayed_is_unbiased_per_region,
    |b| assert_unbiased(b, "delayed")
);
on_both_backends!(
    hybrid_is_unbiased_per_region,
    vulkan_hybrid_is_unbiased_per_region,
    |b| assert_unbiased(b, "hybrid")
);
on_both_backends!(
    sequential_exact_is_unbiased_per_region,
    vulkan_sequential_exact_is_unbiased_per_region,
    |b| assert_unbiased(b, "sequential-exact")
);
#[test]
fn sequential_deferred_bias_is_measured() {
    measure_sequential_deferred(&Backend::Cpu);
}

#[test]
fn control_delayed_without_jacobian_is_detected() {
    assert_detected(
        &Backend::Cpu,
        ShiftKind::DelayedWithoutJacobian,
        TEMPORAL_CAP,
    );
}

#[test]
fn control_delayed_without_visibility_is_detected() {
    assert_detected(
        &Backend::Cpu,
        ShiftKind::DelayedWithoutVisibility,
        SEED_001_TEMPORAL_CAP,
    );
}

#[test]
fn control_hybrid_ignoring_criterion_is_detected() {
    assert_detected(
        &Backend::Cpu,
        ShiftKind::HybridIgnoringCriterion,
        TEMPORAL_CAP,
    );
}

/// The paired test of Rao-Blackwellised shading below: δ = 5% of the reference's channel mean
/// per region, α = 0.01 (99% CIs, Holm across the 4 regions of a channel), N = [`REPLICAS`]
/// pairs.
///
/// Power: pairing removes the noise both shadings share (same seeds, same reservoirs), so the
/// difference's spread is the selection's colour noise alone. At N = 192 the widest 99% CI
/// half-width is the shadowed region's blue (mean 0.0032; half-width 2.0% on `hybrid`, 2.2% on
/// `reconnection`, 1.4% on `sequential-exact`); δ = 2% would leave those cells inconclusive.
/// δ = 5% is more than twice the widest half-width, and the control below (+1.5δ = +7.5% on
/// blue) then lies beyond δ with its whole CI (measured: [+5.7%, +10.3%] at worst).
const PAIRED: Protocol = Protocol {
    delta: 0.05,
    alpha: 0.01,
};

/// Per region and channel R, G, B: the path tracer's reference (the batches of [`setup`]'s
/// reference, per channel), computed once.
fn channel_reference() -> &'static [Vec<RegionSummary>; 3] {
    static REFERENCE: OnceLock<[Vec<RegionSummary>; 3]> = OnceLock::new();
    REFERENCE.get_or_init(|| {
        let setup = setup();
        let gbuffer = GBuffer::render(&setup.scene, FRAME);
        let batches: Vec<Vec<Vec3>> = (0..REFERENCE_BATCHES)
            .map(|b| {
                pt::render(
                    &setup.scene,
                    &gbuffer,
                    &PtSettings::default(),
                    REFERENCE_SEED,
                    b * SPP_PER_BATCH,
                    SPP_PER_BATCH,
                )
                .pixels
                .iter()
                .map(|p| p.as_vec3())
                .collect()
            })
            .collect();
        std::array::from_fn(|c| summarize(&channel(&batches, c, 1.0), &setup.regions))
    })
}

/// Channel `c` of every image, scaled by `scale`.
fn channel(images: &[Vec<Vec3>], c: usize, scale: f64) -> Vec<Vec<f64>> {
    images
        .iter()
        .map(|i| i.iter().map(|p| scale * p[c] as f64).collect())
        .collect()
}

/// Frame 15 of replicas `0..REPLICAS` of `preset` on the CPU (replica `i` with seed `i`).
fn last_frames(preset: &Preset) -> Vec<Vec<Vec3>> {
    let setup = setup();
    (0..REPLICAS)
        .into_par_iter()
        .map(|seed| {
            let config = RunConfig {
                seed,
                frames: FRAMES,
                collect_diagnostics: false,
            };
            let mut run = engine::run(&setup.scene, preset, &config).expect("preset runs");
            assert_eq!(run.nan_count, 0, "{}: non-finite values", preset.name);
            run.frames.pop().expect("a frame").pixels
        })
        .collect()
}

/// The paired bias rows of channel `c`: per replica `scale·RB − selected`, per region, as a
/// relative "bias" against the reference's channel mean (taken as exact: the pairs' difference
/// is what is tested, not the reference).
fn paired_rows(
    method: &str,
    c: usize,
    rb: &[Vec<Vec3>],
    selected: &[Vec<Vec3>],
    scale: f64,
) -> Vec<BiasRow> {
    let setup = setup();
    let reference = &channel_reference()[c];
    let differences: Vec<Vec<f64>> = channel(rb, c, scale)
        .iter()
        .zip(&channel(selected, c, 1.0))
        .map(|(a, b)| a.iter().zip(b).map(|(x, y)| x - y).collect())
        .collect();
    // mean(RB − selected) + reference mean, against the reference mean exactly: the relative
    // bias of these is the paired difference relative to the channel's mean.
    let shifted: Vec<RegionSummary> = summarize(&differences, &setup.regions)
        .into_iter()
        .zip(reference)
        .map(|(d, r)| RegionSummary {
            summary: Summary {
                mean: d.summary.mean + r.summary.mean,
                ..d.summary
            },
            ..d
        })
        .collect();
    let exact: Vec<RegionSummary> = reference
        .iter()
        .map(|r| RegionSummary {
            summary: Summary::exact(r.summary.mean),
            ..*r
        })
        .collect();
    bias_rows(
        &format!("{method} {} − selected", ["R", "G", "B"][c]),
        &shifted,
        &exact,
        &PAIRED,
    )
}

/// Rao-Blackwellised shading (`restir:<name>/shade=all`) has, given the inputs of the last reuse
/// pass, the expectation of `f(Y)·W`, keeps the reservoirs (so every frame's inputs) and the
/// luminance (exactly: `engine` `cpu.rs`), and re-distributes the colour. So its test is per
/// channel and paired: replicas `0..N` of the preset shaded both ways share their seeds and
/// reservoirs; per channel and region the 99% CI of `mean(RB) − mean(selected)` must lie inside
/// ±[`PAIRED`]`.delta` of the reference's channel mean. Each shading's per-channel comparison
/// with the path tracer (δ = 10%) is printed for information. Negative control: the RB images
/// with blue scaled by `1 + 1.5δ` must be Biased in some region.
fn assert_rao_blackwellised_matches_selected(name: &str) {
    let start = Instant::now();
    let selected = Preset::named(name).expect("registered preset");
    let rb = Preset {
        shade: Shade::AllInputs,
        ..selected.clone()
    };
    let method = format!("{name}/shade=all");
    let (rb_frames, selected_frames) = (last_frames(&rb), last_frames(&selected));
    let mut rows = Vec::new();
    for c in 0..3 {
        let paired = paired_rows(&method, c, &rb_frames, &selected_frames, 1.0);
        let against_pt = bias_rows(
            &format!("{method} {} vs path tracer", ["R", "G", "B"][c]),
            &summarize(&channel(&rb_frames, c, 1.0), &setup().regions),
            &channel_reference()[c],
            &PROTOCOL,
        );
        println!(
            "{method} ({:.1} s), N = {REPLICAS} pairs\npaired, δ = {}%, α = {}:\n{}\nagainst the path tracer, δ = {}% (information):\n{}",
            start.elapsed().as_secs_f64(),
            100.0 * PAIRED.delta,
            PAIRED.alpha,
            Table(&paired),
            100.0 * PROTOCOL.delta,
            Table(&against_pt)
        );
        assert_eq!(paired.len(), Region::ALL.len(), "{}", Table(&paired));
        rows.extend(paired);
    }
    assert!(
        rows.iter().all(|r| r.verdict == Verdict::Unbiased),
        "{method} differs from the selected shading (δ = {}, α = {}, N = {REPLICAS}):\n{}",
        PAIRED.delta,
        PAIRED.alpha,
        Table(&rows)
    );
    let control = paired_rows(
        &format!("{method} × (1 + 1.5δ)"),
        2,
        &rb_frames,
        &selected_frames,
        1.0 + 1.5 * PAIRED.delta,
    );
    println!("negative control, blue × (1 + 1.5δ):\n{}", Table(&control));
    assert!(
        control.iter().any(|r| r.verdict == Verdict::Biased),
        "negative control not detected:\n{}",
        Table(&control)
    );
}

#[test]
fn hybrid_rao_blackwellised_matches_selected_per_channel() {
    assert_rao_blackwellised_matches_selected("hybrid");
}

#[test]
fn reconnection_rao_blackwellised_matches_selected_per_channel() {
    assert_rao_blackwellised_matches_selected("reconnection");
}

#[test]
fn sequential_exact_rao_blackwellised_matches_selected_per_channel() {
    assert_rao_blackwellised_matches_selected("sequential-exact");
}
