//! The kernels of this crate's methods (path tracer, image space, adaptive, single scattering,
//! random walk), once, under the Khronos
//! validation layer with synchronization validation: any error (an invalid use, a missing
//! barrier) fails the test with the layer's message (the engine's kernels:
//! `engine/tests/vulkan_validation.rs`).
//!
//! Small on purpose: validation multiplies lavapipe's time, so the run is 32×24 pixels, 2
//! frames. Skips without Vulkan or without the layer, unless `RESHIFT_REQUIRE_VULKAN=1`.

use engine::vulkan::Checks;
use engine::vulkan::testing::{assert_no_unreported_errors, validated, validated_or_skip};
use methods::adaptive::{self, cpu::AdaptiveParams};
use methods::{image_space, pt, random_walk, single_scatter};
use sss::integrator::pt::HitPolicy;
use sss::integrator::single_scatter::ChannelSelection;
use sss::scene::Scene;

const WIDTH: u32 = 32;
const HEIGHT: u32 = 24;
const FRAMES: u32 = 2;
const SEED: u64 = 5;

#[test]
fn every_method_kernel_passes_sync_validation() {
    let Some(mut renderer) = validated_or_skip("methods sync_validation", Checks::Sync) else {
        return;
    };
    let mut scene = Scene::builtin("bumpy").expect("built-in scene");
    scene.camera = scene.camera.with_resolution(WIDTH, HEIGHT);
    for frame in 0..FRAMES {
        for hits in [HitPolicy::All, HitPolicy::UniformOne] {
            validated(
                "pt",
                pt::vulkan::render(&mut renderer, &scene, frame, SEED, 1, hits),
            );
        }
        let image = image_space::vulkan::render(&mut renderer, &scene, frame, SEED, 1);
        validated("image-space", image);
        let channels = ChannelSelection::Scattering;
        let image = single_scatter::vulkan::render(&mut renderer, &scene, frame, SEED, 1, channels);
        validated("single-scatter", image);
        let image = random_walk::vulkan::render(&mut renderer, &scene, frame, SEED, 1);
        validated("random-walk", image);
    }
    let params = AdaptiveParams::default();
    let last = adaptive::vulkan::run(&mut renderer, &scene, &params, SEED, FRAMES, |_| {});
    validated("adaptive", last);
    assert_no_unreported_errors(&renderer);
}
