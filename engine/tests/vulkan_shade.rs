//! Parity of the shade pass (`pass_shade.glsl`) with the CPU (`engine/src/cpu.rs` `shade`), on
//! the CPU's G-buffer and reservoirs, through whatever device the Vulkan backend chooses
//! (lavapipe in CI); the path tracer's kernel has its own (`methods/src/pt/parity.rs`).
//!
//! Without Vulkan each test prints why it is skipped and passes, unless `RESHIFT_REQUIRE_VULKAN=1`,
//! which makes it fail.

use engine::reuse::{self, PassInput};
use engine::vulkan::testing::{UploadedFrame, kernel_or_skip};
use engine::vulkan::{Buffer, FrameInput, SHADE, VulkanError, shade};
use engine::{PixelReservoir, Target};
use engine::{candidates, purpose};
use glam::{DVec3, Vec3};
use restir::rng::StreamKey;
use sss::integrator::pt::{self, PtSettings, Shading};
use sss::material::Material;
use sss::scene::{GBuffer, GPixel, Scene};

/// Scenes of the parity tests: a displaced translucent sphere, every material kind, and a
/// half-shadowed translucent object (visibility decisions near shadow boundaries).
const SCENES: [&str; 3] = ["bumpy", "materials", "half-shadow"];
/// Resolution and frame of the tests (frame > 0 so a frame-less stream key would be caught).
const SIZE: u32 = 32;
const FRAME: u32 = 3;
const SEED: u64 = 11;
const OTHER_SEED: u64 = 12;

fn scene(name: &str) -> Scene {
    let mut scene = Scene::builtin(name).expect("built-in scene");
    scene.camera = scene.camera.with_resolution(SIZE, SIZE);
    scene
}

/// The canonical reservoirs of the candidates pass (pass 0, one BSSRDF sample, shared light
/// numbers, shadow-tested), as `cpu::run` writes them.
fn cpu_reservoirs(scene: &Scene, gbuffer: &GBuffer, seed: u64) -> Vec<PixelReservoir> {
    let input = PassInput {
        scene,
        gbuffer,
        reservoirs: &[],
        pass: 0,
        seed,
        collect_diagnostics: false,
        target: Target::Luminance,
    };
    let mut hits = Vec::new();
    (0..gbuffer.pixels.len() as u32)
        .map(|pixel| {
            let Some((domain, _)) = input.domain(pixel) else {
                return PixelReservoir::empty();
            };
            let (mut canonical, _) =
                candidates::generate(&domain, 1, true, seed, &mut hits).unwrap();
            candidates::shadow_test(&domain, &mut canonical);
            PixelReservoir::from(&canonical)
        })
        .collect()
}

/// Lambert direct lighting with the light's pdf left out: the deliberately wrong shade of the
/// negative control (the same NEE as `pt::estimate` on a Lambert pixel, times `p_light`).
fn lambert_without_pdf(
    scene: &Scene,
    x1: &GPixel,
    albedo: Vec3,
    rng: &mut restir::rng::Stream,
) -> Vec3 {
    let u = [rng.next_f32(), rng.next_f32(), rng.next_f32()];
    let Some(light) = scene.lights.sample(x1.position, u) else {
        return Vec3::ZERO;
    };
    let cos = x1.shading_normal.dot(light.wi);
    if !(cos > 0.0 && x1.geometric_normal.dot(light.wi) > 0.0 && light.pdf > 0.0)
        || pt::occluded(
            scene,
            x1.position,
            x1.geometric_normal,
            light.wi,
            light.distance,
        )
    {
        return Vec3::ZERO;
    }
    albedo * (std::f32::consts::FRAC_1_PI * cos) * light.radiance
}

