//! Parity of the scene twins (`sss/glsl/{scene,light,camera,material}.glsl`) and the G-buffer
//! pass (`engine/glsl/pass_gbuffer.glsl`) with `sss::scene`, through the Vulkan backend.
//!
//! Without Vulkan each test prints why it is skipped and passes, unless
//! `RESHIFT_REQUIRE_VULKAN=1`, which makes it fail.
//!
//! Which values must match bit for bit: everything computed with `+ − × ÷ sqrt` only (camera
//! rays, BVH hits, positions, geometric normals, light pdfs, radiance, selection, projection),
//! which lavapipe rounds as the CPU does. The exceptions, with their tolerances, are stated at
//! each comparison: shading normals (the corner normals the host can read are renormalised),
//! sphere-light samples (GPU `sin`/`cos`) and the Burley profile (GPU `exp`).

use engine::vulkan::testing::kernel_or_skip;
use std::path::Path;

use bytemuck::{Pod, Zeroable};
use engine::vulkan::{
    Buffer, Context, FrameParams, GBUFFER, GpuPixel, GpuScene, Kernel, PassParams, Shader,
    groups_for,
};
use glam::Vec3;
use restir::rng::{Stream, StreamKey};
use sss::color::luminance;
use sss::material::Material;
use sss::scene::{GBuffer, LightSample, Scene};

/// The run seed of every stream in this file.
const SEED: u64 = 0x5CE_4E5;

/// `parity_scene.glsl`: the scene (0–8), 9 [`SceneQuery`] in, 10 [`SceneResult`] out; push
/// constants: the query count.
const PARITY_SCENE: Shader = Shader::new("parity_scene", 11, 4);

/// `2⁻²³`: the largest relative spacing of f32 (one ulp at the bottom of a binade).
const ULP: f64 = 1.0 / 8_388_608.0;

fn stream(purpose: u32) -> Stream {
    StreamKey::new(0, 0, 0, purpose).stream(SEED)
}

/// Distance in units in the last place between two finite floats (`±0` are equal); `u64::MAX`
/// when exactly one is NaN.
fn ulps(a: f32, b: f32) -> u64 {
    if a.is_nan() || b.is_nan() {
        return if a.is_nan() && b.is_nan() {
            0
        } else {
            u64::MAX
        };
    }
    let key = |x: f32| {
        let bits = x.to_bits() as i64;
        if bits < 0 { i64::MIN - bits } else { bits }
    };
    key(a).abs_diff(key(b))
}

fn max_ulps(a: Vec3, b: Vec3) -> u64 {
    (0..3).map(|c| ulps(a[c], b[c])).max().unwrap()
}

fn max_abs(a: Vec3, b: Vec3) -> f64 {
    (a - b).abs().max_element() as f64
}

// ---------------------------------------------------------------------------------------------
// (a) G-buffer

/// G-buffer resolution of the parity test (small, so that ten scenes × two frames run in a
/// few seconds on lavapipe).
const GBUFFER_SIZE: (u32, u32) = (64, 48);

/// Shading-normal tolerance (absolute, per component of a unit vector). The host uploads the
/// corner normals as `Geometry::shading_normal` returns them at the corners: the stored unit
/// normal `n` renormalised, `n · (1/‖n‖)`, which moves each component by at most 2 ulp of 1
/// (2 · 2⁻²⁴: ‖n‖ is within an ulp of 1, plus the product's rounding). Interpolating with
/// barycentric weights summing to 1 keeps that bound on the interpolated vector, and
/// renormalising divides it by its length, ≥ ½ on the built-in meshes (smooth or flat), so
/// 2⁻²² plus the two renormalisations' own roundings (2 × 2⁻²⁴) bound the difference.
const SHADING_NORMAL_TOL: f64 = 1.0 / 4_194_304.0 + 2.0 / 16_777_216.0;

/// How one G-buffer differs from the CPU's.
#[derive(Debug, Default)]
struct GBufferDiff {
    pixels: usize,
    hits: usize,
    /// Pixels where hit/miss, object or prim differ.
    integer_mismatches: usize,
    /// Largest ulp distance over position, depth, bary, view and geometric normal.
    max_ulps: u64,
    max_shading_abs: f64,
}

impl GBufferDiff {
    fn passes(&self) -> bool {
        self.integer_mismatches == 0
            && self.max_ulps == 0
            && self.max_shading_abs <= SHADING_NORMAL_TOL
    }
}

