//! Parity of the GLSL twins with their Rust modules, run through the Vulkan backend
//! (`engine::vulkan`) on whatever device it chooses (Mesa lavapipe in CI).
//!
//! Without Vulkan (no loader, no driver, no device, or a build without `glslc`) each test prints
//! why it is skipped and passes, unless `RESHIFT_REQUIRE_VULKAN=1`, which makes it fail.

use engine::reciprocal::Pairing;
use engine::vulkan::testing::kernel_or_skip;
use engine::vulkan::{
    BVH_MAX_HITS, Buffer, BurleyInput, BurleyOutput, BvhRayInput, BvhRayOutput, Context, Dispatch,
    GpuBvh, GpuStreamKey, Kernel, PairingQuery, RngParams, Shader, VulkanError, groups_for,
};
use geometry::{Geometry, Hit, Ray, shapes};
use glam::{Affine3A, IVec2, Vec3, Vec3A};
use restir::rng::StreamKey;
use sss::profile::Burley;

fn gpu_time(seconds: Option<f64>) -> String {
    seconds.map_or("no timestamps".into(), |s| format!("{:.3} ms GPU", s * 1e3))
}

/// Keys of the RNG test: the golden key of `restir::rng`, extreme field values, and 4000 keys
/// with fields drawn from a CPU stream (so the test covers all bits of every field).
fn rng_keys() -> Vec<StreamKey> {
    let mut keys = vec![
        StreamKey::new(1, 2, 3, 4),
        StreamKey::new(0, 0, 0, 0),
        StreamKey::new(u32::MAX, u32::MAX, u32::MAX, u32::MAX),
        StreamKey::new(u32::MAX, 0, u32::MAX, 0),
    ];
    let mut fields = StreamKey::new(0, 0, 0x7A11, 0x0006).stream(6);
    keys.extend((0..4000).map(|_| {
        let [pixel, frame, pass, purpose] = [0; 4].map(|_| fields.next_u32());
        StreamKey::new(pixel, frame, pass, purpose)
    }));
    keys
}

/// The first four values of key (1, 2, 3, 4) under seed 5 from PCG32 written out, as in
/// `restir::rng`'s golden test: inc = 2·stream + 1; state ← state + inc; step; then output.
fn golden_pcg32() -> [u32; 4] {
    let (state, stream) = StreamKey::new(1, 2, 3, 4).seed_pair(5);
    let inc = (stream << 1) | 1;
    let mul = 6_364_136_223_846_793_005u64;
    let mut st = state.wrapping_add(inc).wrapping_mul(mul).wrapping_add(inc);
    [0; 4].map(|_| {
        let old = st;
        st = st.wrapping_mul(mul).wrapping_add(inc);
        ((((old >> 18) ^ old) >> 27) as u32).rotate_right((old >> 59) as u32)
    })
}

