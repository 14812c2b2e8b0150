use super::*;
use crate::with_threads;
use crate::{Run, run, run_pt};

fn scene(name: &str, size: u32) -> Scene {
    let mut scene = Scene::builtin(name).unwrap();
    scene.camera = scene.camera.with_resolution(size, size);
    scene
}

fn luminance_mean(image: &Image) -> f64 {
    sss::color::luminance(glam::DVec3::from_array(image.mean()))
}

fn bits(run: &Run) -> (Vec<u32>, Vec<u8>) {
    let pixels = run
        .frames
        .iter()
        .flat_map(|f| &f.pixels)
        .flat_map(|p| p.to_array().map(f32::to_bits));
    (
        pixels.collect(),
        bytemuck::cast_slice(&run.reservoirs).to_vec(),
    )
}

/// Same seed → bit-identical frames and final reservoirs with 1 and 2 threads, for a preset
/// with every pass kind (sequential, deferred index), the hybrid, the hybrid with
/// Rao-Blackwellised shading and the sequential preset with reciprocal pairs, diagnostics on.
/// Control: another seed changes the output, so the comparison can see a difference.
#[test]
fn output_is_bit_identical_for_any_thread_count() {
    let scene = scene("bumpy", 24);
    let config = RunConfig {
        seed: 3,
        frames: 4,
        collect_diagnostics: true,
    };
    let rao_blackwellised = Preset {
        name: "hybrid/shade=all".into(),
        shade: Shade::AllInputs,
        ..Preset::named("hybrid").unwrap()
    };
    let presets = [
        Preset::named("sequential").unwrap(),
        Preset::named("hybrid").unwrap(),
        rao_blackwellised,
        Preset::named("sequential")
            .unwrap()
            .with_pairs(shifts::preset::Pairs::Reciprocal),
    ];
    for preset in presets {
        let name = &preset.name;
        let one = with_threads(1, || run(&scene, &preset, &config).unwrap());
        let two = with_threads(2, || run(&scene, &preset, &config).unwrap());
        assert_eq!(bits(&one), bits(&two), "{name}: 1 vs 2 threads");
        assert_eq!(one.diagnostics, two.diagnostics, "{name}: diagnostics");
        assert_eq!(one.reservoirs.len(), 24 * 24);
        let other = RunConfig { seed: 4, ..config };
        let reseeded = with_threads(2, || run(&scene, &preset, &other).unwrap());
        assert_ne!(
            bits(&one).0,
            bits(&reseeded).0,
            "{name}: control, another seed"
        );
    }
}

/// Rao-Blackwellised shading changes only the colour of the shaded value: for every preset,
/// the reservoirs are bit-identical to [`Shade::Selected`]'s (later frames are unaffected),
/// every pixel has the same luminance up to f32 rounding (`p̂ = luminance(f)`, so
/// `Σ_i p̂(y_i)·m_i·W_i·J_i = w_sum = p̂(Y)·W`), and the colours differ in more than 10% of
/// the pixels (control: the option does something).
#[test]
fn rao_blackwellised_shading_keeps_reservoirs_and_luminance() {
    let scene = scene("bumpy", 24);
    let config = RunConfig {
        seed: 5,
        frames: 3,
        collect_diagnostics: false,
    };
    let luminance = |p: Vec3| sss::color::luminance(p.as_dvec3());
    for preset in Preset::all() {
        let rb = Preset {
            shade: Shade::AllInputs,
            ..preset.clone()
        };
        let (a, b) = (
            run(&scene, &preset, &config).unwrap(),
            run(&scene, &rb, &config).unwrap(),
        );
        assert_eq!(bits(&a).1, bits(&b).1, "{}: reservoirs", preset.name);
        let (mut differing, mut compared) = (0, 0);
        for (fa, fb) in a.frames.iter().zip(&b.frames) {
            for (pa, pb) in fa.pixels.iter().zip(&fb.pixels) {
                let (la, lb) = (luminance(*pa), luminance(*pb));
                assert!(
                    (la - lb).abs() <= 1e-4 * la.max(lb) + 1e-7,
                    "{}: luminance {la} vs {lb}",
                    preset.name
                );
                compared += 1;
                differing += (pa != pb) as u32;
            }
        }
        println!(
            "{}: {differing} of {compared} pixels change colour",
            preset.name
        );
        assert!(
            differing * 10 > compared,
            "{}: only {differing} of {compared} changed",
            preset.name
        );
    }
}