/// `cpu::shade` of one frame, pixel by pixel with the same calls (`reuse::shade` on translucent
/// pixels, `pt::estimate` with the OPAQUE stream elsewhere); `drop_pdf` swaps in
/// [`lambert_without_pdf`] on Lambert pixels. Non-finite values are written as 0.
fn cpu_shade(
    scene: &Scene,
    gbuffer: &GBuffer,
    reservoirs: &[PixelReservoir],
    pass: u32,
    seed: u64,
    drop_pdf: bool,
) -> Vec<Vec3> {
    let input = PassInput {
        scene,
        gbuffer,
        reservoirs,
        pass,
        seed,
        collect_diagnostics: false,
        target: Target::Luminance,
    };
    let settings = PtSettings::default();
    (0..gbuffer.pixels.len() as u32)
        .map(|pixel| {
            let Some(g) = &gbuffer.pixels[pixel as usize] else {
                return Vec3::ZERO;
            };
            let value = match input.domain(pixel) {
                Some((domain, _)) => reuse::shade(&domain, &reservoirs[pixel as usize]),
                None => {
                    let mut rng =
                        StreamKey::new(pixel, gbuffer.frame, pass, purpose::OPAQUE).stream(seed);
                    match (scene.material_of_object(g.object), drop_pdf) {
                        (Material::Lambert(m), true) => {
                            lambert_without_pdf(scene, g, m.albedo, &mut rng)
                        }
                        _ => pt::estimate(
                            scene,
                            &Shading::new(scene, g),
                            &settings,
                            &mut rng,
                            &mut Vec::new(),
                        ),
                    }
                }
            };
            if value.is_finite() { value } else { Vec3::ZERO }
        })
        .collect()
}

/// Per-pixel comparison of a GPU image with a CPU one.
#[derive(Debug)]
struct PixelErrors {
    /// Pixels whose largest per-channel relative error `|g − c| / max(|c|, floor)` exceeds the
    /// tolerance.
    outliers: usize,
    /// The largest relative error over the pixels within tolerance (reported).
    max_relative: f64,
    /// `Σ ‖g − c‖² / Σ ‖c‖²` over the image.
    rel_mse: f64,
}

/// Relative errors below `floor` (in absolute radiance) are measured against `floor`, so that
/// black pixels of the CPU image do not divide by zero.
const FLOOR: f64 = 1e-6;

fn compare(gpu: &[Vec3], cpu: &[Vec3], tolerance: f64) -> PixelErrors {
    let (mut outliers, mut max_relative, mut num, mut den) = (0, 0.0f64, 0.0, 0.0);
    for (g, c) in gpu.iter().zip(cpu) {
        let (g, c) = (g.as_dvec3(), c.as_dvec3());
        let relative = ((g - c).abs() / c.abs().max(DVec3::splat(FLOOR))).max_element();
        if relative > tolerance {
            outliers += 1;
        } else {
            max_relative = max_relative.max(relative);
        }
        num += (g - c).length_squared();
        den += c.length_squared();
    }
    PixelErrors {
        outliers,
        max_relative,
        rel_mse: if den > 0.0 { num / den } else { 0.0 },
    }
}

/// Per-pixel relative tolerance of `pass_shade`. The inputs (G-buffer, reservoirs, `W`) are the
/// CPU's bits and `+ − × ÷ sqrt` match Rust exactly on lavapipe; what differs is the
/// transcendentals: the Burley profile's `exp` in `f(Y)` on translucent pixels, `cos`/`sin` of
/// sphere-light cones on Lambert ones, each a few ulp from Rust's libm. A value is a product of
/// ≲ 10 factors, so ≲ 40 ulp ≈ 5e-6 relative; the tolerance is twice that.
const SHADE_TOLERANCE: f64 = 1e-5;
/// Pixels allowed beyond [`SHADE_TOLERANCE`]: a shadow ray whose light point moved by an ulp can
/// flip its visibility decision where it grazes an edge, which changes a pixel by 100 %. Such
/// grazes are rare: at most 0.5 % of the pixels (5 of 1024).
const SHADE_OUTLIER_FRACTION: f64 = 0.005;
/// Image relMSE bound of `pass_shade` (`Σ‖g − c‖² / Σ‖c‖²`): pixels within tolerance contribute
/// ≤ (1e-5)²; the bound leaves room for a flip or two in dim pixels of the allowed outliers, not for
/// a systematic error (the controls below measure relMSE ≥ 0.4).
const SHADE_REL_MSE: f64 = 1e-6;

/// Whether a GPU image passes the shade parity criteria against a CPU one.
fn shade_matches(errors: &PixelErrors, pixels: usize) -> bool {
    errors.outliers as f64 <= SHADE_OUTLIER_FRACTION * pixels as f64
        && errors.rel_mse <= SHADE_REL_MSE
}

