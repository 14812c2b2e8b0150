//! The worked example of docs/adding-a-method.md, `pt-one-hit`, through the registry: on the
//! CPU it is exactly the path tracer with `HitPolicy::UniformOne`, and on Vulkan (where there
//! is one) it renders the CPU's image of the same seed up to device rounding.
//!
//! Without Vulkan the second test says why it skips and passes, unless
//! `RESHIFT_REQUIRE_VULKAN=1`, which makes it fail.

use engine::Image;
use engine::vulkan::testing::backend_or_skip;
use methods::{Method, REGISTRY};
use sss::integrator::pt::{self, HitPolicy, PtSettings};
use sss::scene::{GBuffer, Scene};

const FRAMES: u32 = 16;

fn bumpy(width: u32, height: u32) -> Scene {
    let scene = Scene::builtin("bumpy").expect("built-in");
    Scene {
        camera: scene.camera.with_resolution(width, height),
        ..scene
    }
}

fn bits(image: &Image) -> Vec<u32> {
    image
        .pixels
        .iter()
        .flat_map(|p| p.to_array().map(f32::to_bits))
        .collect()
}

/// Mean over pixels and RGB of `(a − b)² / (b² + ε)`, ε = 1e-2, in f64.
fn rel_mse(a: &Image, b: &Image) -> f64 {
    let sum: f64 = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .flat_map(|(pa, pb)| (0..3).map(move |c| (pa[c] as f64, pb[c] as f64)))
        .map(|(x, y)| (x - y) * (x - y) / (y * y + 1e-2))
        .sum();
    sum / (3 * a.pixels.len()).max(1) as f64
}

/// The registry lists it and parses it; on the CPU its image is bit for bit
/// `sss::integrator::pt::render` with `HitPolicy::UniformOne` at the last frame, a function of
/// the seed. Negative control: `pt` (every hit) at the same spp and seed gives other bits, so the
/// hit policy really reaches the integrator.
#[test]
fn on_the_cpu_it_is_the_one_hit_path_tracer() {
    assert!(REGISTRY.iter().any(|e| e.family == "pt-one-hit"));
    assert_eq!(Method::parse("pt-one-hit").unwrap().name(), "pt-one-hit:1");
    assert!(Method::parse("pt-one-hit:0").is_err());
    let method = Method::parse("pt-one-hit:4").unwrap();
    assert_eq!(method.with_spp(8).name(), "pt-one-hit:8");
    let scene = bumpy(24, 18);
    let rendered = method.render(&scene, FRAMES, 7).unwrap();
    assert_eq!((rendered.frames_rendered, rendered.nonfinite), (1, 0));
    let settings = PtSettings {
        hits: HitPolicy::UniformOne,
        ..PtSettings::default()
    };
    let gbuffer = GBuffer::render(&scene, FRAMES - 1);
    let direct = pt::render(&scene, &gbuffer, &settings, 7, 0, 4);
    let direct: Vec<u32> = direct
        .pixels
        .iter()
        .flat_map(|p| p.as_vec3().to_array().map(f32::to_bits))
        .collect();
    assert_eq!(bits(&rendered.image), direct);
    let again = method.render(&scene, FRAMES, 7).unwrap();
    assert_eq!(bits(&again.image), direct);
    let every_hit = Method::parse("pt:4")
        .unwrap()
        .render(&scene, FRAMES, 7)
        .unwrap();
    assert_ne!(bits(&every_hit.image), direct, "control: the hit policy");
}

/// On Vulkan, with `R = relMSE(GPU a, CPU a) / relMSE(CPU b, CPU a)` (seeds a = 1, b = 2,
/// 48×36, 4 spp): the same random streams on both backends make R ≈ 0 up to device rounding of
/// transcendentals (and probes over the kernel's 16 hits, left out); R < 0.1 is required, as for
/// the other methods in `vulkan_methods.rs`. Negative control: the GPU image of seed b gives
/// R ≥ 0.1 (it is ≈ 1, Monte Carlo noise).
#[test]
fn on_vulkan_it_renders_the_cpu_image_of_its_seed() {
    let Some(backend) = backend_or_skip("on_vulkan_it_renders_the_cpu_image_of_its_seed") else {
        return;
    };
    let method = Method::parse("pt-one-hit:4").unwrap();
    let scene = bumpy(48, 36);
    let gpu = |seed| method.render_on(&backend, &scene, FRAMES, seed).unwrap();
    let cpu = |seed| method.render(&scene, FRAMES, seed).unwrap().image;
    let (gpu_a, gpu_b) = (gpu(1), gpu(2));
    let (cpu_a, cpu_b) = (cpu(1), cpu(2));
    assert_eq!(gpu_a.nonfinite, 0);
    assert_eq!((gpu_a.image.width, gpu_a.image.height), (48, 36));
    let noise = rel_mse(&cpu_b, &cpu_a);
    let ratio = rel_mse(&gpu_a.image, &cpu_a) / noise;
    let control = rel_mse(&gpu_b.image, &cpu_a) / noise;
    println!("relMSE(CPU b, CPU a) = {noise:.4e}; R(GPU a) = {ratio:.3e}; control {control:.3}");
    assert!(noise > 0.0, "two CPU seeds gave the same image");
    assert!(
        ratio < 0.1,
        "R = {ratio}: the GPU image is not the CPU image of its seed"
    );
    assert!(control >= 0.1, "control: another seed gave R = {control}");
}