/// Every preset runs the 16-frame trajectory at 32×32 on `bumpy` and `half-shadow` with no
/// NaN, finite non-negative pixels, and an accumulated mean luminance within a factor 1.5 of
/// the path tracer's (16 spp per frame). A plausibility bound, not the unbiasedness test
/// (that is `lab/tests/unbiased.rs`).
#[test]
fn every_preset_renders_plausible_frames() {
    for name in ["bumpy", "half-shadow"] {
        let scene = scene(name, 32);
        let config = RunConfig {
            seed: 1,
            ..RunConfig::default()
        };
        let pt = luminance_mean(&run_pt(&scene, 16, &config).accumulated().unwrap());
        for preset in Preset::all() {
            let r = run(&scene, &preset, &config).unwrap();
            assert_eq!(r.frames.len(), 16);
            assert_eq!(r.nan_count, 0, "{name} {}", preset.name);
            for frame in &r.frames {
                assert_eq!((frame.width, frame.height), (32, 32));
                assert!(
                    frame
                        .pixels
                        .iter()
                        .all(|p| p.is_finite() && p.min_element() >= 0.0)
                );
            }
            let mean = luminance_mean(&r.accumulated().unwrap());
            println!(
                "{name} {}: mean luminance {mean:.5}, path tracer {pt:.5}",
                preset.name
            );
            assert!(
                (pt / 1.5..pt * 1.5).contains(&mean),
                "{name} {}: mean {mean} vs path tracer {pt}",
                preset.name
            );
        }
    }
}

/// Reuse telemetry on a tiny scene: it leaves every frame and the final reservoirs
/// bit-identical (diagnostics on vs off); its counts are consistent (origins account for
/// every pixel with a sample, failures by kind ≤ shifts, `m_0 ∈ [0, 1]`, `Σ 1/sharing` =
/// the number of distinct x2); every origin occurs. Control: reconnection copies x2, so
/// pixels share samples (mean sharing > 1), and the failure kinds sum to the diagnostics'
/// failure count of the last frame (a one-frame run, where both see the same frame).
#[test]
fn telemetry_observes_without_changing_the_output() {
    let scene = scene("bumpy", 24);
    let quiet = RunConfig {
        seed: 9,
        frames: 4,
        collect_diagnostics: false,
    };
    let loud = RunConfig {
        collect_diagnostics: true,
        ..quiet
    };
    for name in ["hybrid", "reconnection", "sequential"] {
        let preset = Preset::named(name).unwrap();
        let (a, b) = (
            run(&scene, &preset, &quiet).unwrap(),
            run(&scene, &preset, &loud).unwrap(),
        );
        assert_eq!(bits(&a), bits(&b), "{name}: telemetry changed the output");
        let t = b.diagnostics.unwrap().telemetry.unwrap();
        assert_eq!((t.frame, t.passes.len()), (3, preset.passes.len() - 1));
        let with_sample = b.reservoirs.iter().filter(|r| r.has_sample != 0).count();
        let mut origins = vec![0usize; preset.passes.len()];
        for o in t.origin.iter().flatten() {
            origins[*o as usize] += 1;
        }
        assert_eq!(origins.iter().sum::<usize>(), with_sample, "{name}");
        assert!(origins.iter().all(|&n| n > 0), "{name}: {origins:?}");
        for p in &t.passes {
            for (shifted, failed) in p.shifted.iter().zip(&p.failed_by) {
                assert!(failed.iter().sum::<u32>() <= *shifted);
            }
            assert!(
                p.canonical_mis
                    .iter()
                    .flatten()
                    .all(|m| (0.0..=1.0).contains(m))
            );
        }
        let distinct: f64 = t
            .sharing
            .iter()
            .filter(|&&k| k > 0)
            .map(|&k| 1.0 / k as f64)
            .sum();
        let keys: std::collections::HashSet<_> = b
            .reservoirs
            .iter()
            .filter(|r| r.has_sample != 0)
            .map(|r| (r.y.prim(), r.y.bary().x.to_bits(), r.y.bary().y.to_bits()))
            .collect();
        assert!((distinct - keys.len() as f64).abs() < 1e-6, "{name}");
        let mean_sharing = t.sharing.iter().map(|&k| k as f64).sum::<f64>() / with_sample as f64;
        println!("{name}: origins {origins:?}, mean sharing {mean_sharing:.3}");
        if name == "reconnection" {
            assert!(mean_sharing > 1.0, "control: {mean_sharing}");
        }
    }
    let one = RunConfig { frames: 1, ..loud };
    let d = run(&scene, &Preset::named("hybrid").unwrap(), &one)
        .unwrap()
        .diagnostics
        .unwrap();
    let t = d.telemetry.as_ref().unwrap();
    for (pass, f) in t.passes.iter().zip(&d.failures) {
        let by_kind: u64 = pass.failed_by.iter().flatten().map(|&n| n as u64).sum();
        let shifted: u64 = pass.shifted.iter().map(|&n| n as u64).sum();
        assert_eq!(shifted, f.shifted, "{}", f.label);
        assert_eq!(
            by_kind as f64,
            (f.rate * f.shifted as f64).round(),
            "{}",
            f.label
        );
    }
}

