//! The image-space method of paper 002 on the device (`method_image_space.glsl`,
//! `image_space.glsl`) against its CPU twin [`render`].
//!
//! Without Vulkan each test prints why it is skipped and passes, unless
//! `RESHIFT_REQUIRE_VULKAN=1`, which makes it fail.

use super::cpu::{EntryCounts, ImageSpaceSettings, render};
use super::vulkan::{IMAGE_SPACE, render_image_space, scene_gather_profiles};
use engine::vulkan::testing::{UploadedFrame, kernel_or_skip, pixel_error, rel_mse_pixels};
use glam::Vec3;
use sss::material::Material;
use sss::scene::{GBuffer, Scene};

const WIDTH: u32 = 40;
const HEIGHT: u32 = 30;
/// Frame > 0, so that a frame-less stream key would be caught.
const FRAME: u32 = 3;
const SEED: u64 = 21;
const OTHER_SEED: u64 = 22;
/// Passes per pixel of the parity test.
const SPP: u32 = 2;

fn scene(name: &str) -> Scene {
    let mut scene = Scene::builtin(name).expect("built-in scene");
    scene.camera = scene.camera.with_resolution(WIDTH, HEIGHT);
    scene
}

/// The largest difference of one kind of [`EntryCounts`] between `a` and `b`, as a fraction of
/// the samples drawn.
fn entry_difference(a: &EntryCounts, b: &EntryCounts) -> f64 {
    let pairs = [
        (a.samples, b.samples),
        (a.off_screen, b.off_screen),
        (a.occluded, b.occluded),
        (a.outside, b.outside),
        (a.edge_on, b.edge_on),
    ];
    let worst = pairs.iter().map(|&(x, y)| x.abs_diff(y)).max().unwrap();
    worst as f64 / b.samples.max(1) as f64
}

/// The parity criterion: relMSE(GPU, CPU same seed) over the translucent pixels must be below
/// this fraction of relMSE(CPU other seed, CPU same seed). Bit-exactness is impossible: the
/// dipole's Newton inversion and profile take `exp`, `expm1` and `log1p`, the disk angle `cos`
/// and `sin`, and lavapipe's are a few ulp off the CPU's libm. Such an ulp moves a tangent-plane
/// point `p′` by about 1e-7 of its radius; it changes the looked-up pixel (and with it the entry
/// point, its normal and `E`) only where `p′` projects within that distance of a pixel edge or
/// the truncation radius, and the sample then behaves like an independent one. The ratio is
/// therefore about the fraction of such samples; 0.01 allows one in a hundred.
const RATIO: f64 = 0.01;
/// Per pixel: the error of a translucent pixel (its channels' largest difference over its largest
/// channel, `testing::pixel_error`) may exceed this on at most a fraction `RATIO` of them. The
/// transcendentals' few-ulp differences (≈ 1e-7 relative each) compound through the Newton
/// inversion, the profile and ten gather samples to a few 1e-6 (measured at most 4.3e-6 here);
/// 1e-4 leaves a factor 20, while a sample that looked up another pixel moves its pixel by a
/// sizeable fraction of its value.
const PIXEL_TOLERANCE: f64 = 1e-4;
/// Largest difference of an entry count (off screen, occluded, outside, edge-on) between GPU and
/// CPU as a fraction of the samples: a flipped lookup moves one sample from one kind to another.
const ENTRY_FRACTION: f64 = 0.01;

