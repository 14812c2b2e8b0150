//! Parity of the BSSRDF IS twins (`sss/glsl/bssrdf.glsl`, `shifts/glsl/domain.glsl`) and of the
//! candidates pass (`engine/glsl/pass_candidates.glsl`) with the CPU, through the Vulkan
//! backend on whatever device it chooses (Mesa lavapipe in CI).
//!
//! Inputs come from the CPU (G-buffer, random numbers), so each comparison sees one twin.
//! Without Vulkan each test prints why it is skipped and passes, unless
//! `RESHIFT_REQUIRE_VULKAN=1`, which makes it fail.
//!
//! Why floats differ: `+ − × ÷ sqrt` match bit for bit, but the sampled radius goes through
//! `burley_sample_radius` (≤ 32 ulp, see `vulkan_parity.rs`), the disk angle through the device's
//! `cos`/`sin`, the profile through `exp` and the inverted angle through `atan`. So a probe ray's
//! origin moves by a few ulp of the scene scale, its hits' `t` and barycentrics follow, and every
//! density evaluated at a hit (p_disk, f, p̂) inherits that relative error plus `exp`'s bound.
//! Why integers may differ: such a shift can carry a hit across a triangle edge or the chord's
//! end, or flip a comparison that sits at a boundary (a RIS selection `u·w_sum < w`, the
//! posterior CDF of inversion, the shadow ray grazing an edge). Each test states how many such
//! flips it allows.

use bytemuck::{Pod, Zeroable};
use engine::PixelReservoir;
use engine::candidates;
use engine::purpose;
use engine::vulkan::testing::{Tally, kernel_or_skip, rel_error, scaled_error};
use engine::vulkan::{
    BVH_MAX_HITS, Buffer, CANDIDATES, Context, FrameParams, GpuPixel, GpuScene, PassParams, Shader,
    groups_for,
};
use geometry::Hit;
use geometry::contract::bvh::NO_HIT;
use restir::rng::StreamKey;
use restir::shift::Domain;
use shifts::{Hybrid, SssDomain, SssSample};
use sss::bssrdf::{
    BssrdfSample, EntryPoint, Probe, Technique, TechniqueSelection, invert, invert_technique,
    pick_hit,
};
use sss::contract::bssrdf::INDEX_UNKNOWN;
use sss::scene::{GBuffer, GPixel, Scene};

/// `parity_bssrdf.glsl`: scene (0–8), G-buffer (9), queries (10), results (11); push constants
/// query count and pass index.
const PARITY_BSSRDF: Shader = Shader::new("parity_bssrdf", 12, 8);

/// The scenes of both tests: closed bumpy sphere with a shadow edge, a flat slab under a shadow
/// edge, and ten materials side by side.
const SCENES: [&str; 3] = ["bumpy", "half-shadow", "materials"];

fn scene(name: &str, size: u32) -> Scene {
    let mut scene = Scene::builtin(name).unwrap();
    scene.camera = scene.camera.with_resolution(size, size);
    scene
}

// ---------------------------------------------------------------------- function-level parity

/// `parity_bssrdf.glsl`'s `BssrdfQuery` (std430, 36 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
struct BssrdfQuery {
    pixel: u32,
    u_technique: f32,
    u_radius: f32,
    u_angle: f32,
    u_pick: f32,
    gamma: f32,
    u_light: [f32; 3],
}

/// `parity_bssrdf.glsl`'s `BssrdfResult` (std430, 204 bytes with `BVH_MAX_HITS` = 8).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
struct BssrdfResult {
    domain: u32,
    technique: u32,
    /// The technique that `with_channel_weights(u_light − ¼)` samples, 9 if it is `None`.
    weighted_technique: u32,
    u_lo: f32,
    u_hi: f32,
    ray_ok: u32,
    origin: [f32; 3],
    dir: [f32; 3],
    t_max: f32,
    hit_count: u32,
    hit_prims: [u32; BVH_MAX_HITS],
    hit_ts: [f32; BVH_MAX_HITS],
    picked: u32,
    rank: u32,
    prim: u32,
    object: u32,
    p_disk: f32,
    light_ok: u32,
    light: u32,
    contribution: [f32; 3],
    target: f32,
    visible: u32,
    hybrid: u32,
    inverted_u_radius: f32,
    inverted_u_angle: f32,
    invert_code: u32,
    invert_technique: u32,
    invert_u_radius: f32,
    invert_u_angle: f32,
    invert_index: u32,
    invert_p_disk: f32,
}

