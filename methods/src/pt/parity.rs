//! The path tracer on the device (`method_pt.glsl`, `sss/glsl/pt.glsl`) against its CPU twin
//! `sss::integrator::pt::render`, on the CPU's G-buffer, through whatever device the Vulkan
//! backend chooses (lavapipe in CI).
//!
//! Without Vulkan each test prints why it is skipped and passes, unless
//! `RESHIFT_REQUIRE_VULKAN=1`, which makes it fail.

use super::vulkan::{PT, render_pt};
use engine::contract::KEPT_HITS;
use engine::vulkan::testing::{UploadedFrame, kernel_or_skip, rel_mse_pixels};
use geometry::Hit;
use glam::Vec3;
use sss::integrator::pt::{self, HitPolicy, PtSettings, Shading};
use sss::scene::{GBuffer, Scene};

/// Scenes of the parity test: a displaced translucent sphere, every material kind, and a
/// half-shadowed translucent object (visibility decisions near shadow boundaries).
const SCENES: [&str; 3] = ["bumpy", "materials", "half-shadow"];
/// Resolution and frame of the test (frame > 0 so a frame-less stream key would be caught).
const SIZE: u32 = 32;
const FRAME: u32 = 3;
const SEED: u64 = 11;
const OTHER_SEED: u64 = 12;
/// Samples per pixel of the parity test.
const SPP: u32 = 4;
/// The honest criterion of `method_pt` parity: relMSE(GPU, CPU with the same seed) must be below
/// this fraction of relMSE(CPU with another seed, CPU), i.e. the GPU image is at least 1000×
/// closer to its CPU twin than an independent replica is. Same-seed differences come from
/// transcendentals a few ulp apart (probe radius `log`, disk angle `cos`/`sin`, profile `exp`)
/// and from the rare hit or shadow decision they flip; an independent replica differs by the
/// full Monte Carlo noise.
const RATIO: f64 = 1e-3;

/// Emitters that are geometry: a translucent ball lit by a one-sided emissive panel facing down
/// and a two-sided one facing the camera's side, both in view (the second from its back).
const EMITTERS: &str = r#"
[camera]
resolution = [32, 32]
vfov = 60.0
eye = [0.2, 1.2, 3.0]
target = [0.0, 0.9, 0.0]

[[materials]]
name = "wax"
type = "translucent"
albedo = [0.8, 0.6, 0.4]
mfp = [0.1, 0.05, 0.02]

[[materials]]
name = "floor"
type = "lambert"
albedo = [0.5, 0.5, 0.5]

[[materials]]
name = "down"
type = "lambert"
albedo = [0.3, 0.3, 0.3]
emission = [3.0, 2.5, 2.0]

[[materials]]
name = "both"
type = "lambert"
albedo = [0.6, 0.6, 0.6]
emission = [1.0, 2.0, 4.0]
two_sided = true

[[objects]]
name = "ball"
material = "wax"
shape = { type = "sphere", radius = 0.4 }
transform = { translate = [0.0, 0.4, 0.0] }

[[objects]]
name = "floor"
material = "floor"
shape = { type = "quad", size = [6.0, 6.0] }

[[objects]]
name = "down"
material = "down"
shape = { type = "quad", size = [1.0, 1.0] }
transform = { translate = [-0.6, 1.8, 0.0], rotate = [180.0, 0.0, 0.0] }

[[objects]]
name = "both"
material = "both"
shape = { type = "quad", size = [0.8, 0.8] }
transform = { translate = [0.9, 1.0, -0.5], rotate = { axis = [0.0, 0.0, 1.0], degrees = 80.0 } }
"#;

/// The scenes of the parity test at [`SIZE`]²: [`SCENES`] and [`EMITTERS`].
fn scenes() -> Vec<(&'static str, Scene)> {
    let emitters = Scene::from_toml_str(EMITTERS, std::path::Path::new("emitters.toml"));
    SCENES
        .iter()
        .map(|&name| (name, Scene::builtin(name).expect("built-in scene")))
        .chain([("emitters", emitters.expect("the emitter scene"))])
        .map(|(name, mut scene)| {
            scene.camera = scene.camera.with_resolution(SIZE, SIZE);
            (name, scene)
        })
        .collect()
}