/// `method_image_space` at 2 passes on the CPU's G-buffer reproduces `image_space::render` with
/// the same seed on `bumpy`, `slab` and `materials` (40×30, frame 3): on translucent pixels
/// at most 1 % of them off by more than 1e-4 and relMSE(GPU, CPU) ≤ 0.01 · relMSE(CPU seed 22,
/// CPU seed 21), the same ratio on Lambert (path-traced) pixels, the entry counts within 1 % of
/// the samples drawn, nothing left out as non-finite and no dispatch cut short. Negative control: the GPU with the other seed fails both image criteria.
#[test]
fn image_space_method_matches_the_cpu() {
    let Some((mut context, kernel)) = kernel_or_skip("image-space parity", IMAGE_SPACE) else {
        return;
    };
    let settings = ImageSpaceSettings::default();
    for name in ["bumpy", "slab", "materials"] {
        let start = std::time::Instant::now();
        let scene = scene(name);
        let gbuffer = GBuffer::render(&scene, FRAME);
        let profiles = scene_gather_profiles(&scene, &settings);
        let uploaded = UploadedFrame::new(&context, &scene, &gbuffer, SEED).unwrap();
        let gpu = render_image_space(
            &mut context,
            &kernel,
            &uploaded.input(),
            &profiles,
            &settings,
            SPP,
        )
        .unwrap();
        assert_eq!(gpu.cut, 0, "{name}: the device cut loops short");
        let cpu = render(&scene, &gbuffer, &settings, SEED, SPP);
        let replica = render(&scene, &gbuffer, &settings, OTHER_SEED, SPP);
        let cpu_pixels: Vec<Vec3> = cpu.image.pixels.iter().map(|p| p.as_vec3()).collect();
        let replica_pixels: Vec<Vec3> = replica.image.pixels.iter().map(|p| p.as_vec3()).collect();
        let gpu_pixels = &gpu.image.image.pixels;
        let translucent = |want: bool| -> Vec<usize> {
            (0..gbuffer.pixels.len())
                .filter(|&p| {
                    gbuffer.pixels[p].is_some_and(|g| {
                        matches!(scene.material_of_object(g.object), Material::Translucent(_))
                            == want
                    })
                })
                .collect()
        };
        let (gather_pixels, pt_pixels) = (translucent(true), translucent(false));
        assert!(
            gather_pixels.len() > 50,
            "{name}: {} translucent pixels",
            gather_pixels.len()
        );
        assert_eq!(
            (gpu.image.left_out, cpu.image.nonfinite),
            (0, 0),
            "{name}: left out"
        );
        let exact = gather_pixels
            .iter()
            .filter(|&&p| gpu_pixels[p] == cpu_pixels[p])
            .count();
        let noise = rel_mse_pixels(&replica_pixels, &cpu_pixels, gather_pixels.iter().copied());
        let ratio = rel_mse_pixels(gpu_pixels, &cpu_pixels, gather_pixels.iter().copied()) / noise;
        let pt_ratio = rel_mse_pixels(gpu_pixels, &cpu_pixels, pt_pixels.iter().copied())
            / rel_mse_pixels(&replica_pixels, &cpu_pixels, pt_pixels.iter().copied());
        let entries = entry_difference(&gpu.entries, &cpu.entries);
        let errors: Vec<f64> = gather_pixels
            .iter()
            .map(|&p| pixel_error(gpu_pixels[p], cpu_pixels[p]))
            .collect();
        let worst = errors.iter().copied().fold(0.0, f64::max);
        let beyond = errors.iter().filter(|&&e| e > PIXEL_TOLERANCE).count();
        eprintln!(
            "{name}: {} translucent pixels ({exact} bit-identical, worst error {worst:.2e}, \
             {beyond} beyond {PIXEL_TOLERANCE:e}), relMSE ratio {ratio:.2e} \
             (noise {noise:.3e}); entry counts GPU {:?} CPU {:?} (worst difference {entries:.2e}); \
             {} Lambert pixels, ratio {pt_ratio:.2e}; {:.2?}",
            gather_pixels.len(),
            gpu.entries,
            cpu.entries,
            pt_pixels.len(),
            start.elapsed()
        );
        assert!(
            beyond as f64 <= RATIO * gather_pixels.len() as f64,
            "{name}: {beyond} pixels beyond {PIXEL_TOLERANCE:e}"
        );
        assert!(
            ratio <= RATIO,
            "{name}: relMSE(GPU, CPU) / relMSE(replica, CPU) = {ratio:.3e} > {RATIO}"
        );
        assert!(
            entries <= ENTRY_FRACTION,
            "{name}: entry counts GPU {:?}, CPU {:?}",
            gpu.entries,
            cpu.entries
        );
        assert_eq!(gpu.entries.samples, cpu.entries.samples, "{name}");
        if !pt_pixels.is_empty() {
            assert!(
                pt_ratio <= RATIO,
                "{name}: Lambert pixels: ratio {pt_ratio:.3e} > {RATIO}"
            );
        }

        let other = UploadedFrame::new(&context, &scene, &gbuffer, OTHER_SEED).unwrap();
        let control = render_image_space(
            &mut context,
            &kernel,
            &other.input(),
            &profiles,
            &settings,
            SPP,
        )
        .unwrap();
        let control_beyond = gather_pixels
            .iter()
            .filter(|&&p| {
                pixel_error(control.image.image.pixels[p], cpu_pixels[p]) > PIXEL_TOLERANCE
            })
            .count();
        assert!(
            control_beyond as f64 > RATIO * gather_pixels.len() as f64,
            "{name}: control with another seed passes the per-pixel criterion"
        );
        let control_ratio = rel_mse_pixels(
            &control.image.image.pixels,
            &cpu_pixels,
            gather_pixels.iter().copied(),
        ) / noise;
        eprintln!("{name}: control (seed {OTHER_SEED}): relMSE ratio {control_ratio:.2e}");
        assert!(
            control_ratio > RATIO,
            "{name}: control with another seed passes: ratio {control_ratio:.3e} ≤ {RATIO}"
        );
    }
}