fn compare_gbuffer(cpu: &GBuffer, gpu: &[GpuPixel]) -> GBufferDiff {
    let mut diff = GBufferDiff {
        pixels: cpu.pixels.len(),
        ..GBufferDiff::default()
    };
    assert_eq!(gpu.len(), cpu.pixels.len());
    for (want, got) in cpu.pixels.iter().zip(gpu) {
        match (want, got.to_cpu()) {
            (None, None) => {}
            (Some(w), Some(g)) if w.object == g.object && w.prim == g.prim => {
                diff.hits += 1;
                let exact = [
                    max_ulps(w.position, g.position),
                    max_ulps(w.view, g.view),
                    max_ulps(w.geometric_normal, g.geometric_normal),
                    ulps(w.depth, g.depth),
                ];
                diff.max_ulps = diff.max_ulps.max(*exact.iter().max().unwrap());
                diff.max_shading_abs = diff
                    .max_shading_abs
                    .max(max_abs(w.shading_normal, g.shading_normal));
            }
            _ => diff.integer_mismatches += 1,
        }
    }
    diff
}

/// `scene` at the parity resolution.
fn small(scene: Scene) -> Scene {
    let (w, h) = GBUFFER_SIZE;
    Scene {
        camera: scene.camera.with_resolution(w, h),
        ..scene
    }
}

fn gpu_gbuffer(
    context: &mut Context,
    kernel: &Kernel,
    gpu_scene: &GpuScene,
    scene: &Scene,
    frame: u32,
) -> (Vec<GpuPixel>, Option<f64>) {
    let params = FrameParams::new(scene, frame, None, SEED);
    let count = params.width * params.height;
    let params = params.buffer(context).unwrap();
    let out = Buffer::zeroed(context, count as usize * size_of::<GpuPixel>()).unwrap();
    let mut buffers = gpu_scene.buffers().to_vec();
    buffers.extend([&params, &out]);
    let timing = context
        .dispatch(
            kernel,
            &buffers,
            bytemuck::bytes_of(&PassParams::default()),
            [groups_for(count, GBUFFER.local_size), 1, 1],
        )
        .unwrap();
    (out.read::<GpuPixel>().unwrap(), timing.gpu_seconds)
}

/// The GPU G-buffer of every built-in scene at 64 × 48, frames 0 and 15, equals the CPU's:
/// hit/miss, object and prim exactly (0 mismatching pixels allowed: camera rays and the BVH
/// are bit-exact twins, so no ulp can cross a decision), position, depth, barycentrics, view
/// and geometric normal bit for bit (0 ulp), shading normals within [`SHADING_NORMAL_TOL`].
/// Negative control: the GPU's frame 0 against the CPU's frame 15 fails the same comparison.
#[test]
fn gbuffer_matches_cpu_on_builtin_scenes() {
    let Some((mut context, kernel)) = kernel_or_skip("gbuffer parity", GBUFFER) else {
        return;
    };
    let mut totals = GBufferDiff::default();
    for &(name, _) in Scene::BUILTIN {
        let scene = small(Scene::builtin(name).unwrap());
        // The device renders scenes at rest; a moving one is refused (`passing`, below).
        if scene.motion.is_some() {
            continue;
        }
        let gpu_scene = GpuScene::upload(&context, &scene).unwrap();
        let mut frame0 = Vec::new();
        for frame in [0, 15] {
            let cpu = GBuffer::render(&scene, frame);
            let (gpu, seconds) = gpu_gbuffer(&mut context, &kernel, &gpu_scene, &scene, frame);
            let diff = compare_gbuffer(&cpu, &gpu);
            eprintln!(
                "{name} frame {frame}: {} hits of {} pixels, {} integer mismatches, max {} ulp, \
                 shading normal max |Δ| {:.2e} (tolerance {SHADING_NORMAL_TOL:.2e}), {}",
                diff.hits,
                diff.pixels,
                diff.integer_mismatches,
                diff.max_ulps,
                diff.max_shading_abs,
                seconds.map_or("no timestamps".into(), |s| format!("{:.2} ms GPU", s * 1e3))
            );
            assert!(diff.passes(), "{name} frame {frame}: {diff:?}");
            assert!(
                diff.hits > 0,
                "{name} frame {frame}: the camera sees something"
            );
            totals.pixels += diff.pixels;
            totals.hits += diff.hits;
            totals.max_ulps = totals.max_ulps.max(diff.max_ulps);
            totals.max_shading_abs = totals.max_shading_abs.max(diff.max_shading_abs);
            if frame == 0 {
                frame0 = gpu;
            }
        }
        let wrong = compare_gbuffer(&GBuffer::render(&scene, 15), &frame0);
        eprintln!(
            "{name} negative control (GPU frame 0 vs CPU frame 15): {} integer mismatches, \
             max {} ulp",
            wrong.integer_mismatches, wrong.max_ulps
        );
        assert!(
            !wrong.passes(),
            "negative control: {name} GPU frame 0 passed as CPU frame 15: {wrong:?}"
        );
    }
    eprintln!("gbuffer parity totals: {totals:?}");
}

