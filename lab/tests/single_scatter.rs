//! The `single-scatter` method through the registry: on the CPU it is exactly
//! `sss::integrator::single_scatter::render` at the last frame, lit at the exits by the scene's
//! lights with the documented light-selection streams, a function of its seed; on Vulkan it
//! renders through its kernel, with the channel option, at the last frame.
//!
//! Without Vulkan the second test says why it skips and passes, unless
//! `RESHIFT_REQUIRE_VULKAN=1`, which makes it fail.

use std::cell::RefCell;

use engine::Image;
use engine::scene_lighting::SceneLighting;
use engine::vulkan::testing::{backend_or_skip, rel_mse_pixels};
use methods::single_scatter::PURPOSE_SINGLE_SCATTER_LIGHT;
use methods::{Method, REGISTRY};
use restir::rng::StreamKey;
use sss::integrator::single_scatter::{self, ChannelSelection, SingleScatterSettings};
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

/// `single_scatter::render` of frame `FRAMES − 1` at `spp`, written out from its documentation:
/// the light selection of pixel `p` from `StreamKey { p, frame, 0, "SS" + 2 }`.
fn direct(scene: &Scene, channel: ChannelSelection, seed: u64, spp: u32) -> Vec<u32> {
    let frame = FRAMES - 1;
    let gbuffer = GBuffer::render(scene, frame);
    let settings = SingleScatterSettings {
        channel,
        ..SingleScatterSettings::default()
    };
    let (image, truncated) =
        single_scatter::render(scene, &gbuffer, &settings, seed, 0, spp, |pixel| {
            let key = StreamKey {
                pixel,
                frame,
                pass: 0,
                purpose: PURPOSE_SINGLE_SCATTER_LIGHT,
            };
            SceneLighting {
                scene,
                selection: RefCell::new(key.stream(seed)),
            }
        })
        .unwrap();
    assert_eq!((truncated, image.nonfinite), (0, 0));
    image
        .pixels
        .iter()
        .flat_map(|p| p.as_vec3().to_array().map(f32::to_bits))
        .collect()
}

/// Registered and parsed; on the CPU its image is bit for bit the integrator's, twice (a
/// function of the seed), for both channel selections. Negative controls: another seed, and the
/// other channel selection at the same seed, give other bits (the option reaches the
/// integrator); `pt` differs too (the method is not the BSSRDF path tracer). The translucent
/// pixels are lit (not all zero).
#[test]
fn on_the_cpu_it_is_the_single_scatter_integrator() {
    assert!(REGISTRY.iter().any(|e| e.family == "single-scatter"));
    let scene = bumpy(24, 18);
    let method = Method::parse("single-scatter:4").unwrap();
    let rendered = method.render(&scene, FRAMES, 7).unwrap();
    assert_eq!((rendered.frames_rendered, rendered.nonfinite), (1, 0));
    let scattering = direct(&scene, ChannelSelection::Scattering, 7, 4);
    assert_eq!(bits(&rendered.image), scattering);
    let again = method.render(&scene, FRAMES, 7).unwrap();
    assert_eq!(bits(&again.image), scattering);
    assert_ne!(
        bits(&method.render(&scene, FRAMES, 8).unwrap().image),
        scattering,
        "control: another seed"
    );

    let uniform = Method::parse("single-scatter:4/channels=uniform")
        .unwrap()
        .render(&scene, FRAMES, 7)
        .unwrap();
    let expected = direct(&scene, ChannelSelection::Uniform, 7, 4);
    assert_eq!(bits(&uniform.image), expected);
    assert_ne!(expected, scattering, "control: the channel selection");
    let pt = Method::parse("pt:4").unwrap().render(&scene, FRAMES, 7);
    assert_ne!(bits(&pt.unwrap().image), scattering, "control: pt");

    let gbuffer = GBuffer::render(&scene, FRAMES - 1);
    let lit = gbuffer
        .pixels
        .iter()
        .zip(&rendered.image.pixels)
        .filter(|(g, p)| {
            g.is_some_and(|g| scene.objects[g.object as usize].name == "object")
                && p.max_element() > 0.0
        })
        .count();
    assert!(lit > 50, "only {lit} lit pixels on the translucent object");
}

/// On Vulkan the method renders frame `FRAMES − 1` through its kernel: no non-finite sample, and
/// for both channel selections relMSE(GPU, CPU seed 7) ≤ 0.01 · relMSE(CPU seed 8, CPU seed 7)
/// (every built-in scene: `vulkan_comparison_methods.rs`). Control: the option reaches the kernel (the
/// GPU images of the two selections differ).
#[test]
fn on_vulkan_it_renders_through_its_kernel() {
    let Some(backend) = backend_or_skip("on_vulkan_it_renders_through_its_kernel") else {
        return;
    };
    let scene = bumpy(24, 18);
    let mut images = Vec::new();
    for spec in ["single-scatter:2", "single-scatter:2/channels=uniform"] {
        let method = Method::parse(spec).unwrap();
        let gpu = method.render_on(&backend, &scene, FRAMES, 7).unwrap();
        assert_eq!((gpu.frames_rendered, gpu.nonfinite), (1, 0), "{spec}");
        let cpu = method.render(&scene, FRAMES, 7).unwrap().image.pixels;
        let other = method.render(&scene, FRAMES, 8).unwrap().image.pixels;
        let n = cpu.len();
        let ratio =
            rel_mse_pixels(&gpu.image.pixels, &cpu, 0..n) / rel_mse_pixels(&other, &cpu, 0..n);
        assert!(ratio <= 0.01, "{spec}: ratio {ratio:.3e}");
        images.push(bits(&gpu.image));
    }
    assert_ne!(images[0], images[1], "control: the channel selection");
}
