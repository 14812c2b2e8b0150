//! Every preset and so every pass kernel of the engine, and the SVGF denoiser, once, under the
//! Khronos
//! validation layer with synchronization validation: any error (an invalid use, a missing
//! barrier) fails the test with the layer's message. The negative control (a frame recorded
//! without one of its barriers is caught) is `renderer::tests` in the library; the kernels of the
//! `methods` crate are validated in `methods/tests/vulkan_validation.rs`.
//!
//! Small on purpose: validation multiplies lavapipe's time, so the run is 32×24 pixels, 2
//! frames. Skips without Vulkan or without the layer, unless `RESHIFT_REQUIRE_VULKAN=1`.

use engine::denoise::{Guide, svgf};
use engine::vulkan::Checks;
use engine::vulkan::testing::{assert_no_unreported_errors, validated, validated_or_skip};
use engine::{Preset, RunConfig, Shade, run_pt};
use sss::scene::Scene;

const WIDTH: u32 = 32;
const HEIGHT: u32 = 24;
const FRAMES: u32 = 2;
const SEED: u64 = 5;

fn scene() -> Scene {
    let mut scene = Scene::builtin("bumpy").expect("built-in scene");
    scene.camera = scene.camera.with_resolution(WIDTH, HEIGHT);
    scene
}

#[test]
fn every_preset_pass_and_the_denoiser_pass_sync_validation() {
    let Some(mut renderer) = validated_or_skip("sync_validation", Checks::Sync) else {
        return;
    };
    let scene = scene();
    let config = RunConfig {
        seed: SEED,
        frames: FRAMES,
        collect_diagnostics: true,
    };
    for preset in Preset::all() {
        for shade in [Shade::Selected, Shade::AllInputs] {
            let preset = Preset {
                shade,
                ..preset.clone()
            };
            let what = format!("restir:{} ({shade:?})", preset.name);
            validated(&what, renderer.run(&scene, &preset, &config));
        }
    }
    // The denoiser stage's device pass: SVGF over the frames of a path-traced trajectory (traced
    // on the CPU: the path tracer's kernel is the `methods` crate's).
    let guides = Guide::trajectory(&scene, FRAMES);
    let frames = run_pt(&scene, 1, &config).frames;
    validated(
        "svgf",
        renderer.svgf(&guides, &frames, &svgf::Params::default()),
    );
    // Errors were returned above.
    assert_no_unreported_errors(&renderer);
}

/// Under best-practice validation, a `restir:sequential` run draws no warning about memory
/// allocations (many small `vkAllocateMemory` calls, too many allocations, small dedicated
/// ones): buffers are sub-allocated from large blocks.
#[test]
fn restir_sequential_has_no_allocation_warnings() {
    let Some(mut renderer) = validated_or_skip("best_practices", Checks::BestPractices) else {
        return;
    };
    let preset = Preset::named("sequential").expect("registered preset");
    let config = RunConfig {
        seed: SEED,
        frames: FRAMES,
        collect_diagnostics: false,
    };
    validated(
        "restir:sequential",
        renderer.run(&scene(), &preset, &config),
    );
    let messages = renderer.context().validation_messages();
    for m in &messages {
        eprintln!("best_practices: {:?} {}: {}", m.severity, m.id, m.text);
    }
    let allocation: Vec<_> = messages
        .iter()
        .filter(|m| m.id.contains("AllocateMemory") || m.id.contains("BindMemory"))
        .collect();
    assert!(allocation.is_empty(), "{allocation:#?}");
}