/// Every `next_u32` and `next_f32` of 4004 keys × 16 draws under two run seeds (one with its
/// high 32 bits set) is bit-identical on the GPU and the CPU. Negative controls: the same
/// comparison flags the CPU streams of the neighbouring purpose, and a `u · 2⁻³²` unit float.
#[test]
fn rng_streams_are_bit_identical() {
    let Some((mut context, kernel)) = kernel_or_skip("rng parity", Shader::PARITY_RNG) else {
        return;
    };
    const DRAWS: usize = 16;
    assert!(
        matches!(
            context.dispatch(&kernel, &[], &[], [1, 1, 1]),
            Err(VulkanError::Binding(_))
        ),
        "a dispatch without the kernel's buffers must be refused"
    );
    let keys = rng_keys();
    for seed in [5u64, 0xDEAD_BEEF_0123_4567] {
        let gpu_keys: Vec<GpuStreamKey> = keys.iter().map(|&k| k.into()).collect();
        let key_buffer = Buffer::from_slice(&context, &gpu_keys).unwrap();
        let bits = Buffer::zeroed(&context, keys.len() * DRAWS * 4).unwrap();
        let units = Buffer::zeroed(&context, keys.len() * DRAWS * 4).unwrap();
        let params = RngParams {
            count: keys.len() as u32,
            draws: DRAWS as u32,
            seed_lo: seed as u32,
            seed_hi: (seed >> 32) as u32,
        };
        let groups = groups_for(params.count, Shader::PARITY_RNG.local_size);
        let timing = context
            .dispatch(
                &kernel,
                &[&key_buffer, &bits, &units],
                bytemuck::bytes_of(&params),
                [groups, 1, 1],
            )
            .unwrap();
        let (gpu_bits, gpu_units) = (bits.read::<u32>().unwrap(), units.read::<f32>().unwrap());
        if seed == 5 {
            assert_eq!(
                &gpu_bits[..4],
                &golden_pcg32(),
                "golden key (1, 2, 3, 4), seed 5"
            );
        }
        let (mut neighbour_equal, mut coarse_equal) = (0usize, 0usize);
        for (i, key) in keys.iter().enumerate() {
            let mut cpu = key.stream(seed);
            let want: Vec<u32> = (0..DRAWS).map(|_| cpu.next_u32()).collect();
            let mut cpu = key.stream(seed);
            let want_units: Vec<u32> = (0..DRAWS).map(|_| cpu.next_f32().to_bits()).collect();
            let got = &gpu_bits[i * DRAWS..(i + 1) * DRAWS];
            let got_units: Vec<u32> = gpu_units[i * DRAWS..(i + 1) * DRAWS]
                .iter()
                .map(|f| f.to_bits())
                .collect();
            assert_eq!(got, &want[..], "next_u32, seed {seed}, {key:?}");
            assert_eq!(got_units, want_units, "next_f32, seed {seed}, {key:?}");
            let neighbour = StreamKey {
                purpose: key.purpose.wrapping_add(1),
                ..*key
            };
            let mut other = neighbour.stream(seed);
            neighbour_equal += usize::from((0..DRAWS).all(|k| other.next_u32() == got[k]));
            coarse_equal += usize::from(
                want.iter()
                    .zip(&got_units)
                    .all(|(&u, &g)| (u as f32 * 2f32.powi(-32)).to_bits() == g),
            );
        }
        assert_eq!(
            (neighbour_equal, coarse_equal),
            (0, 0),
            "negative controls: streams of the neighbouring purpose / u·2⁻³² floats matched"
        );
        eprintln!(
            "rng parity: seed {seed:#x}, {} keys × {DRAWS} draws × 2 streams identical ({})",
            keys.len(),
            gpu_time(timing.gpu_seconds)
        );
    }
}

/// `2⁻²³`: the largest relative spacing of f32 (one ulp at the bottom of a binade).
const ULP: f64 = 1.0 / 8_388_608.0;

/// The Vulkan bound on `exp(x)`: `3 + 2|x|` ulp (Vulkan spec, "Precision and Operation of
/// SPIR-V Instructions"; conformant drivers such as lavapipe pass the CTS checks of it).
fn exp_bound_ulp(x: f64) -> f64 {
    3.0 + 2.0 * x.abs()
}