/// `pass_shade` on the CPU's G-buffer and candidate reservoirs reproduces `cpu::shade` on
/// `bumpy`, `materials` and `half-shadow` (32×32, frame 3, pass index 1 as after a
/// candidates-only preset): per-pixel relative error ≤ 1e-5 except ≤ 0.5 % of the pixels, image
/// relMSE ≤ 1e-6 (reasons at the constants), no pixel flagged. Negative controls through the same
/// criteria: the CPU frame of another seed (reservoirs and shade), and, on the scenes with Lambert
/// surfaces under an area light (`bumpy`, `materials`), a CPU shade that leaves the light's pdf
/// out of Lambert NEE (on `half-shadow` the only light is directional, pdf 1, so leaving it out
/// changes nothing) must both be rejected.
#[test]
fn shade_pass_matches_the_cpu() {
    let Some((mut context, kernel)) = kernel_or_skip("shade parity", SHADE) else {
        return;
    };
    let pass = 1;
    for name in SCENES {
        let scene = scene(name);
        let gbuffer = GBuffer::render(&scene, FRAME);
        let reservoirs = cpu_reservoirs(&scene, &gbuffer, SEED);
        let uploaded = UploadedFrame::new(&context, &scene, &gbuffer, SEED).unwrap();
        let reservoir_buffer = Buffer::from_slice(&context, &reservoirs).unwrap();
        let start = std::time::Instant::now();
        let gpu = shade(
            &mut context,
            &kernel,
            &uploaded.input(),
            &reservoir_buffer,
            pass,
        )
        .unwrap();
        let seconds = start.elapsed().as_secs_f64();
        assert_eq!(gpu.left_out, 0, "{name}: pixels written as 0");
        let gpu = gpu.image.pixels;
        let n = gpu.len();
        let cpu = cpu_shade(&scene, &gbuffer, &reservoirs, pass, SEED, false);
        let errors = compare(&gpu, &cpu, SHADE_TOLERANCE);
        eprintln!(
            "{name}: {} of {n} pixels beyond {SHADE_TOLERANCE}, max relative error {:.2e} \
             within, relMSE {:.2e} ({seconds:.3} s)",
            errors.outliers, errors.max_relative, errors.rel_mse
        );
        assert!(
            shade_matches(&errors, n),
            "{name}: {errors:?}; want ≤ {SHADE_OUTLIER_FRACTION} of {n} pixels beyond \
             {SHADE_TOLERANCE}, relMSE ≤ {SHADE_REL_MSE}"
        );
        let other = cpu_reservoirs(&scene, &gbuffer, OTHER_SEED);
        let reseeded = cpu_shade(&scene, &gbuffer, &other, pass, OTHER_SEED, false);
        let control = compare(&gpu, &reseeded, SHADE_TOLERANCE);
        eprintln!("{name}: control, other seed: {control:?}");
        assert!(
            !shade_matches(&control, n),
            "{name}: control, another seed passes: {control:?}"
        );
        if name != "half-shadow" {
            let no_pdf = cpu_shade(&scene, &gbuffer, &reservoirs, pass, SEED, true);
            let control = compare(&gpu, &no_pdf, SHADE_TOLERANCE);
            eprintln!("{name}: control, no light pdf: {control:?}");
            assert!(
                !shade_matches(&control, n),
                "{name}: control, shade without the light pdf passes: {control:?}"
            );
        }
    }
}

/// `FrameInput::bindings` refuses a G-buffer smaller than the frame (one row short, here through
/// the shade pass) with a binding error; the same G-buffer at the frame's own size is accepted
/// (the control).
#[test]
fn a_gbuffer_smaller_than_the_frame_is_refused() {
    let Some((mut context, kernel)) = kernel_or_skip("G-buffer size check", SHADE) else {
        return;
    };
    let scene = scene("bumpy");
    let gbuffer = GBuffer::render(&scene, FRAME);
    let uploaded = UploadedFrame::new(&context, &scene, &gbuffer, SEED).unwrap();
    let reservoirs = Buffer::from_slice(&context, &cpu_reservoirs(&scene, &gbuffer, SEED)).unwrap();
    let too_large = FrameInput {
        height: SIZE + 1,
        ..uploaded.input()
    };
    assert!(
        matches!(
            shade(&mut context, &kernel, &too_large, &reservoirs, 1),
            Err(VulkanError::Binding(_))
        ),
        "a G-buffer smaller than the frame must be refused"
    );
    assert!(shade(&mut context, &kernel, &uploaded.input(), &reservoirs, 1).is_ok());
}