/// Largest number of probe hits the CPU path tracer sees over `spp` samples of every pixel (the
/// hit list `pt::estimate` leaves behind is its probe's). The GPU keeps `KEPT_HITS` hits per
/// probe, so parity is only meaningful while this stays within the cap.
fn max_probe_hits(
    scene: &Scene,
    gbuffer: &GBuffer,
    settings: &PtSettings,
    seed: u64,
    spp: u32,
) -> usize {
    let mut hits: Vec<Hit> = Vec::new();
    let mut most = 0;
    for (pixel, g) in gbuffer.pixels.iter().enumerate() {
        let Some(g) = g else { continue };
        let shading = Shading::new(scene, g);
        for sample in 0..spp {
            let mut rng = pt::sample_stream(pixel as u32, gbuffer.frame, sample, seed);
            pt::estimate(scene, &shading, settings, &mut rng, &mut hits);
            most = most.max(hits.len());
        }
    }
    most
}

/// `method_pt` at 4 spp on the CPU's G-buffer reproduces `pt::render` with the same seed on
/// `bumpy`, `materials`, `half-shadow` and a scene of one- and two-sided emissive meshes
/// (32×32, frame 3), for both hit policies:
/// relMSE(GPU, CPU) ≤ 1e-3 · relMSE(CPU seed 12, CPU seed 11), no sample left out, and every CPU
/// probe has at most `KEPT_HITS` hits (else the GPU's capped hit list could not match).
/// Negative control: the GPU image of seed 12 against the CPU image of seed 11 fails the same
/// ratio.
#[test]
fn pt_method_matches_the_cpu() {
    let Some((mut context, kernel)) = kernel_or_skip("pt parity", PT) else {
        return;
    };
    for (name, scene) in scenes() {
        let gbuffer = GBuffer::render(&scene, FRAME);
        let all = 0..gbuffer.pixels.len();
        let uploads = [SEED, OTHER_SEED]
            .map(|seed| UploadedFrame::new(&context, &scene, &gbuffer, seed).unwrap());
        for hits in [HitPolicy::All, HitPolicy::UniformOne] {
            let settings = PtSettings {
                hits,
                ..PtSettings::default()
            };
            let most = max_probe_hits(&scene, &gbuffer, &settings, SEED, SPP);
            assert!(
                most <= KEPT_HITS,
                "{name} {hits:?}: a CPU probe has {most} hits > {KEPT_HITS}"
            );
            let cpu_image = |seed| -> Vec<Vec3> {
                let image = pt::render(&scene, &gbuffer, &settings, seed, 0, SPP);
                image.pixels.iter().map(|p| p.as_vec3()).collect()
            };
            let cpu = cpu_image(SEED);
            let noise = rel_mse_pixels(&cpu_image(OTHER_SEED), &cpu, all.clone());
            assert!(
                noise > 0.0,
                "{name} {hits:?}: replicas of two seeds are identical"
            );
            let mut gpu_image = |uploaded: &UploadedFrame| {
                let out = render_pt(&mut context, &kernel, &uploaded.input(), SPP, hits).unwrap();
                assert_eq!(out.cut, 0, "{name} {hits:?}: loops cut short");
                out.image
            };
            let gpu = gpu_image(&uploads[0]);
            assert_eq!(gpu.left_out, 0, "{name} {hits:?}: samples left out");
            let ratio = rel_mse_pixels(&gpu.image.pixels, &cpu, all.clone()) / noise;
            eprintln!(
                "{name} {hits:?}: relMSE ratio {ratio:.3e} (other-seed relMSE {noise:.3e}, max probe hits {most})"
            );
            assert!(
                ratio <= RATIO,
                "{name} {hits:?}: relMSE ratio {ratio:.3e} > {RATIO}"
            );
            let other = gpu_image(&uploads[1]).image.pixels;
            let control = rel_mse_pixels(&other, &cpu, all.clone()) / noise;
            eprintln!("{name} {hits:?}: control, GPU with another seed: ratio {control:.3e}");
            assert!(
                control > RATIO,
                "{name} {hits:?}: control, another seed passes: ratio {control:.3e}"
            );
        }
    }
}