/// Relative bounds of the GPU twin against the CPU, per function, from the Vulkan precision
/// bounds (exp: `3 + 2|x|` ulp; log outside [½, 2]: 3 ulp; +, ×, ÷, sqrt: correctly rounded)
/// and ≤ 1 ulp for each libm call on the CPU:
/// - `pdf_radius`: two exps (≤ E(r/d)) summed without cancellation, one add, one divide, and
///   the CPU's exp → `E + 4` ulp; `pdf_disk` adds a product and a divide → `E + 6`.
/// - `cdf`: expm1 is a Horner series for |x| ≤ ½ (≤ 4 ulp) and exp − 1 beyond, which multiplies
///   exp's bound by at most e^x/|e^x − 1| ≤ 1.55; the two terms have one sign → `1.55 E + 8`.
/// - `sample_radius`: the series asinh/sinh/log1p give the Cardano root x to ≤ 10 ulp, and
///   `r = −3d ln x` with x < 0.6 amplifies it by ≤ 1/|ln 0.6| < 2, plus log (3 ulp), two products
///   and the CPU's three libm calls (amplified alike, 6 ulp) → 32 ulp; the Newton branch
///   (u ≤ ½) converges to the same f32 root from either start and stays below this.
///
/// Non-finite r must give exactly the CPU's value (0 or 1): bound 0.
fn bounds(input: &BurleyInput) -> [f64; 3] {
    if !input.r.is_finite() {
        return [0.0; 3];
    }
    let e = exp_bound_ulp((input.r / input.d) as f64);
    [e + 4.0, e + 6.0, 1.55 * e + 8.0].map(|ulps| ulps * ULP)
}
const SAMPLE_RADIUS_BOUND: f64 = 32.0 * ULP;

/// Relative error of `got` against `want`; exact agreement (incl. 0, ∞) is 0, a mismatch of
/// classes (one 0 or non-finite, the other not) is ∞.
fn rel_error(got: f32, want: f32) -> f64 {
    if got == want || (got.is_nan() && want.is_nan()) {
        0.0
    } else if want == 0.0 || !want.is_finite() || !got.is_finite() {
        f64::INFINITY
    } else {
        ((got as f64 - want as f64) / want as f64).abs()
    }
}

/// Burley profile inputs: r from 10⁻⁶ d to 33 d (geometric), u over (0, 1) and its edges
/// (1e-7 … 1 − 2⁻²⁴), for d ∈ {0.05, 1, 3}, and the special inputs r, u ∈ {0, −1, NaN, ±∞, 1}.
fn burley_inputs() -> Vec<BurleyInput> {
    let mut us: Vec<f32> = (1..2000).map(|i| i as f32 / 2000.0).collect();
    us.extend([
        1e-7,
        1e-6,
        1e-5,
        1e-4,
        1e-3,
        0.499_999_97,
        0.5,
        0.500_000_06,
    ]);
    us.extend([0.999, 0.999_99, 1.0 - 2f32.powi(-24)]);
    let mut inputs = Vec::new();
    for d in [0.05f32, 1.0, 3.0] {
        for (i, &u) in us.iter().enumerate() {
            let r = d * 1e-6 * 1.0085f32.powi(i as i32);
            inputs.push(BurleyInput { d, r, u });
        }
        for (r, u) in [
            (0.0, 0.0),
            (-1.0, -0.5),
            (f32::NAN, f32::NAN),
            (f32::INFINITY, 1.0),
            (f32::NEG_INFINITY, 2.0),
        ] {
            inputs.push(BurleyInput { d, r, u });
        }
    }
    inputs
}