/// What `parity_bssrdf.glsl` computes, on the CPU: the same calls in the same order.
fn cpu_result(
    scene: &Scene,
    gpixel: Option<&GPixel>,
    q: &BssrdfQuery,
    pass: u32,
    seed: u64,
) -> BssrdfResult {
    let mut r = BssrdfResult {
        hit_prims: [NO_HIT; BVH_MAX_HITS],
        ..BssrdfResult::default()
    };
    let Some(domain) = gpixel.and_then(|g| SssDomain::new(scene, g, q.pixel, 0, pass, seed)) else {
        return r;
    };
    r.domain = 1;
    let geometry = &scene.geometry;
    let (x1, selection) = (domain.x1(), domain.selection());
    let probe = Probe::sample(selection, q.u_technique, q.u_radius, q.u_angle);
    r.technique = probe.technique.index() as u32;
    r.weighted_technique = TechniqueSelection::with_channel_weights(q.u_light.map(|u| u - 0.25))
        .map_or(Technique::COUNT as u32, |w| {
            w.sample(q.u_technique).index() as u32
        });
    (r.u_lo, r.u_hi) = selection.u_interval(probe.technique);
    if let Some(ray) = probe.ray(x1) {
        r.ray_ok = 1;
        r.origin = ray.origin.to_array();
        r.dir = ray.dir.to_array();
        r.t_max = ray.t_max;
    }
    let mut hits: Vec<Hit> = Vec::new();
    probe.trace(geometry, x1, &mut hits);
    r.hit_count = hits.len() as u32;
    for (k, hit) in hits.iter().take(BVH_MAX_HITS).enumerate() {
        r.hit_prims[k] = hit.prim;
        r.hit_ts[k] = hit.t;
    }
    let Some((rank, hit)) = pick_hit(&hits, None, q.u_pick) else {
        return r;
    };
    (r.picked, r.rank, r.prim) = (1, rank, hit.prim);
    let x2 = EntryPoint::from_hit(geometry, &hit);
    r.object = x2.object;
    let p_disk = domain.p_disk(&x2);
    r.p_disk = p_disk;
    let inverted = invert_technique(x1, probe.technique, x2.position);
    (r.inverted_u_radius, r.inverted_u_angle) = (inverted.u_radius, inverted.u_angle);
    match invert(geometry, x1, selection, &x2, q.gamma, &mut Vec::new()) {
        Ok(s) => {
            r.invert_technique = s.technique.index() as u32;
            (r.invert_u_radius, r.invert_u_angle) = (s.u_radius, s.u_angle);
            r.invert_index = s.index.unwrap_or(INDEX_UNKNOWN);
            r.invert_p_disk = s.p_disk;
        }
        Err(fail) => {
            r.invert_code = fail.code();
            r.invert_index = INDEX_UNKNOWN;
        }
    }
    if let Some(light) = scene.lights.sample(x2.position, q.u_light) {
        r.light_ok = 1;
        r.light = light.light;
        let bssrdf = BssrdfSample::new(&probe, Some(rank), &x2, p_disk);
        let y = SssSample::new(&bssrdf, light.light, light.point);
        r.contribution = domain.contribution(&y).to_array();
        r.target = domain.target(&y);
        r.visible = domain.visible(&y) as u32;
        r.hybrid = match Hybrid::for_material(domain.material()).uses_reconnection(&y, &domain) {
            Some(true) => 1,
            Some(false) => 2,
            None => 0,
        };
    }
    r
}

/// The integer fields of a result, for exact comparison.
fn integers(r: &BssrdfResult) -> Vec<u32> {
    let stored = (r.hit_count as usize).min(BVH_MAX_HITS);
    let mut v = vec![
        r.domain,
        r.technique,
        r.weighted_technique,
        r.ray_ok,
        r.hit_count,
        r.picked,
        r.rank,
        r.prim,
        r.object,
        r.light_ok,
        r.light,
        r.visible,
        r.hybrid,
        r.invert_code,
        r.invert_technique,
        r.invert_index,
    ];
    v.extend_from_slice(&r.hit_prims[..stored]);
    v
}

