//! The spatiotemporal variance-guided filter on the device (`denoise_svgf.glsl`) against its CPU
//! twin `engine::denoise::svgf::filter`, on a short trajectory of path-traced `bumpy` frames.
//!
//! Without Vulkan the test prints why it is skipped and passes, unless
//! `RESHIFT_REQUIRE_VULKAN=1`, which makes it fail.

use engine::denoise::svgf::{Params, filter};
use engine::denoise::{Denoiser, Guide, denoise};
use engine::vulkan::testing::backend_or_skip;
use engine::{Image, RunConfig, run_pt};
use sss::scene::Scene;

const WIDTH: u32 = 48;
const HEIGHT: u32 = 36;
const FRAMES: u32 = 5;

/// Per pixel, the largest channel difference over the CPU pixel's largest channel may not exceed
/// this. Everything but `exp` (the edge-stopping weights, ≈ 25 per pixel and iteration) is
/// bit-identical: `+ × ÷ sqrt` round the same, the normal weight's power is exact multiplies.
/// Lavapipe's `exp` is a few ulp (≈ 1e-7 relative each) off Rust's; a weight error δ moves a
/// normalised weighted mean by at most δ times the spread of the values it averages over the
/// mean, and the luminance weight feeds the filtered colour back into the next iteration's
/// weights and (through the first iteration) the next frame's history: a few ulp through
/// 2 (temporal + variance) + 4 frames × 1 + 5 iterations, with spreads of order 1 in noisy
/// frames, is ≲ 1e-5; 1e-4 leaves a factor 10. A wrong operation order or a missing stage moves
/// pixels by whole percents.
const PIXEL_TOLERANCE: f32 = 1e-4;

#[test]
fn svgf_twin_matches_the_cpu() {
    let Some(backend) = backend_or_skip("svgf_twin_matches_the_cpu") else {
        return;
    };
    let mut scene = Scene::builtin("bumpy").expect("built-in scene");
    scene.camera = scene.camera.with_resolution(WIDTH, HEIGHT);
    let guides = Guide::trajectory(&scene, FRAMES);
    let config = RunConfig {
        seed: 9,
        frames: FRAMES,
        collect_diagnostics: false,
    };
    let frames: Vec<Image> = run_pt(&scene, 1, &config).frames;
    let cpu = filter(&guides, &frames, &Params::default());
    let gpu = denoise(Denoiser::Svgf, &backend, &guides, &frames)
        .expect("the device filters")
        .image;
    let (mut worst, mut identical) = (0.0f32, 0);
    for (g, c) in gpu.pixels.iter().zip(&cpu.pixels) {
        let error = (*g - *c).abs().max_element() / c.max_element().max(f32::MIN_POSITIVE);
        worst = worst.max(error);
        identical += usize::from(g == c);
    }
    eprintln!(
        "worst pixel {worst:.3e} relative; {identical} of {} pixels bit-identical",
        cpu.pixels.len()
    );
    assert!(worst <= PIXEL_TOLERANCE, "worst pixel {worst}");
    // Control: the CPU filter of another trajectory's frames (another seed) is far outside.
    let other = run_pt(&scene, 1, &RunConfig { seed: 10, ..config }).frames;
    let other = filter(&guides, &other, &Params::default());
    let moved = other
        .pixels
        .iter()
        .zip(&cpu.pixels)
        .filter(|(o, c)| (**o - **c).abs().max_element() > PIXEL_TOLERANCE * c.max_element())
        .count();
    eprintln!("control, another seed: {moved} pixels beyond the tolerance");
    assert!(
        moved > cpu.pixels.len() / 4,
        "{moved} pixels moved by another seed"
    );
}