/// The GPU Burley twin (pdf_radius, pdf_disk, cdf, sample_radius) agrees with
/// `sss::profile::Burley` within the bounds derived in [`bounds`]; special inputs agree exactly.
/// Negative controls: the same cdf bound rejects the textbook `1 − ¼e^{−r/d} − ¾e^{−r/3d}`
/// (cancellation at small r), and the sample_radius bound rejects a profile with
/// d′ = d(1 + 2⁻¹⁷) (r scales with d, so every radius is off by 2⁻¹⁷ relative).
#[test]
fn burley_twin_within_precision_bounds() {
    let Some((mut context, kernel)) = kernel_or_skip("burley parity", Shader::PARITY_BURLEY) else {
        return;
    };
    let inputs = burley_inputs();
    let input_buffer = Buffer::from_slice(&context, &inputs).unwrap();
    let output_buffer = Buffer::zeroed(&context, inputs.len() * size_of::<BurleyOutput>()).unwrap();
    let count = inputs.len() as u32;
    let timing = context
        .dispatch(
            &kernel,
            &[&input_buffer, &output_buffer],
            bytemuck::bytes_of(&count),
            [groups_for(count, Shader::PARITY_BURLEY.local_size), 1, 1],
        )
        .unwrap();
    let outputs = output_buffer.read::<BurleyOutput>().unwrap();
    let names = ["pdf_radius", "pdf_disk", "cdf", "sample_radius"];
    let mut worst = [0.0f64; 4];
    let (mut naive_rejected, mut scaled_rejected, mut compared) = (0, 0, 0);
    for (input, gpu) in inputs.iter().zip(&outputs) {
        let cpu = Burley::new(input.d);
        let want = [
            cpu.pdf_radius(input.r),
            cpu.pdf_disk(input.r),
            cpu.cdf(input.r),
            cpu.sample_radius(input.u),
        ];
        let got = [gpu.pdf_radius, gpu.pdf_disk, gpu.cdf, gpu.sample_radius];
        let [pdf_bound, disk_bound, cdf_bound] = bounds(input);
        let limits = [pdf_bound, disk_bound, cdf_bound, SAMPLE_RADIUS_BOUND];
        for k in 0..4 {
            let error = rel_error(got[k], want[k]);
            assert!(
                error <= limits[k],
                "{}: {input:?}: GPU {} vs CPU {}, relative error {error:.3e} > bound {:.3e}",
                names[k],
                got[k],
                want[k],
                limits[k]
            );
            if error.is_finite() {
                worst[k] = worst[k].max(error / ULP);
            }
        }
        naive_rejected += usize::from(rel_error(gpu.cdf_naive, want[2]) > cdf_bound);
        let scaled = Burley::new(input.d * (1.0 + 2f32.powi(-17))).sample_radius(input.u);
        let finite = scaled.is_finite() && scaled > 0.0;
        scaled_rejected +=
            usize::from(finite && rel_error(gpu.sample_radius, scaled) > SAMPLE_RADIUS_BOUND);
        compared += usize::from(finite);
    }
    eprintln!(
        "burley parity: {} inputs ({}); worst relative error in units of 2⁻²³: {}",
        inputs.len(),
        gpu_time(timing.gpu_seconds),
        names
            .iter()
            .zip(worst)
            .map(|(n, w)| format!("{n} {w:.2}"))
            .collect::<Vec<_>>()
            .join(", ")
    );
    assert!(
        naive_rejected > inputs.len() / 10,
        "negative control: the naive cdf was rejected on only {naive_rejected} inputs"
    );
    assert_eq!(
        scaled_rejected, compared,
        "negative control: d′ = d(1 + 2⁻¹⁷) passed the sample_radius bound"
    );
}

/// Four objects with curved, flat and closed surfaces, some overlapping in depth.
fn bvh_scene() -> Geometry {
    let at = |x: f32, y: f32, z: f32| Affine3A::from_translation(Vec3::new(x, y, z));
    Geometry::new(&[
        shapes::icosphere(1.0, 3).transformed(&at(-1.2, 0.0, 0.0)),
        shapes::torus(0.9, 0.3, 48, 24).transformed(&at(1.1, 0.2, 0.3)),
        shapes::quad(6.0, 6.0).transformed(&at(0.0, -1.1, 0.0)),
        shapes::cuboid(Vec3::new(0.4, 0.7, 0.5)).transformed(&at(0.2, 0.1, -1.3)),
    ])
}

/// Rays from a box around the scene aimed at points inside it, every sixth with axis-aligned
/// components of either zero sign, some with t_min > 0 or a finite t_max.
fn bvh_rays(n: usize) -> Vec<Ray> {
    let mut rng = StreamKey::new(0, 0, 0x7A11, 0x00B7).stream(6);
    let mut point = |scale: f32| {
        Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * (2.0 * scale) - scale
    };
    (0..n)
        .map(|i| {
            let origin = point(4.0);
            let mut dir = point(1.5) - origin;
            if i % 6 == 0 {
                let axis = (i / 6) % 3;
                for k in 0..3 {
                    if k != axis {
                        dir[k] = if (i / 18) % 2 == 0 { 0.0 } else { -0.0 };
                    }
                }
            }
            let t_min = if i % 5 == 0 { 0.3 } else { 0.0 };
            let t_max = if i % 7 == 0 { 1.0 } else { f32::INFINITY };
            // A struct literal keeps −0.0 components (Ray::new would canonicalise them).
            Ray {
                origin,
                dir,
                t_min,
                t_max,
            }
        })
        .collect()
}