/// Compares GPU results with the CPU's; floats only where all integers agree.
fn compare_results(
    scene: &Scene,
    gbuffer: &GBuffer,
    queries: &[BssrdfQuery],
    got: &[BssrdfResult],
    pass: u32,
    seed: u64,
) -> Tally {
    let mut tally = Tally::new(&BOUNDS);
    for (q, g) in queries.iter().zip(got) {
        let gpixel = gbuffer.pixels[q.pixel as usize].as_ref();
        let want = cpu_result(scene, gpixel, q, pass, seed);
        tally.compared += 1;
        if integers(g) != integers(&want) {
            tally.mismatched += 1;
            continue;
        }
        let r_max = gpixel
            .and_then(|p| SssDomain::new(scene, p, q.pixel, 0, pass, seed))
            .map_or(1.0, |d| d.x1().r_max.max_element());
        if compare_floats(&mut tally, g, &want, r_max) {
            tally.beyond_bounds += 1;
        }
    }
    tally
}

/// Records the float errors of one query whose integers agree; true if any exceeds its bound.
fn compare_floats(tally: &mut Tally, g: &BssrdfResult, want: &BssrdfResult, r_max: f32) -> bool {
    // Random numbers in [0, 1) wrap at 1 for the angle: compare on the circle.
    let on_circle = |a: f32, b: f32| {
        let d = (a as f64 - b as f64).abs();
        d.min(1.0 - d)
    };
    let absolute = |a: f32, b: f32| (a as f64 - b as f64).abs();
    let stored = (g.hit_count as usize).min(BVH_MAX_HITS);
    let mut beyond = [
        tally.float(
            "u interval",
            rel_error(g.u_lo, want.u_lo).max(rel_error(g.u_hi, want.u_hi)),
        ),
        tally.float("ray dir", scaled_error(&g.dir, &want.dir, 1.0)),
        tally.float(
            "ray origin / r_max",
            scaled_error(&g.origin, &want.origin, r_max),
        ),
        tally.float(
            "t_max / r_max",
            scaled_error(&[g.t_max], &[want.t_max], r_max),
        ),
        tally.float(
            "hit t / r_max",
            scaled_error(&g.hit_ts[..stored], &want.hit_ts[..stored], r_max),
        ),
    ]
    .contains(&true);
    if g.picked == 0 {
        return beyond;
    }
    beyond |= tally.float("p_disk", rel_error(g.p_disk, want.p_disk));
    beyond |= tally.float(
        "inverted u_radius",
        absolute(g.inverted_u_radius, want.inverted_u_radius),
    );
    beyond |= tally.float(
        "inverted u_angle",
        on_circle(g.inverted_u_angle, want.inverted_u_angle),
    );
    if g.invert_code == 0 {
        beyond |= tally.float(
            "invert u_radius",
            absolute(g.invert_u_radius, want.invert_u_radius),
        );
        beyond |= tally.float(
            "invert u_angle",
            on_circle(g.invert_u_angle, want.invert_u_angle),
        );
        beyond |= tally.float(
            "invert p_disk",
            rel_error(g.invert_p_disk, want.invert_p_disk),
        );
    }
    if g.light_ok != 0 {
        for c in 0..3 {
            beyond |= tally.float("f", rel_error(g.contribution[c], want.contribution[c]));
        }
        beyond |= tally.float("target", rel_error(g.target, want.target));
    }
    beyond
}

/// `count` queries on the translucent pixels of `gbuffer`, round robin over pixels, with random
/// numbers from the test's own streams (purpose 0x7E57_0000 | query).
fn queries(scene: &Scene, gbuffer: &GBuffer, count: usize, seed: u64) -> Vec<BssrdfQuery> {
    let pixels: Vec<u32> = gbuffer
        .pixels
        .iter()
        .enumerate()
        .filter(|(i, g)| {
            g.as_ref()
                .is_some_and(|g| SssDomain::new(scene, g, *i as u32, 0, 0, seed).is_some())
        })
        .map(|(i, _)| i as u32)
        .collect();
    assert!(!pixels.is_empty(), "{}: no translucent pixel", scene.name);
    (0..count)
        .map(|k| {
            let pixel = pixels[k % pixels.len()];
            let mut rng = StreamKey::new(pixel, 0, 0, 0x7E57_0000 | k as u32).stream(seed);
            let mut u = || rng.next_f32();
            BssrdfQuery {
                pixel,
                u_technique: u(),
                u_radius: u(),
                u_angle: u(),
                u_pick: u(),
                gamma: u(),
                u_light: [u(), u(), u()],
            }
        })
        .collect()
}