/// Timings name every pass; a bad configuration is a typed error.
#[test]
fn timings_and_configuration_errors() {
    let scene = scene("half-shadow", 8);
    let preset = Preset::named("sequential").unwrap();
    let r = run(
        &scene,
        &preset,
        &RunConfig {
            seed: 0,
            frames: 2,
            collect_diagnostics: false,
        },
    )
    .unwrap();
    let labels: Vec<&str> = r.timings.iter().map(|t| t.label.as_str()).collect();
    assert_eq!(labels.len(), preset.passes.len() + 2);
    assert_eq!((labels[0], labels[labels.len() - 1]), ("gbuffer", "shade"));
    assert!(r.diagnostics.is_none());
    assert!(r.seconds_per_frame("candidates").unwrap() >= 0.0);
    let zero = RunConfig {
        frames: 0,
        ..RunConfig::default()
    };
    assert!(matches!(
        run(&scene, &preset, &zero),
        Err(PipelineError::Config(_))
    ));
    let bad = Preset {
        name: "bad".into(),
        passes: preset.passes[1..].to_vec(),
        ..preset.clone()
    };
    assert!(matches!(
        run(&scene, &bad, &RunConfig::default()),
        Err(PipelineError::Preset(_))
    ));
}

/// Diagnostics on the flat `half-shadow` plane: a probe along the normal hits the plane once,
/// along a tangent never, so hits per probe estimate P(normal axis) = 0.5 (binomial z over
/// all N probes, two-sided α = 1e-3). Control: on the curved `bumpy` object the same test
/// rejects 0.5. Failure rates are ratios of counts, per-pass images lie in [0, 1], and the
/// hybrid map shows both shifts on `bumpy` [001 Fig. 4].
#[test]
fn diagnostics_count_hits_failures_and_hybrid_choices() {
    let config = RunConfig {
        seed: 2,
        frames: 4,
        collect_diagnostics: true,
    };
    let preset = Preset::named("hybrid").unwrap();
    let z = |d: &crate::Diagnostics| {
        let n = d.probes as f64;
        ((d.mean_hits_per_probe - 0.5) / (0.25 / n).sqrt(), n)
    };
    let flat = run(&scene("half-shadow", 24), &preset, &config).unwrap();
    let d = flat.diagnostics.unwrap();
    let (z_flat, n) = z(&d);
    assert!(z_flat.abs() < 3.2905, "α = 1e-3, N ≈ {n}: z = {z_flat}");
    let curved = run(&scene("bumpy", 24), &preset, &config).unwrap();
    let d = curved.diagnostics.unwrap();
    let (z_curved, n_curved) = z(&d);
    println!(
        "hits per probe: half-shadow z = {z_flat:.3} (N = {n}), bumpy {:.4} z = {z_curved:.1} (N = {n_curved})",
        d.mean_hits_per_probe
    );
    assert!(
        z_curved.abs() > 3.2905,
        "control: α = 1e-3, N ≈ {n}: z = {z_curved}"
    );
    assert_eq!(d.failures.len(), 2);
    for f in &d.failures {
        assert!(f.shifted > 0 && (0.0..=1.0).contains(&f.rate), "{f:?}");
        assert!(f.image.pixels.iter().all(|p| (0.0..=1.0).contains(&p.x)));
    }
    assert!(
        d.improved_fraction
            .pixels
            .iter()
            .all(|p| (0.0..=1.0).contains(&p.x))
    );
    let blue = d.hybrid_choice.pixels.iter().filter(|p| p.z > 0.5).count();
    let yellow = d.hybrid_choice.pixels.iter().filter(|p| p.x > 0.5).count();
    assert!(
        blue > 0 && yellow > 0,
        "hybrid map: {blue} reconnection, {yellow} delayed"
    );
    let names: std::collections::HashSet<String> = d.images().into_iter().map(|(n, _)| n).collect();
    assert_eq!(names.len(), 3 + d.failures.len());
    assert!(names.contains("failures-2-spatial4-hybrid"), "{names:?}");
}