/// Relative bound on hit distances: `t = (u a_z + v b_z + w c_z) / det` mirrors the CPU's
/// arithmetic operation for operation, and +, −, × are correctly rounded on every Vulkan device;
/// division may be off by 2.5 ulp (Vulkan spec), once in each shear factor and once in `t`, and
/// the shear factors enter `t` with weight ≤ 1 each → ≤ 10 ulp. On lavapipe division is correctly
/// rounded, so distances come out bit-identical (the test prints the worst case).
const T_BOUND: f64 = 10.0 * ULP;

/// The GPU traversal of the uploaded CWBVH finds the CPU's closest hit (same triangle, t within
/// [`T_BOUND`], barycentrics within the same bound of their scale), the same occlusion, and the
/// same (t, prim)-sorted hits on one object, for 3000 rays. It must exercise something: many
/// hits and multi-hit chords. Negative control: CPU rays whose origins move by 10⁻⁴ along the
/// ray give distances that the same bound rejects.
/// Dispatches the BVH parity kernel over the first `count` rays of `rays` against `bvh`.
fn trace_rays(
    context: &mut Context,
    kernel: &Kernel,
    bvh: &GpuBvh,
    rays: &Buffer,
    results: &Buffer,
    count: u32,
) -> Dispatch {
    let [nodes, triangles, leaf_prims, leaf_objects] = bvh.buffers();
    let push = [count, bvh.node_count()];
    context
        .dispatch(
            kernel,
            &[rays, results, nodes, triangles, leaf_prims, leaf_objects],
            bytemuck::cast_slice(&push),
            [groups_for(count, Shader::PARITY_BVH.local_size), 1, 1],
        )
        .unwrap()
}