/// Bounds of the function-level comparison (module doc for the causes), each about ten times
/// the worst error seen on lavapipe (bumpy, half-shadow, materials):
/// - the technique interval: `+` and `×` of the selection's probabilities only: exact;
/// - the probe direction: `Frame::from_normal` uses `+ − × ÷` only: exact;
/// - chord origin, `t_max` and hit `t`, relative to `r_max`: the radius (≤ 32 ulp of `r`) and
///   the device's `cos`/`sin` move the disk point by ~1e-7 r_max, the chord half-length
///   `h = √(r_max² − r²)` amplifies it by `r/h` near the chord's end (seen: 1.5e-6): 1e-5;
/// - densities at the hit (p_disk, f, p̂): `exp`'s bound (3 + 2|x| ulp) plus the hit's
///   displacement times the profile's log-slope `1/d`, with `r_max / d` up to ~20 per channel
///   (seen: 8e-5): 5e-4;
/// - re-derived random numbers (absolute, in [0, 1)): the CDF and `atan2` at a displaced x2
///   (seen: 8e-6): 5e-5.
const BOUNDS: [(&str, f64); 13] = [
    ("u interval", 0.0),
    ("ray dir", 0.0),
    ("ray origin / r_max", 1e-5),
    ("t_max / r_max", 1e-5),
    ("hit t / r_max", 1e-5),
    ("p_disk", 5e-4),
    ("f", 5e-4),
    ("target", 5e-4),
    ("invert p_disk", 5e-4),
    ("inverted u_radius", 5e-5),
    ("inverted u_angle", 5e-5),
    ("invert u_radius", 5e-5),
    ("invert u_angle", 5e-5),
];

/// At most this fraction of queries may differ in an integer field: each query makes about a
/// dozen discrete decisions on values that differ by ~1e-6 relative, so a flip needs a value
/// within ~1e-6 of a boundary, which a few queries in 10⁴ can be.
const FUNCTION_MISMATCH_FRACTION: f64 = 2e-3;

/// Function-level parity on `bumpy`, `half-shadow` and `materials` (24×24, frame 0, 1536
/// queries each on the translucent pixels): technique and its u interval, the technique of a
/// channel-weighted selection (weights `u − ¼`, so some are rejected), probe ray, all hits
/// (count, prims, t), the uniform pick, p_disk, f and p̂ of a light sample, visibility, the
/// hybrid criterion, `invert_technique` and `invert` (recovered u's, index, p_disk). Integer
/// fields exact up to [`FUNCTION_MISMATCH_FRACTION`], floats within [`BOUNDS`]. Negative
/// control: the same queries answered at the neighbouring pixel's x1 (every query's `pixel`
/// shifted by one) must exceed the allowed mismatch fraction.
#[test]
fn bssrdf_functions_match_the_cpu() {
    let Some((mut context, kernel)) = kernel_or_skip("bssrdf parity", PARITY_BSSRDF) else {
        return;
    };
    let (seed, pass, count) = (11u64, 0u32, 1536usize);
    for name in SCENES {
        let scene = scene(name, 24);
        let gbuffer = GBuffer::render(&scene, 0);
        let gpu_scene = GpuScene::upload(&context, &scene).unwrap();
        let frame = FrameParams::new(&scene, 0, None, seed)
            .buffer(&context)
            .unwrap();
        let pixels: Vec<GpuPixel> = gbuffer
            .pixels
            .iter()
            .map(|g| GpuPixel::from_cpu(g.as_ref()))
            .collect();
        let pixel_buffer = Buffer::from_slice(&context, &pixels).unwrap();
        let run = |context: &mut Context, queries: &[BssrdfQuery]| {
            let query_buffer = Buffer::from_slice(context, queries).unwrap();
            let results =
                Buffer::zeroed(context, queries.len() * size_of::<BssrdfResult>()).unwrap();
            let mut buffers: Vec<&Buffer> = gpu_scene.buffers().to_vec();
            buffers.extend([&frame, &pixel_buffer, &query_buffer, &results]);
            let push = [queries.len() as u32, pass];
            context
                .dispatch(
                    &kernel,
                    &buffers,
                    bytemuck::bytes_of(&push),
                    [
                        groups_for(queries.len() as u32, PARITY_BSSRDF.local_size),
                        1,
                        1,
                    ],
                )
                .unwrap();
            results.read::<BssrdfResult>().unwrap()
        };
        let queries = queries(&scene, &gbuffer, count, seed);
        let got = run(&mut context, &queries);
        let tally = compare_results(&scene, &gbuffer, &queries, &got, pass, seed);
        let multi_hit = got.iter().filter(|r| r.hit_count > 1).count();
        eprintln!(
            "bssrdf parity, {name}: {} queries ({multi_hit} with > 1 hit), {} with an integer \
             mismatch ({:.2e}); worst {:?}",
            tally.compared,
            tally.mismatched,
            tally.mismatch_fraction(),
            tally.worst
        );
        assert!(
            tally.mismatch_fraction() <= FUNCTION_MISMATCH_FRACTION,
            "{name}: {} of {} queries differ in an integer field (allowed {FUNCTION_MISMATCH_FRACTION})",
            tally.mismatched,
            tally.compared
        );
        assert_eq!(
            tally.beyond_bounds, 0,
            "{name}: float errors beyond BOUNDS; worst {:?}",
            tally.worst
        );
        // Negative control: x1 of the next pixel (wrapping) for every query.
        let n = gbuffer.pixels.len() as u32;
        let shifted: Vec<BssrdfQuery> = queries
            .iter()
            .map(|q| BssrdfQuery {
                pixel: (q.pixel + 1) % n,
                ..*q
            })
            .collect();
        let wrong = run(&mut context, &shifted);
        let control = compare_results(&scene, &gbuffer, &queries, &wrong, pass, seed);
        eprintln!(
            "bssrdf parity, {name}: control (neighbouring x1) rejected {:.3}",
            control.rejected_fraction()
        );
        assert!(
            control.rejected_fraction() > FUNCTION_MISMATCH_FRACTION,
            "{name}: negative control undetected ({} of {})",
            control.mismatched,
            control.compared
        );
    }
}