/// On `passing` (the wax sphere moves every frame): the stream poses the scene at each frame,
/// and its output is bit-identical with 1 and 2 threads and with each frame's posed geometry
/// built anew or reused from the motion's keep (a second run of the same scene). Control: the
/// same scene with the sphere held at its frame-0 pose gives other frames.
#[test]
fn a_moving_scene_streams_deterministically() {
    let scene = scene("passing", 24);
    let config = RunConfig {
        seed: 3,
        frames: 4,
        collect_diagnostics: false,
    };
    for name in ["hybrid", "sequential"] {
        let preset = Preset::named(name).unwrap();
        let one = with_threads(1, || run(&scene, &preset, &config).unwrap());
        let two = with_threads(2, || run(&scene, &preset, &config).unwrap());
        assert_eq!(bits(&one), bits(&two), "{name}: 1 vs 2 threads");
        let reloaded = scene_with_fresh_motion(&scene);
        let again = run(&reloaded, &preset, &config).unwrap();
        assert_eq!(bits(&one), bits(&again), "{name}: geometry rebuilt");
        let at_rest = Scene {
            motion: None,
            ..scene.clone()
        };
        let still = run(&at_rest, &preset, &config).unwrap();
        assert_eq!(bits(&one).0[..24 * 24 * 3], bits(&still).0[..24 * 24 * 3]);
        assert_ne!(
            bits(&one).0,
            bits(&still).0,
            "{name}: control, the sphere at rest"
        );
    }
}

/// `scene` loaded again: a motion whose keep of posed geometries is empty.
fn scene_with_fresh_motion(scene: &Scene) -> Scene {
    Scene {
        camera: scene.camera.clone(),
        ..Scene::builtin(&scene.name).unwrap()
    }
}

/// `duplication=divides` ([`Duplication::Divides`]) changes only what temporal reuse weighs: the
/// first frame (no history) is bit-identical to the preset's, later frames differ, and the
/// output stays bit-identical for 1 and 2 threads.
#[test]
fn the_duplication_map_divides_only_the_history() {
    let scene = scene("bumpy", 24);
    let config = RunConfig {
        seed: 5,
        frames: 3,
        collect_diagnostics: false,
    };
    let hybrid = Preset::named("hybrid").unwrap();
    let divided = hybrid.clone().with_duplication(Duplication::Divides);
    let plain = run(&scene, &hybrid, &config).unwrap();
    let one = with_threads(1, || run(&scene, &divided, &config).unwrap());
    let two = with_threads(2, || run(&scene, &divided, &config).unwrap());
    assert_eq!(bits(&one), bits(&two), "1 vs 2 threads");
    assert_eq!(
        plain.frames[0].pixels, one.frames[0].pixels,
        "frame 0 has no history"
    );
    assert_ne!(
        plain.frames[2].pixels, one.frames[2].pixels,
        "control: the option acts"
    );
}