#[test]
fn bvh_queries_match_cpu() {
    let Some((mut context, kernel)) = kernel_or_skip("bvh parity", Shader::PARITY_BVH) else {
        return;
    };
    let geometry = bvh_scene();
    let rays = bvh_rays(3000);
    let objects = geometry.object_count();
    let inputs: Vec<BvhRayInput> = rays
        .iter()
        .enumerate()
        .map(|(i, r)| BvhRayInput {
            origin: r.origin.to_array(),
            dir: r.dir.to_array(),
            t_min: r.t_min,
            t_max: r.t_max,
            object: i as u32 % objects,
        })
        .collect();
    let bvh = GpuBvh::upload(&context, &geometry).unwrap();
    let ray_buffer = Buffer::from_slice(&context, &inputs).unwrap();
    let results = Buffer::zeroed(&context, inputs.len() * size_of::<BvhRayOutput>()).unwrap();
    let timing = trace_rays(
        &mut context,
        &kernel,
        &bvh,
        &ray_buffer,
        &results,
        inputs.len() as u32,
    );
    let outputs = results.read::<BvhRayOutput>().unwrap();
    let (mut closest_hits, mut multi, mut shifted_rejected, mut worst_t) = (0, 0, 0, 0.0f64);
    let mut all_hits: Vec<Hit> = Vec::new();
    for ((ray, input), gpu) in rays.iter().zip(&inputs).zip(&outputs) {
        let cpu = geometry.closest_hit(ray);
        assert_eq!(
            (gpu.closest_prim != u32::MAX).then_some(gpu.closest_prim),
            cpu.map(|h| h.prim),
            "closest triangle, {ray:?}"
        );
        if let Some(hit) = cpu {
            let error = rel_error(gpu.closest_t, hit.t);
            assert!(
                error <= T_BOUND,
                "closest t {} vs {}, {ray:?}",
                gpu.closest_t,
                hit.t
            );
            for k in 0..2 {
                let scale = hit.bary[k].abs().max(1.0) as f64;
                let diff = (gpu.closest_bary[k] - hit.bary[k]).abs() as f64;
                assert!(
                    diff <= T_BOUND * scale,
                    "barycentric {k}: {gpu:?} vs {hit:?}"
                );
            }
            worst_t = worst_t.max(error / ULP);
            closest_hits += 1;
            let shifted = Ray {
                origin: ray.origin + 1e-4 * ray.dir.normalize(),
                ..*ray
            };
            if let Some(moved) = geometry.closest_hit(&shifted) {
                shifted_rejected += usize::from(rel_error(gpu.closest_t, moved.t) > T_BOUND);
            }
        }
        assert_eq!(
            gpu.occluded == 1,
            geometry.occluded(ray),
            "occluded, {ray:?}"
        );
        geometry.all_hits_on_object(ray, input.object, &mut all_hits);
        assert_eq!(
            gpu.hit_count as usize,
            all_hits.len(),
            "hits on {}, {ray:?}",
            input.object
        );
        for (k, hit) in all_hits.iter().take(BVH_MAX_HITS).enumerate() {
            assert_eq!(
                gpu.hit_prims[k], hit.prim,
                "hit {k} on {}, {ray:?}",
                input.object
            );
            let error = rel_error(gpu.hit_ts[k], hit.t);
            assert!(error <= T_BOUND, "hit {k} t {} vs {}", gpu.hit_ts[k], hit.t);
            worst_t = worst_t.max(error / ULP);
        }
        multi += usize::from(all_hits.len() >= 2);
    }
    eprintln!(
        "bvh parity: {} rays, {} nodes, {closest_hits} closest hits, {multi} multi-hit chords \
         ({}); worst t error {worst_t:.2} × 2⁻²³ relative",
        rays.len(),
        bvh.node_count(),
        gpu_time(timing.gpu_seconds)
    );
    assert!(
        closest_hits > rays.len() / 3 && multi > rays.len() / 10,
        "the rays must exercise the BVH: {closest_hits} hits, {multi} multi-hit chords"
    );
    // An empty scene uploads (zero nodes) and is never hit.
    let empty = GpuBvh::upload(&context, &Geometry::new::<geometry::TriangleMesh>(&[])).unwrap();
    trace_rays(&mut context, &kernel, &empty, &ray_buffer, &results, 1);
    let first = results.read::<BvhRayOutput>().unwrap()[0];
    assert_eq!(
        (first.closest_prim, first.occluded, first.hit_count),
        (u32::MAX, 0, 0),
        "empty scene"
    );
    assert!(
        shifted_rejected > closest_hits * 9 / 10,
        "negative control: origins moved by 1e-4 rejected on only {shifted_rejected} of \
         {closest_hits} hits"
    );
}

/// Pixels whose partners the pairing test compares: every pixel of `[−12, 12]²` (negative
/// coordinates, where GLSL's truncating `/` is not `div_euclid`) and a few far ones.
fn pairing_pixels() -> Vec<IVec2> {
    let mut pixels: Vec<IVec2> = (-12..=12)
        .flat_map(|y| (-12..=12).map(move |x| IVec2::new(x, y)))
        .collect();
    pixels.extend([
        IVec2::new(1919, 1079),
        IVec2::new(-1000, 37),
        IVec2::new(37, -1001),
    ]);
    pixels
}

/// The CPU partners of `pixels` in the pairing of `query` (the pixel itself where the slot is
/// empty), as `parity_pairing.glsl` writes them.
fn cpu_partners(query: &PairingQuery, seed: u64, pixels: &[IVec2]) -> Vec<IVec2> {
    let pairing = Pairing::draw(query.radius, query.slot, query.frame, query.pass, seed);
    pixels
        .iter()
        .map(|&p| pairing.map_or(p, |pairing| pairing.partner(p)))
        .collect()
}

