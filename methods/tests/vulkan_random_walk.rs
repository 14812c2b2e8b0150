//! The random-walk method on the device (`method_random_walk.glsl`, `sss/glsl/random_walk.glsl`)
//! against its CPU twin `methods::random_walk::render`, and energy conservation of
//! the GPU walk on its own.
//!
//! Without Vulkan each test prints why it is skipped and passes, unless
//! `RESHIFT_REQUIRE_VULKAN=1`, which makes it fail.

use engine::vulkan::testing::{UploadedFrame, kernel_or_skip, rel_mse_pixels};
use std::path::Path;

use engine::vulkan::{Context, Kernel};
use glam::{DVec3, Vec3};
use methods::random_walk::vulkan::{
    GpuMedium, RANDOM_WALK, RandomWalkImage, WalkStats, render_random_walk, scene_media,
};
use methods::random_walk::{PixelWalk, render};
use sss::material::Material;
use sss::random_walk::{Interface, Medium, WalkEnd, WalkSettings, estimate_exitant_with};
use sss::scene::{GBuffer, Scene};

const WIDTH: u32 = 40;
const HEIGHT: u32 = 30;
/// Frame > 0, so that a frame-less stream key would be caught.
const FRAME: u32 = 3;
const SEED: u64 = 11;
const OTHER_SEED: u64 = 12;
/// Walks per pixel of the parity test.
const SPP: u32 = 4;

fn scene(name: &str) -> Scene {
    let mut scene = Scene::builtin(name).expect("built-in scene");
    scene.camera = scene.camera.with_resolution(WIDTH, HEIGHT);
    scene
}

/// The random-walk kernel on an uploaded frame.
fn render_gpu(
    uploaded: &UploadedFrame,
    context: &mut Context,
    kernel: &Kernel,
    media: &[GpuMedium],
    spp: u32,
) -> RandomWalkImage {
    render_random_walk(context, kernel, &uploaded.input(), media, spp).unwrap()
}

/// Per pixel, how the CPU's `spp` walks ended (`[exited, terminated, truncated]`; zero on pixels
/// without walks) and their mean: the loop of `random_walk::render` written out so that
/// the ends are visible. Its image must equal `render`'s on walk pixels (checked by the caller).
fn cpu_walks(scene: &Scene, gbuffer: &GBuffer, seed: u64, spp: u32) -> (Vec<[u32; 3]>, Vec<Vec3>) {
    let mut ends = vec![[0u32; 3]; gbuffer.pixels.len()];
    let mut means = vec![Vec3::ZERO; gbuffer.pixels.len()];
    for (index, g) in gbuffer.pixels.iter().enumerate() {
        let Some(g) = g else { continue };
        let Material::Translucent(t) =
            &scene.materials[scene.objects[g.object as usize].material as usize]
        else {
            continue;
        };
        let medium = Medium::from_translucent(t, Path::new("x"), "m").unwrap();
        let PixelWalk {
            boundary,
            n1,
            lighting,
            mut stream,
        } = PixelWalk::new(scene, g, index as u32, gbuffer.frame, seed);
        let (mut sum, mut finite) = (DVec3::ZERO, 0u32);
        for _ in 0..spp {
            let sample = estimate_exitant_with(
                &boundary,
                &medium,
                g.position,
                n1,
                g.view,
                &lighting,
                &WalkSettings::default(),
                &mut stream,
            );
            let slot = match sample.end {
                WalkEnd::Exited(_) => 0,
                WalkEnd::Terminated => 1,
                WalkEnd::Truncated => 2,
            };
            ends[index][slot] += 1;
            if sample.radiance.is_finite() {
                sum += sample.radiance.as_dvec3();
                finite += 1;
            }
        }
        means[index] = if finite > 0 {
            (sum / finite as f64).as_vec3()
        } else {
            Vec3::ZERO
        };
    }
    (ends, means)
}

fn gpu_ends(stats: &[WalkStats]) -> Vec<[u32; 3]> {
    stats
        .iter()
        .map(|s| [s.exited, s.terminated, s.truncated])
        .collect()
}

