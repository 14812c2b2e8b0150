//! The worked example of docs/adding-a-shift.md on both backends: `distant-reconnection`, a
//! shift added as one Rust file (`shifts/src/distant.rs`), its GLSL twin
//! (`shifts/glsl/distant.glsl`) and one registry line, in a preset of paper 001's shape
//! (candidates → temporal → one spatial pass with 4 neighbours, all with the new shift).
//!
//! Its conformance checks and unbiasedness test are in `shifts/tests/{conformance,unbiased}.rs`,
//! the function-level parity of every registered kind and the pass-level parity of this
//! preset's passes in `vulkan_reuse.rs`. Here: the whole run. Bit-exactness is impossible (a
//! few ulp of the device's transcendentals flip a resampling decision now and then, and that
//! pixel's history diverges), so, as in `lab/tests/vulkan_methods.rs`, with
//! `R = relMSE(GPU a, CPU a) / relMSE(CPU b, CPU a)` (seeds a = 1, b = 2), a diverged pixel-frame
//! counts like an independent replica and R estimates their fraction: R < 0.1 is required, and
//! the control R(GPU b) ≥ 0.1.

use engine::vulkan::testing::{backend_or_skip, rel_mse};
use engine::{Preset, RunConfig, ShiftKind};
use sss::scene::Scene;

const SIDE: u32 = 48;
const FRAMES: u32 = 8;

fn config(seed: u64, collect_diagnostics: bool) -> RunConfig {
    RunConfig {
        seed,
        frames: FRAMES,
        collect_diagnostics,
    }
}

/// The new shift runs in a preset on the CPU, where it both succeeds and fails (it is live, and
/// its threshold matters), and on the device, where the run is the CPU run of its seed up to
/// Monte Carlo noise.
#[test]
fn distant_reconnection_preset_runs_on_both_backends() {
    let mut scene = Scene::builtin("bumpy").expect("built-in scene");
    scene.camera = scene.camera.with_resolution(SIDE, SIDE);
    let kind = ShiftKind::named("distant-reconnection").expect("registered");
    let preset = Preset::single_shift(kind.name(), kind);
    let cpu_a = engine::run(&scene, &preset, &config(1, true)).unwrap();
    let diagnostics = cpu_a.diagnostics.as_ref().expect("collected");
    for pass in &diagnostics.failures {
        println!(
            "CPU {}: {} shifted, failure rate {:.3}",
            pass.label, pass.shifted, pass.rate
        );
        assert!(
            pass.shifted > 0 && 0.0 < pass.rate && pass.rate < 1.0,
            "{}: the shift never ran, never failed or never succeeded ({} shifted, rate {})",
            pass.label,
            pass.shifted,
            pass.rate
        );
    }
    let Some(backend) = backend_or_skip("distant_reconnection_preset_runs_on_both_backends") else {
        return;
    };
    let gpu_a = backend.run(&scene, &preset, &config(1, false)).unwrap();
    let gpu_b = backend.run(&scene, &preset, &config(2, false)).unwrap();
    let cpu_b = engine::run(&scene, &preset, &config(2, false)).unwrap();
    assert_eq!((gpu_a.nan_count, cpu_a.nan_count), (0, 0));
    let noise = rel_mse(&cpu_b, &cpu_a);
    let ratio = rel_mse(&gpu_a, &cpu_a) / noise;
    let control = rel_mse(&gpu_b, &cpu_a) / noise;
    println!(
        "{FRAMES} frames at {SIDE}×{SIDE}: relMSE(CPU b, CPU a) = {noise:.4e}; R(GPU a) = {ratio:.3e}; control R(GPU b) = {control:.4}"
    );
    assert!(noise > 0.0, "two CPU seeds gave the same images");
    assert!(
        ratio < 0.1,
        "R = {ratio} ≥ 0.1: the GPU run is not the CPU run of its seed"
    );
    assert!(
        control >= 0.1,
        "control: another seed gave R = {control} < 0.1"
    );
}