/// The pairings of a reciprocal spatial pass (`engine::reciprocal::Pairing`; GLSL twin
/// `engine/glsl/include/reciprocal.glsl`): for 1200 queries (radius from 0.3 px, where most
/// slots are empty, to 60 px; 8 slots; 5 frames; 3 passes) under two run seeds, the partners of
/// 628 pixels are identical on the GPU and the CPU. Negative controls: the partners with the
/// stripes' signs swapped match no paired query, and the pairings of the neighbouring frame
/// match fewer than half the paired queries of radius ≥ 4 px (two independent offsets uniform in
/// such a disk round to the same pixel with probability below 1/(π·4²) ≈ 2%).
#[test]
fn pairings_are_identical() {
    let Some((mut context, kernel)) = kernel_or_skip("pairing parity", Shader::PARITY_PAIRING)
    else {
        return;
    };
    let pixels = pairing_pixels();
    let mut queries = Vec::new();
    for radius in [0.3f32, 1.0, 2.5, 4.0, 7.3, 16.0, 25.5, 33.3, 47.9, 60.0] {
        for slot in 0..8 {
            for frame in 0..5 {
                for pass in 1..4 {
                    queries.push(PairingQuery {
                        radius,
                        slot,
                        frame,
                        pass,
                    });
                }
            }
        }
    }
    let gpu_pixels: Vec<[i32; 2]> = pixels.iter().map(|p| p.to_array()).collect();
    let query_buffer = Buffer::from_slice(&context, &queries).unwrap();
    let pixel_buffer = Buffer::from_slice(&context, &gpu_pixels).unwrap();
    let partners = Buffer::zeroed(&context, queries.len() * pixels.len() * 8).unwrap();
    for seed in [5u64, 0xDEAD_BEEF_0123_4567] {
        let params = RngParams {
            count: queries.len() as u32,
            draws: pixels.len() as u32,
            seed_lo: seed as u32,
            seed_hi: (seed >> 32) as u32,
        };
        let timing = context
            .dispatch(
                &kernel,
                &[&query_buffer, &pixel_buffer, &partners],
                bytemuck::bytes_of(&params),
                [
                    groups_for(params.count, Shader::PARITY_PAIRING.local_size),
                    1,
                    1,
                ],
            )
            .unwrap();
        let gpu: Vec<IVec2> = partners
            .read::<[i32; 2]>()
            .unwrap()
            .into_iter()
            .map(IVec2::from_array)
            .collect();
        let (mut paired, mut swapped_equal, mut wide, mut neighbour_equal) = (0, 0, 0, 0);
        for (query, got) in queries.iter().zip(gpu.chunks(pixels.len())) {
            let want = cpu_partners(query, seed, &pixels);
            assert_eq!(got, &want[..], "seed {seed:#x}, {query:?}");
            if want == pixels {
                continue;
            }
            paired += 1;
            let swapped: Vec<IVec2> = pixels.iter().zip(got).map(|(&p, &q)| 2 * p - q).collect();
            swapped_equal += usize::from(swapped == want);
            if query.radius >= 4.0 {
                wide += 1;
                let neighbour = PairingQuery {
                    frame: query.frame + 5,
                    ..*query
                };
                neighbour_equal += usize::from(cpu_partners(&neighbour, seed, &pixels) == got);
            }
        }
        assert_eq!(
            swapped_equal, 0,
            "negative control: partners with swapped signs matched"
        );
        assert!(
            2 * neighbour_equal < wide,
            "negative control: {neighbour_equal} of {wide} pairings of another frame matched"
        );
        eprintln!(
            "pairing parity: seed {seed:#x}, {} queries ({paired} paired) × {} pixels identical; \
             another frame's pairings matched {neighbour_equal} of {wide} ({})",
            queries.len(),
            pixels.len(),
            gpu_time(timing.gpu_seconds)
        );
    }
}