/// The parity criterion: relMSE(GPU, CPU same seed) over the walk pixels must be below this
/// fraction of relMSE(CPU other seed, CPU same seed). Bit-exactness is impossible: free flights
/// take `log`, transmittance ratios `exp`, phase and cosine sampling `sin`/`cos`, and lavapipe's
/// are a few ulp off the CPU's libm. A walk follows the CPU's path until such an ulp flips a
/// discrete decision (collision before or after the boundary, roulette, a light's visibility);
/// from there it is an independent walk, whose squared error is on average twice the variance
/// of one walk, like an other-seed walk's. The ratio is therefore about the fraction of
/// diverging walks; 0.05 allows one walk in twenty to diverge, far above what ulp-level
/// differences flip, and far below the ratio ≈ 1 of an independent image.
const WALK_RATIO: f64 = 0.05;
/// Pixels whose `[exited, terminated, truncated]` walk counts may differ from the CPU's: the
/// same divergence budget as `WALK_RATIO`.
const END_MISMATCH_FRACTION: f64 = 0.05;

/// `method_random_walk` at 4 walks per pixel on the CPU's G-buffer reproduces
/// `random_walk::render` with the same seed on `slab`, `bumpy` and `materials` (40×30,
/// frame 3): on walk pixels relMSE(GPU, CPU) ≤ 0.05 · relMSE(CPU seed 12, CPU seed 11) and at
/// most 5 % of pixels end their walks differently; on path-traced pixels the same ratio (the
/// path tracer's own parity is tested in `vulkan_shade`); nothing is left out as non-finite and
/// no dispatch had its loops cut short.
/// Negative control: the GPU with every medium's `g` set to 0.5 (another phase function, so
/// every walk scatters elsewhere) fails the same ratio.
#[test]
fn random_walk_method_matches_the_cpu() {
    let Some((mut context, kernel)) = kernel_or_skip("random-walk parity", RANDOM_WALK) else {
        return;
    };
    for name in ["slab", "bumpy", "materials"] {
        let start = std::time::Instant::now();
        let scene = scene(name);
        let gbuffer = GBuffer::render(&scene, FRAME);
        let media = scene_media(&scene).unwrap();
        let uploaded = UploadedFrame::new(&context, &scene, &gbuffer, SEED).unwrap();
        let gpu = render_gpu(&uploaded, &mut context, &kernel, &media, SPP);
        assert_eq!(gpu.cut, 0, "{name}: the device cut loops short");
        let (cpu, cpu_left_out) = render(&scene, &gbuffer, SEED, SPP).unwrap();
        let (replica, _) = render(&scene, &gbuffer, OTHER_SEED, SPP).unwrap();
        let (ends, means) = cpu_walks(&scene, &gbuffer, SEED, SPP);
        let walk_pixels: Vec<usize> = (0..ends.len())
            .filter(|&p| ends[p].iter().sum::<u32>() > 0)
            .collect();
        let pt_pixels: Vec<usize> = (0..ends.len())
            .filter(|&p| gbuffer.pixels[p].is_some() && ends[p].iter().sum::<u32>() == 0)
            .collect();
        assert!(
            walk_pixels.len() > 50,
            "{name}: {} walk pixels",
            walk_pixels.len()
        );
        for &p in &walk_pixels {
            assert_eq!(
                means[p], cpu.pixels[p],
                "{name}: test loop ≠ render at pixel {p}"
            );
        }
        assert_eq!(
            (gpu.image.left_out, cpu_left_out),
            (0, 0),
            "{name}: left out"
        );

        let noise = rel_mse_pixels(&replica.pixels, &cpu.pixels, walk_pixels.iter().copied());
        let ratio = rel_mse_pixels(
            &gpu.image.image.pixels,
            &cpu.pixels,
            walk_pixels.iter().copied(),
        ) / noise;
        let mismatched = walk_pixels
            .iter()
            .filter(|&&p| gpu_ends(&gpu.stats)[p] != ends[p])
            .count();
        let pt_noise = rel_mse_pixels(&replica.pixels, &cpu.pixels, pt_pixels.iter().copied());
        let pt_ratio = rel_mse_pixels(
            &gpu.image.image.pixels,
            &cpu.pixels,
            pt_pixels.iter().copied(),
        ) / pt_noise;
        let walks: u32 = walk_pixels
            .iter()
            .map(|&p| ends[p].iter().sum::<u32>())
            .sum();
        eprintln!(
            "{name}: {} walk pixels ({walks} walks), relMSE ratio {ratio:.2e} (noise {noise:.3e}), \
             walk ends differ on {mismatched} pixels; {} path-traced pixels, ratio {pt_ratio:.2e}; {:.2?}",
            walk_pixels.len(),
            pt_pixels.len(),
            start.elapsed()
        );
        assert!(
            ratio <= WALK_RATIO,
            "{name}: relMSE(GPU, CPU) / relMSE(replica, CPU) = {ratio:.3e} > {WALK_RATIO}"
        );
        assert!(
            mismatched as f64 <= END_MISMATCH_FRACTION * walk_pixels.len() as f64,
            "{name}: walk ends differ on {mismatched} of {} pixels",
            walk_pixels.len()
        );
        assert!(
            pt_ratio <= WALK_RATIO,
            "{name}: path-traced pixels: ratio {pt_ratio:.3e} > {WALK_RATIO}"
        );

        let other_phase: Vec<GpuMedium> =
            media.iter().map(|m| GpuMedium { g: 0.5, ..*m }).collect();
        let control = render_gpu(&uploaded, &mut context, &kernel, &other_phase, SPP);
        let control_ratio = rel_mse_pixels(
            &control.image.image.pixels,
            &cpu.pixels,
            walk_pixels.iter().copied(),
        ) / noise;
        eprintln!("{name}: control (g = 0.5): relMSE ratio {control_ratio:.2e}");
        assert!(
            control_ratio > WALK_RATIO,
            "{name}: control with g = 0.5 passes: ratio {control_ratio:.3e} ≤ {WALK_RATIO}"
        );
    }
}