// ---------------------------------------------------------------------------------------------
// (b, c) lights, camera, material

/// `parity_scene.glsl`'s `SceneQuery` (std430, 60 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
struct SceneQuery {
    x: [f32; 3],
    u: [f32; 3],
    p: [f32; 3],
    light: u32,
    r: f32,
    mu: f32,
    max_d: f32,
    material: u32,
}

/// `parity_scene.glsl`'s `SceneResult` (std430, 128 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
struct SceneResult {
    sampled: u32,
    light: u32,
    is_delta: u32,
    distance: f32,
    point: [f32; 3],
    normal: [f32; 3],
    wi: [f32; 3],
    radiance: [f32; 3],
    pdf: f32,
    pdf_at_sample: f32,
    selection_pmf: f32,
    luminance: f32,
    radiance_at: [f32; 3],
    projected: u32,
    pixel: [f32; 2],
    radius_px: f32,
    profile: [f32; 3],
    fresnel: f32,
    pdf_at: f32,
}

/// One light of each kind around a translucent ball on a Lambert floor, with a moving,
/// jittered camera: the quad and triangle face down, a two-sided triangle stands upright (both
/// faces seen from the query points), the sphere is sampled by its cone.
const ALL_LIGHT_KINDS: &str = r#"
[camera]
resolution = [64, 48]
vfov = 45.0
eye = [0.0, 1.2, 3.0]
target = [0.0, 0.4, 0.0]
eye_end = [0.5, 1.4, 2.6]
target_end = [0.1, 0.4, 0.0]

[[materials]]
name = "wax"
type = "translucent"
albedo = [0.8, 0.6, 0.4]
mfp = [0.1, 0.05, 0.02]

[[materials]]
name = "floor"
type = "lambert"
albedo = [0.5, 0.5, 0.5]

[[objects]]
name = "ball"
material = "wax"
shape = { type = "sphere", radius = 0.5 }
transform = { translate = [0.0, 0.5, 0.0] }

[[objects]]
name = "floor"
material = "floor"
shape = { type = "quad", size = [6.0, 6.0] }

[[lights]]
type = "quad"
corner = [-0.5, 2.0, -0.4]
edge_u = [1.0, 0.1, 0.0]
edge_v = [0.0, 0.05, 0.8]
radiance = [4.0, 4.0, 4.0]

[[lights]]
type = "triangle"
vertices = [[1.5, 1.8, -0.5], [2.0, 2.1, 0.3], [1.2, 1.9, 0.8]]
radiance = [2.0, 4.0, 6.0]

[[lights]]
type = "triangle"
vertices = [[-1.8, 0.6, 1.5], [-1.2, 1.4, 1.2], [-1.9, 1.3, 0.4]]
radiance = [1.0, 3.0, 2.0]
two_sided = true

[[lights]]
type = "sphere"
center = [-1.5, 2.0, 0.5]
radius = 0.3
radiance = [3.0, 2.0, 1.0]

[[lights]]
type = "point"
position = [0.5, 1.5, 1.5]
intensity = [1.0, 1.0, 1.5]

[[lights]]
type = "directional"
direction = [0.3, -1.0, 0.2]
irradiance = [0.5, 0.5, 0.6]
"#;

/// Queries per scene.
const QUERIES: usize = 4096;
/// The camera frame of the projection queries.
const CAMERA_FRAME: u32 = 7;

fn random_in_box(rng: &mut Stream, lo: Vec3, hi: Vec3) -> Vec3 {
    let t = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
    lo + t * (hi - lo)
}

