//! The seed methods `image-space` [002] and `adaptive` [004] render every built-in scene on both
//! backends, and the Vulkan images agree with the CPU's of the same seed. Per-pixel parity on
//! small scenes, with negative controls, is `engine/tests/vulkan_image_space.rs` and
//! `engine/tests/vulkan_adaptive.rs`.
//!
//! Without Vulkan the test says why it is skipped and passes, unless `RESHIFT_REQUIRE_VULKAN=1`,
//! which makes it fail.

use engine::vulkan::testing::{backend_or_skip, rel_mse_pixels};
use lab::methods::Method;
use sss::scene::Scene;

const WIDTH: u32 = 24;
const HEIGHT: u32 = 18;

/// The images' criterion, as in the per-pixel parity tests: relMSE(GPU, CPU same seed) at most
/// this fraction of relMSE(CPU other seed, CPU same seed) (their headers say why the twins are
/// not bit-exact; a diverged sample behaves like an independent one).
const RATIO: f64 = 0.01;

/// `image-space:1` (1 frame) and `adaptive` (the paper's controller, 2 frames, so that frame 1
/// reprojects frame 0's histories) on every built-in scene at 24×18: no error and no non-finite
/// value on either backend, finite non-negative pixels, and on Vulkan relMSE(GPU, CPU seed 7) ≤
/// 0.01 · relMSE(CPU seed 8, CPU seed 7), the adaptive counts equal to the CPU's.
#[test]
fn seed_methods_render_every_scene_on_both_backends() {
    let Some(backend) = backend_or_skip("seed_methods_render_every_scene_on_both_backends") else {
        return;
    };
    for (name, _) in Scene::BUILTIN {
        let mut scene = Scene::builtin(name).expect("built-in scene");
        scene.camera = scene.camera.with_resolution(WIDTH, HEIGHT);
        for (spec, frames) in [("image-space:1", 1), ("adaptive", 2)] {
            let method = Method::parse(spec).unwrap();
            let gpu = method
                .render_on(&backend, &scene, frames, 7)
                .unwrap_or_else(|e| panic!("{name} {spec} on Vulkan: {e}"));
            let cpu = method.render(&scene, frames, 7).unwrap();
            let other = method.render(&scene, frames, 8).unwrap();
            for (rendered, on) in [(&gpu, "Vulkan"), (&cpu, "CPU")] {
                assert_eq!(rendered.nonfinite, 0, "{name} {spec} on {on}");
                assert_eq!(
                    (rendered.image.width, rendered.image.height),
                    (WIDTH, HEIGHT)
                );
                assert!(
                    rendered
                        .image
                        .pixels
                        .iter()
                        .all(|p| p.is_finite() && p.min_element() >= 0.0),
                    "{name} {spec} on {on}"
                );
            }
            let n = cpu.image.pixels.len();
            let error = rel_mse_pixels(&gpu.image.pixels, &cpu.image.pixels, 0..n);
            let noise = rel_mse_pixels(&other.image.pixels, &cpu.image.pixels, 0..n);
            eprintln!("{name} {spec}: relMSE(GPU, CPU) {error:.2e}, CPU seeds {noise:.2e}");
            assert!(
                error <= RATIO * noise,
                "{name} {spec}: {error:.3e} vs {noise:.3e}"
            );
            assert_eq!(gpu.counts, cpu.counts, "{name} {spec}: sample counts");
        }
    }
}