/// Walks per pixel of the energy test.
const ENERGY_SPP: u32 = 16;
/// Largest `|weight − 1|` of an exiting walk in a gray albedo-1 medium. In exact arithmetic it
/// is 0: every collision multiplies `β` and `r` by `σs/σt = 1` and the rescaling by `1/mean(r)`
/// is the identity. In f32 `σ · (1/σ)` and `(3r)/3` round, so `β` sits within a few ulp
/// (2⁻²³ ≈ 1.2e-7) of 1 after every collision; the rescaling stops the error from accumulating.
const WEIGHT_TOLERANCE: f32 = 1e-5;
/// Walks that may end other than by exiting, as a fraction of all. A weight rounded to
/// `1 − 2⁻²⁴` survives roulette with `q = 1 − 2⁻²⁴`, i.e. is killed with probability 2⁻²⁴ per
/// collision (tiny, yet not impossible over 10⁵ collisions); the bounce cap (65 536 segments)
/// and the mesh's entry-skip cap are never reached by a walk that does not leak.
const LOST_FRACTION: f64 = 1e-3;

/// A gray medium per translucent material of `scene`: `σt` = the CPU medium's green `σt`,
/// `σa = absorption · σt`, isotropic, with `interface`; Lambert materials get placeholders.
fn gray_media(scene: &Scene, absorption: f32, interface: Interface) -> Vec<GpuMedium> {
    scene
        .materials
        .iter()
        .map(|m| match m {
            Material::Translucent(t) => {
                let cpu = Medium::from_translucent(t, Path::new("x"), "m").unwrap();
                let sigma_t = Vec3::splat(cpu.sigma_t().y);
                let medium = Medium::new(
                    sigma_t * (1.0 - absorption),
                    sigma_t * absorption,
                    0.0,
                    interface,
                    Path::new("x"),
                    "m",
                )
                .unwrap();
                GpuMedium::new(&medium)
            }
            Material::Lambert(_) => GpuMedium::default(),
        })
        .collect()
}

/// What the energy test measures over a frame's walks.
#[derive(Debug)]
struct Energy {
    walks: u64,
    /// Walks that ended other than by exiting.
    lost: u64,
    /// Mean exit weight per channel.
    mean_weight: [f64; 3],
    max_deviation: f32,
}

impl Energy {
    fn of(stats: &[WalkStats]) -> Energy {
        let (mut walks, mut lost, mut exited, mut sum) = (0u64, 0u64, 0u64, [0.0f64; 3]);
        let mut max_deviation = 0.0f32;
        for s in stats {
            walks += u64::from(s.exited + s.terminated + s.truncated);
            lost += u64::from(s.terminated + s.truncated);
            exited += u64::from(s.exited);
            for (total, w) in sum.iter_mut().zip(s.weight_sum) {
                *total += f64::from(w);
            }
            max_deviation = max_deviation.max(s.max_weight_deviation);
        }
        Energy {
            walks,
            lost,
            mean_weight: sum.map(|w| w / exited.max(1) as f64),
            max_deviation,
        }
    }

    fn conserved(&self) -> bool {
        self.walks > 0
            && (self.lost as f64) <= LOST_FRACTION * self.walks as f64
            && self.max_deviation <= WEIGHT_TOLERANCE
            && self
                .mean_weight
                .iter()
                .all(|w| (w - 1.0).abs() <= f64::from(WEIGHT_TOLERANCE))
    }
}