/// Shading points x in a box around the scene (some inside sphere lights, some behind one-sided
/// emitters), light sample numbers u, and for the pdf/radiance queries a point on a light: on
/// half of them the point of an independent CPU sample (so pdf > 0 is exercised), on the rest a
/// random point paired with a random light.
fn scene_queries(scene: &Scene, purpose: u32) -> Vec<SceneQuery> {
    let mut rng = stream(purpose);
    let (lo, hi) = (Vec3::new(-2.5, -0.2, -2.0), Vec3::new(2.5, 3.0, 2.5));
    (0..QUERIES)
        .map(|i| {
            let x = random_in_box(&mut rng, lo, hi);
            let u = [rng.next_f32(), rng.next_f32(), rng.next_f32()];
            let other = [rng.next_f32(), rng.next_f32(), rng.next_f32()];
            let (light, p) = match scene.lights.sample(x, other) {
                Some(s) if i % 2 == 0 => (s.light, s.point),
                _ => (
                    (rng.next_f32() * scene.lights.len() as f32) as u32 % scene.lights.len() as u32,
                    random_in_box(&mut rng, lo, hi),
                ),
            };
            let material = i as u32 % scene.materials.len() as u32;
            let r_max = match scene.materials[material as usize] {
                Material::Translucent(t) => t.r_max_all(),
                Material::Lambert(_) => 1.0,
            };
            SceneQuery {
                x: x.to_array(),
                u,
                p: p.to_array(),
                light,
                r: 1.1 * r_max * rng.next_f32(),
                mu: 2.4 * rng.next_f32() - 1.2,
                max_d: 1e-3 + 0.5 * rng.next_f32(),
                material,
            }
        })
        .collect()
}

fn run_queries(
    context: &mut Context,
    kernel: &Kernel,
    scene: &Scene,
    queries: &[SceneQuery],
) -> Vec<SceneResult> {
    let gpu_scene = GpuScene::upload(context, scene).unwrap();
    let params = FrameParams::new(scene, CAMERA_FRAME, None, SEED)
        .buffer(context)
        .unwrap();
    let input = Buffer::from_slice(context, queries).unwrap();
    let out = Buffer::zeroed(context, queries.len() * size_of::<SceneResult>()).unwrap();
    let mut buffers = gpu_scene.buffers().to_vec();
    buffers.extend([&params, &input, &out]);
    let count = queries.len() as u32;
    context
        .dispatch(
            kernel,
            &buffers,
            bytemuck::bytes_of(&count),
            [groups_for(count, PARITY_SCENE.local_size), 1, 1],
        )
        .unwrap();
    out.read::<SceneResult>().unwrap()
}

/// Sphere-light sample tolerance: the GPU's `sin` and `cos` of the disk angle have an absolute
/// error ≤ 2⁻¹¹ (Vulkan spec, "Precision and Operation of SPIR-V Instructions"; the CPU's libm
/// is within an ulp), which moves the unit normal by at most 2 · 2⁻¹¹ per component; the point
/// moves by radius times that, and the unit direction to it by at most twice that over the
/// distance. Everything else of a sphere sample (pdf, radiance, light) is exact.
const TRIG_ABS: f64 = 2.0 / 2048.0;

/// Light-sample differences of one run.
#[derive(Debug, Default)]
struct LightDiff {
    samples: usize,
    /// Queries where sampled/not sampled, light or is_delta differ.
    integer_mismatches: usize,
    /// Largest ulp distance over the bit-exact fields (all fields of non-sphere samples; pdf
    /// and radiance of sphere samples).
    max_ulps: u64,
    /// Largest sphere-sample error relative to its tolerance (≤ 1 passes).
    max_sphere_ratio: f64,
    sphere_samples: usize,
}

impl LightDiff {
    fn passes(&self) -> bool {
        self.integer_mismatches == 0 && self.max_ulps == 0 && self.max_sphere_ratio <= 1.0
    }
}

fn v3(a: [f32; 3]) -> Vec3 {
    Vec3::from_array(a)
}