// ---------------------------------------------------------------------- pass-level parity

/// One candidates configuration: scene, BSSRDF samples M, shared light numbers, pass index.
struct PassCase {
    scene: &'static str,
    bssrdf_samples: u32,
    shared_light: bool,
    pass: u32,
}

const PASS_CASES: [PassCase; 3] = [
    PassCase {
        scene: "bumpy",
        bssrdf_samples: 2,
        shared_light: true,
        pass: 0,
    },
    PassCase {
        scene: "half-shadow",
        bssrdf_samples: 1,
        shared_light: false,
        pass: 0,
    },
    PassCase {
        scene: "materials",
        bssrdf_samples: 3,
        shared_light: true,
        pass: 2,
    },
];

/// The CPU's Candidates arm (`cpu::run`) for every pixel: reservoir and diag
/// `(probes, hits, hybrid choice, 0)`.
fn cpu_pass(
    scene: &Scene,
    gbuffer: &GBuffer,
    case: &PassCase,
    seed: u64,
) -> Vec<(PixelReservoir, [u32; 4])> {
    let mut hits = Vec::new();
    (0..gbuffer.pixels.len() as u32)
        .map(|pixel| {
            let Some(domain) = gbuffer.pixels[pixel as usize]
                .as_ref()
                .and_then(|g| SssDomain::new(scene, g, pixel, gbuffer.frame, case.pass, seed))
            else {
                return (PixelReservoir::empty(), [0; 4]);
            };
            let (mut canonical, counts) = candidates::generate(
                &domain,
                case.bssrdf_samples,
                case.shared_light,
                seed,
                &mut hits,
            )
            .unwrap();
            candidates::shadow_test(&domain, &mut canonical);
            let hybrid = Hybrid::for_material(domain.material());
            let choice = match canonical
                .y
                .and_then(|y| hybrid.uses_reconnection(&y, &domain))
            {
                Some(true) => 1,
                Some(false) => 2,
                None => 0,
            };
            (
                PixelReservoir::from(&canonical),
                [counts.probes, counts.hits, choice, 0],
            )
        })
        .collect()
}