/// Energy conservation of the GPU walk alone: in a gray, non-absorbing, isotropic medium every
/// walk on the closed meshes of `slab` and `bumpy` (40×30, 16 walks per pixel) exits, with
/// weight 1 per channel within `WEIGHT_TOLERANCE`, through an index-matched, a dielectric
/// (η = 1.4: Fresnel reflections and total internal reflection) and a diffuse boundary; at most
/// `LOST_FRACTION` of the walks end otherwise. Negative control: the same media with
/// `σa = 0.1 σt` fail the check: roulette kills walks (in a gray medium its survivors carry
/// `β/q = 1` exactly, so absorption shows as lost walks, not as lighter ones).
#[test]
fn gpu_walks_conserve_energy_at_albedo_one() {
    let Some((mut context, kernel)) = kernel_or_skip("random-walk energy", RANDOM_WALK) else {
        return;
    };
    for name in ["slab", "bumpy"] {
        let scene = scene(name);
        let gbuffer = GBuffer::render(&scene, FRAME);
        let uploaded = UploadedFrame::new(&context, &scene, &gbuffer, SEED).unwrap();
        for interface in [
            Interface::IndexMatched,
            Interface::Dielectric { eta: 1.4 },
            Interface::Diffuse,
        ] {
            let start = std::time::Instant::now();
            let media = gray_media(&scene, 0.0, interface);
            let gpu = render_gpu(&uploaded, &mut context, &kernel, &media, ENERGY_SPP);
            assert_eq!(
                gpu.cut, 0,
                "{name} {interface:?}: the device cut loops short"
            );
            let energy = Energy::of(&gpu.stats);
            eprintln!("{name} {interface:?}: {energy:?}, {:.2?}", start.elapsed());
            assert!(energy.conserved(), "{name} {interface:?}: {energy:?}");
            let absorbing = gray_media(&scene, 0.1, interface);
            let control = Energy::of(
                &render_gpu(&uploaded, &mut context, &kernel, &absorbing, ENERGY_SPP).stats,
            );
            eprintln!("{name} {interface:?}: control σa = 0.1 σt: {control:?}");
            assert!(
                !control.conserved(),
                "{name} {interface:?}: control with σa = 0.1 σt passes: {control:?}"
            );
        }
    }
}

/// Loops cut short by the device are reported, not hidden: in a gray albedo-1 medium with
/// `σt = 10⁴` per unit, 16 walks per pixel of `bumpy`'s object (3 328 walks), some walks reach
/// the 65 536-segment cap (a walk started next to the surface survives n collisions with
/// probability ~ n^{-1/2}, here ~ 1/256). On lavapipe, whose shared loop budget is 65 535
/// iterations per invocation group, those dispatches must be counted in `cut`; on a device
/// without that budget nothing is cut and the walks are reported truncated.
#[test]
fn loops_cut_short_by_the_device_are_reported() {
    let Some((mut context, kernel)) = kernel_or_skip("random-walk loop budget", RANDOM_WALK) else {
        return;
    };
    let scene = scene("bumpy");
    let gbuffer = GBuffer::render(&scene, FRAME);
    let uploaded = UploadedFrame::new(&context, &scene, &gbuffer, SEED).unwrap();
    let dense: Vec<GpuMedium> = gray_media(&scene, 0.0, Interface::IndexMatched)
        .iter()
        .map(|m| {
            let scale = 1e4 / m.sigma_t[0].max(f32::MIN_POSITIVE);
            GpuMedium {
                sigma_s: m.sigma_s.map(|s| s * scale),
                sigma_t: m.sigma_t.map(|s| s * scale),
                ..*m
            }
        })
        .collect();
    let start = std::time::Instant::now();
    let gpu = render_gpu(&uploaded, &mut context, &kernel, &dense, 16);
    let truncated: u32 = gpu.stats.iter().map(|s| s.truncated).sum();
    let lavapipe = context.device().name.contains("llvmpipe");
    eprintln!(
        "σt = 1e4: {} cut dispatches, {truncated} truncated walks (lavapipe: {lavapipe}), {:.2?}",
        gpu.cut,
        start.elapsed()
    );
    if lavapipe {
        assert!(gpu.cut > 0, "lavapipe: no cut reported for σt = 1e4");
    } else {
        assert_eq!(gpu.cut, 0, "a device without a loop budget reports cuts");
        assert!(truncated > 0, "σt = 1e4: no walk reached the bounce cap");
    }
}