fn compare_sample(
    scene: &Scene,
    want: Option<LightSample>,
    got: &SceneResult,
    diff: &mut LightDiff,
) {
    let Some(w) = want else {
        diff.integer_mismatches += usize::from(got.sampled != 0);
        return;
    };
    if got.sampled == 0 || got.light != w.light || (got.is_delta != 0) != w.is_delta {
        diff.integer_mismatches += 1;
        return;
    }
    diff.samples += 1;
    let exact = [ulps(got.pdf, w.pdf), max_ulps(v3(got.radiance), w.radiance)];
    diff.max_ulps = diff.max_ulps.max(exact.into_iter().max().unwrap());
    if let sss::scene::Light::Sphere { radius, .. } = *scene.lights.get(w.light) {
        diff.sphere_samples += 1;
        let r = radius as f64;
        let ratios = [
            max_abs(v3(got.normal), w.normal) / (TRIG_ABS + 4.0 * ULP),
            max_abs(v3(got.point), w.point)
                / (r * TRIG_ABS + 4.0 * ULP * w.point.abs().max_element() as f64),
            (got.distance as f64 - w.distance as f64).abs()
                / (r * TRIG_ABS + 4.0 * ULP * w.distance as f64),
            max_abs(v3(got.wi), w.wi) / (2.0 * r * TRIG_ABS / w.distance as f64 + 8.0 * ULP),
        ];
        diff.max_sphere_ratio = ratios.into_iter().fold(diff.max_sphere_ratio, f64::max);
    } else {
        let exact = [
            max_ulps(v3(got.point), w.point),
            max_ulps(v3(got.normal), w.normal),
            max_ulps(v3(got.wi), w.wi),
            ulps(got.distance, w.distance),
        ];
        diff.max_ulps = diff.max_ulps.max(exact.into_iter().max().unwrap());
    }
}

/// Burley profile bound (relative, per channel), as in `vulkan_parity.rs`: `pdf_disk` is within
/// `E + 6` ulp with `E = 3 + 2 r/d` the Vulkan bound of `exp`, and the albedo product adds one.
fn profile_bound(r: f32, d: f32) -> f64 {
    (3.0 + 2.0 * (r / d) as f64 + 7.0) * ULP
}

/// Profile error relative to [`profile_bound`] (≤ 1 passes) for one query.
fn profile_ratio(scene: &Scene, q: &SceneQuery, got: [f32; 3], r: f32) -> f64 {
    let Material::Translucent(t) = scene.materials[q.material as usize] else {
        return if got == [0.0; 3] { 0.0 } else { f64::INFINITY };
    };
    let want = t.profile_rgb(r);
    (0..3)
        .map(|c| {
            let (g, w) = (got[c] as f64, want[c] as f64);
            if g == w {
                0.0
            } else if w == 0.0 {
                f64::INFINITY
            } else {
                ((g - w) / w).abs() / profile_bound(r, t.d()[c])
            }
        })
        .fold(0.0, f64::max)
}

/// Everything else of one query that must match bit for bit: selection pmf, luminance, pdf
/// and radiance at the given point, pdf at the sample, projection, spatial radius, Fresnel.
/// Returns (max ulp, integer mismatches).
fn compare_rest(scene: &Scene, q: &SceneQuery, got: &SceneResult, frame: u32) -> (u64, usize) {
    let x = v3(q.x);
    let p = v3(q.p);
    let lights = &scene.lights;
    let mut worst = [
        ulps(got.selection_pmf, lights.selection_pmf(q.light)),
        ulps(got.luminance, luminance(v3(q.u))),
        ulps(got.pdf_at, lights.pdf(x, q.light, p)),
        max_ulps(v3(got.radiance_at), lights.radiance(q.light, p, x)),
        ulps(
            got.radius_px,
            scene.camera.spatial_radius_px(frame, x, q.max_d),
        ),
        ulps(
            got.fresnel,
            match scene.materials[q.material as usize] {
                Material::Translucent(t) => t.fresnel().eval(q.mu),
                Material::Lambert(_) => 0.0,
            },
        ),
    ]
    .into_iter()
    .max()
    .unwrap();
    if let Some(s) = lights.sample(x, q.u) {
        worst = worst.max(ulps(got.pdf_at_sample, lights.pdf(x, s.light, s.point)));
    }
    let projected = scene.camera.project(frame, x);
    let mismatches = usize::from(projected.is_some() != (got.projected != 0));
    if let Some(c) = projected {
        worst = worst
            .max(ulps(got.pixel[0], c.x))
            .max(ulps(got.pixel[1], c.y));
    }
    (worst, mismatches)
}