/// Compares the GPU's reservoirs and diag with the CPU's, pixel by pixel.
fn compare_pass(
    cpu: &[(PixelReservoir, [u32; 4])],
    reservoirs: &[PixelReservoir],
    diag: &[[u32; 4]],
) -> Tally {
    let mut tally = Tally::new(&PASS_BOUNDS);
    for ((want, want_diag), (got, got_diag)) in cpu.iter().zip(reservoirs.iter().zip(diag)) {
        tally.compared += 1;
        let (w, g) = (&want.y, &got.y);
        let key = |r: &PixelReservoir, s: &SssSample| {
            (
                r.has_sample,
                s.object(),
                s.prim(),
                s.technique().map(|t| t.index()),
                s.index(),
                s.light(),
            )
        };
        if key(want, w) != key(got, g) || want_diag != got_diag {
            tally.mismatched += 1;
            continue;
        }
        let mut beyond = tally.float("confidence", rel_error(got.confidence, want.confidence));
        beyond |= tally.float("ucw", rel_error(got.ucw, want.ucw));
        if want.has_sample != 0 {
            beyond |= tally.float(
                "u_radius, u_angle",
                rel_error(g.u_radius(), w.u_radius()).max(rel_error(g.u_angle(), w.u_angle())),
            );
            beyond |= tally.float("p_disk", rel_error(g.p_disk(), w.p_disk()));
            beyond |= tally.float(
                "bary",
                scaled_error(&g.bary().to_array(), &w.bary().to_array(), 1.0),
            );
            let scale = w.x3().abs().max_element().max(1.0);
            beyond |= tally.float(
                "x3",
                scaled_error(&g.x3().to_array(), &w.x3().to_array(), scale),
            );
        }
        tally.beyond_bounds += usize::from(beyond);
    }
    tally
}

/// Bounds of the pass comparison (module doc for the causes). The confidence counts BSSRDF
/// samples and the stored u_radius, u_angle are copied stream numbers: exact. `p_disk` as in
/// [`BOUNDS`]; `W = w_sum / p̂` is a sum of ratios of such densities divided by one more (seen:
/// 2.7e-5): 1e-3; barycentrics move with the chord's hit, divided by the triangle's size (seen:
/// 8e-6): 1e-4; x3 on an area light is sampled at the displaced x2 (seen: 6e-11 of the scene
/// scale): 1e-4.
const PASS_BOUNDS: [(&str, f64); 6] = [
    ("confidence", 0.0),
    ("u_radius, u_angle", 0.0),
    ("p_disk", 5e-4),
    ("ucw", 1e-3),
    ("bary", 1e-4),
    ("x3", 1e-4),
];

/// At most this fraction of pixels may differ in an integer field (has_sample, object, prim,
/// technique, index, light, probes, hits, hybrid choice): a pixel streams M·(hits) candidates
/// and each RIS selection `u·w_sum < w` compares values that differ by ~1e-5 relative, so a
/// flip needs `u` within that of the threshold; plus the hit flips of the function-level test.
const PASS_MISMATCH_FRACTION: f64 = 5e-3;