/// Light sampling, pdf and radiance, selection pmf, luminance, camera projection and spatial
/// radius, the Burley profile and Fresnel transmission agree with the CPU over N = 4096 random
/// queries on `many-lights` (512 sphere lights) and on a scene with one light of each kind.
/// Tolerances: 0 ulp and 0 integer mismatches for everything computed with + − × ÷ sqrt;
/// [`TRIG_ABS`] for the geometry of sphere samples; [`profile_bound`] for the profile.
/// Negative controls, each rejected by the same comparison: light samples of u with u₁ moved
/// by 2⁻⁸, the projection and radius of the previous frame's camera, and the profile at
/// r(1 + 2⁻⁸).
#[test]
fn lights_camera_material_match_cpu() {
    let Some((mut context, kernel)) = kernel_or_skip("scene parity", PARITY_SCENE) else {
        return;
    };
    let custom = Scene::from_toml_str(ALL_LIGHT_KINDS, Path::new("all-light-kinds.toml")).unwrap();
    let many = small(Scene::builtin("many-lights").unwrap());
    for (name, scene, purpose) in [("all-light-kinds", custom, 1), ("many-lights", many, 2)] {
        let queries = scene_queries(&scene, purpose);
        let results = run_queries(&mut context, &kernel, &scene, &queries);
        let (mut diff, mut perturbed) = (LightDiff::default(), LightDiff::default());
        let (mut rest_ulps, mut rest_mismatches) = (0u64, 0usize);
        let (mut wrong_frame_ulps, mut wrong_frame_mismatches) = (0u64, 0usize);
        let (mut profile, mut profile_wrong) = (0.0f64, 0.0f64);
        let mut kinds = [0usize; 5];
        for (q, got) in queries.iter().zip(&results) {
            let x = v3(q.x);
            let want = scene.lights.sample(x, q.u);
            if let Some(s) = want {
                kinds[sss_kind(scene.lights.get(s.light))] += 1;
            }
            compare_sample(&scene, want, got, &mut diff);
            let nudged = [q.u[0], (q.u[1] + 1.0 / 256.0).fract(), q.u[2]];
            compare_sample(&scene, scene.lights.sample(x, nudged), got, &mut perturbed);
            let (u, m) = compare_rest(&scene, q, got, CAMERA_FRAME);
            (rest_ulps, rest_mismatches) = (rest_ulps.max(u), rest_mismatches + m);
            let (u, m) = compare_rest(&scene, q, got, CAMERA_FRAME - 1);
            wrong_frame_ulps = wrong_frame_ulps.max(u);
            wrong_frame_mismatches += m;
            profile = profile.max(profile_ratio(&scene, q, got.profile, q.r));
            profile_wrong = profile_wrong.max(profile_ratio(
                &scene,
                q,
                got.profile,
                q.r * (1.0 + 1.0 / 256.0),
            ));
        }
        eprintln!(
            "{name}: N = {QUERIES}, samples per kind (quad, triangle, sphere, point, \
             directional) {kinds:?}; {diff:?}; other fields max {rest_ulps} ulp, \
             {rest_mismatches} projection mismatches; profile error / bound {profile:.3}"
        );
        eprintln!(
            "{name} negative controls: perturbed u {perturbed:?}; previous frame's camera \
             {wrong_frame_ulps} ulp, {wrong_frame_mismatches} mismatches; profile at r(1 + 2⁻⁸) \
             error / bound {profile_wrong:.1}"
        );
        assert!(diff.passes(), "{name}: light samples differ: {diff:?}");
        assert_eq!(
            (rest_ulps, rest_mismatches),
            (0, 0),
            "{name}: pdf/radiance/camera/fresnel"
        );
        assert!(profile <= 1.0, "{name}: profile error / bound {profile}");
        assert!(
            !perturbed.passes(),
            "negative control (perturbed u) passed: {perturbed:?}"
        );
        assert!(
            wrong_frame_ulps > 0 || wrong_frame_mismatches > 0,
            "negative control: the previous frame's camera matched"
        );
        assert!(
            profile_wrong > 1.0,
            "negative control: the profile at a wrong r matched"
        );
        if name == "all-light-kinds" {
            assert!(
                kinds.iter().all(|&k| k > 100),
                "every light kind is sampled: {kinds:?}"
            );
        }
    }
}

/// Index of a light's kind in (quad, triangle, sphere, point, directional).
fn sss_kind(light: &sss::scene::Light) -> usize {
    use sss::scene::Light::*;
    match light {
        Quad { .. } => 0,
        Triangle { .. } => 1,
        Sphere { .. } => 2,
        Point { .. } => 3,
        Directional { .. } => 4,
    }
}