/// Pass-level parity of `pass_candidates` on `bumpy` (M = 2, shared light), `half-shadow` (M = 1,
/// a light sample per hit) and `materials` (M = 3, pass index 2), 32×32, frame 0: the CPU
/// G-buffer is uploaded, the pass is dispatched and every pixel's reservoir and diag are compared
/// with `candidates::generate` + `shadow_test` + the hybrid choice. Negative controls: the GPU
/// run with another seed and with another pass index must exceed the allowed mismatch fraction.
#[test]
fn candidates_pass_matches_the_cpu() {
    let Some((mut context, kernel)) = kernel_or_skip("candidates pass parity", CANDIDATES) else {
        return;
    };
    let seed = 0x5EED_0000_0000_0003u64;
    for case in &PASS_CASES {
        let scene = scene(case.scene, 32);
        let gbuffer = GBuffer::render(&scene, 0);
        let gpu_scene = GpuScene::upload(&context, &scene).unwrap();
        let pixels: Vec<GpuPixel> = gbuffer
            .pixels
            .iter()
            .map(|g| GpuPixel::from_cpu(g.as_ref()))
            .collect();
        let pixel_buffer = Buffer::from_slice(&context, &pixels).unwrap();
        let n = pixels.len();
        let mut run = |seed: u64, pass: u32| {
            let frame = FrameParams::new(&scene, 0, None, seed)
                .buffer(&context)
                .unwrap();
            let reservoirs = Buffer::zeroed(&context, n * PixelReservoir::BYTES).unwrap();
            let diag = Buffer::zeroed(&context, n * 16).unwrap();
            let mut buffers: Vec<&Buffer> = gpu_scene.buffers().to_vec();
            buffers.extend([&frame, &pixel_buffer, &reservoirs, &diag]);
            let params = PassParams {
                pass,
                bssrdf_samples: case.bssrdf_samples,
                shared_light: case.shared_light as u32,
                collect_diagnostics: 1,
                ..PassParams::default()
            };
            let timing = context
                .dispatch(
                    &kernel,
                    &buffers,
                    bytemuck::bytes_of(&params),
                    [groups_for(n as u32, CANDIDATES.local_size), 1, 1],
                )
                .unwrap();
            (
                reservoirs.read::<PixelReservoir>().unwrap(),
                diag.read::<[u32; 4]>().unwrap(),
                timing.gpu_seconds,
            )
        };
        let cpu = cpu_pass(&scene, &gbuffer, case, seed);
        let (reservoirs, diag, seconds) = run(seed, case.pass);
        let tally = compare_pass(&cpu, &reservoirs, &diag);
        let sampled = cpu.iter().filter(|(r, _)| r.has_sample != 0).count();
        eprintln!(
            "candidates parity, {} (M = {}, shared {}): {} pixels ({sampled} with a sample), {} \
             mismatched ({:.2e}); worst {:?}; {}",
            case.scene,
            case.bssrdf_samples,
            case.shared_light,
            tally.compared,
            tally.mismatched,
            tally.mismatch_fraction(),
            tally.worst,
            seconds.map_or("no timestamps".into(), |s| format!("{:.2} ms GPU", s * 1e3))
        );
        assert!(
            sampled > n / 8,
            "{}: too few sampled pixels ({sampled})",
            case.scene
        );
        assert!(
            tally.mismatch_fraction() <= PASS_MISMATCH_FRACTION,
            "{}: {} of {} pixels differ in an integer field (allowed {PASS_MISMATCH_FRACTION})",
            case.scene,
            tally.mismatched,
            tally.compared
        );
        assert!(
            diag.iter().all(|d| d[3] == 0),
            "{}: a pixel reported an error code",
            case.scene
        );
        assert_eq!(
            tally.beyond_bounds, 0,
            "{}: float errors beyond PASS_BOUNDS; worst {:?}",
            case.scene, tally.worst
        );
        for (label, wrong_seed, wrong_pass) in [
            ("seed + 1", seed + 1, case.pass),
            ("pass + 1", seed, case.pass + 1),
        ] {
            let (reservoirs, diag, _) = run(wrong_seed, wrong_pass);
            let control = compare_pass(&cpu, &reservoirs, &diag);
            eprintln!(
                "candidates parity, {}: control ({label}) rejected {:.3}",
                case.scene,
                control.rejected_fraction()
            );
            assert!(
                control.rejected_fraction() > PASS_MISMATCH_FRACTION,
                "{}: negative control ({label}) undetected",
                case.scene
            );
        }
    }
}

/// The candidates pass keeps `KEPT_HITS` (16) hits per probe (its `BVH_MAX_HITS`; bvh.glsl's
/// default is `BVH_DEFAULT_MAX_HITS`, 8); a probe with more would lose candidates the CPU
/// streams. Over 64 probes of every translucent pixel of every built-in scene (48×48, seed 1)
/// the largest count stays within it. Control: the measurement must see multi-hit probes at all
/// (largest > 2).
#[test]
fn probe_hit_counts_stay_within_the_pass_capacity() {
    const PASS_MAX_HITS: usize = engine::contract::KEPT_HITS;
    let mut hits = Vec::new();
    let mut largest = 0;
    for (name, _) in Scene::BUILTIN {
        let scene = scene(name, 48);
        let gbuffer = GBuffer::render(&scene, 0);
        for (pixel, g) in gbuffer.pixels.iter().enumerate() {
            let Some(domain) = g
                .as_ref()
                .and_then(|g| SssDomain::new(&scene, g, pixel as u32, 0, 0, 1))
            else {
                continue;
            };
            let mut rng = StreamKey::new(pixel as u32, 0, 0, purpose::PROBE).stream(1);
            for _ in 0..64 {
                let probe = Probe::sample(
                    domain.selection(),
                    rng.next_f32(),
                    rng.next_f32(),
                    rng.next_f32(),
                );
                probe.trace(&scene.geometry, domain.x1(), &mut hits);
                largest = largest.max(hits.len());
            }
        }
    }
    eprintln!("largest probe hit count over the built-in scenes: {largest}");
    assert!(largest > 2, "the measurement saw no multi-hit probe");
    assert!(
        largest <= PASS_MAX_HITS,
        "a probe has {largest} hits > {PASS_MAX_HITS}"
    );
}
