//! Tests of BSSRDF IS on analytic meshes: the probe, inversion round trips, the posterior over
//! techniques, and the density of sampled entry points.

use geometry::{Geometry, Hit, TriangleMesh, shapes};
use glam::{DVec3, Vec2, Vec3};
use restir::rng::{Stream, StreamKey};
use restir::stats::{Welford, chi_square_gof, normal_quantile};

use super::*;
use crate::material::{BoundaryKind, Translucent};
use crate::profile::ScaleFit;

/// `purpose` of the streams of these tests.
const PURPOSE: u32 = 0xB55D_0001;

/// d ≈ (0.0152, 0.0078, 0.0041), r_max ≈ (0.30, 0.16, 0.08): curvature matters on unit objects.
fn material() -> Translucent {
    Translucent {
        albedo: Vec3::new(0.8, 0.5, 0.3),
        mfp: Vec3::new(0.016, 0.012, 0.010),
        scale: 1.0,
        ior: 1.3,
        g: 0.0,
        fit: ScaleFit::Searchlight,
        boundary: BoundaryKind::Diffuse,
    }
}

/// x1 at `(prim, bary)`, seen from outside (view along the geometric normal).
fn exit_at(geometry: &Geometry, prim: u32, bary: Vec2, material: &Translucent) -> ExitPoint {
    let n = geometry.geometric_normal(prim);
    let shading = geometry.shading_normal(prim, bary);
    ExitPoint::new(
        geometry.position(prim, bary),
        n,
        shading,
        n,
        geometry.object_of(prim),
        material,
    )
}

/// A uniformly random surface point by triangle index and barycentrics.
fn random_exit(geometry: &Geometry, rng: &mut Stream, material: &Translucent) -> ExitPoint {
    let prim = ((rng.next_f32() * geometry.triangle_count() as f32) as u32)
        .min(geometry.triangle_count() - 1);
    let (a, b) = (rng.next_f32().sqrt(), rng.next_f32());
    exit_at(geometry, prim, Vec2::new(a * (1.0 - b), a * b), material)
}

fn disk_point(x1: &ExitPoint, probe: &Probe) -> Vec2 {
    let r = x1.profiles[probe.technique.channel].sample_radius(probe.u_radius);
    let phi = std::f32::consts::TAU * probe.u_angle;
    r * Vec2::new(phi.cos(), phi.sin())
}

#[test]
fn chord_passes_through_the_disk_point_and_stays_in_the_ball() {
    let m = material();
    let geometry = Geometry::new(&[shapes::uv_sphere(1.0, 64, 32)]);
    let mut rng = StreamKey::new(0, 0, 0, PURPOSE).stream(1);
    for _ in 0..1000 {
        let x1 = random_exit(&geometry, &mut rng, &m);
        let probe = Probe::sample(
            &TechniqueSelection::default(),
            rng.next_f32(),
            rng.next_f32(),
            rng.next_f32(),
        );
        let Some(ray) = probe.ray(&x1) else { continue };
        let r_max = x1.r_max[probe.technique.channel];
        let mid = Vec3::from(ray.at(0.5 * ray.t_max));
        let disk = x1.disk_coordinates(probe.technique.axis, mid);
        assert!(
            (disk - disk_point(&x1, &probe)).length() < 1e-6,
            "chord misses its disk point"
        );
        for t in [0.0, ray.t_max] {
            let end = (Vec3::from(ray.at(t)) - x1.position).length();
            assert!(
                (end - r_max).abs() < 1e-5 * r_max.max(1.0),
                "chord end at {end}, r_max {r_max}"
            );
        }
    }
}

/// Round trip on ≥ 10⁴ probes over three curved meshes: for every hit x2 of a sampled probe,
/// (1) inverting with the sampled technique gives back `u_radius`, `u_angle` (compared as disk
/// points: ≤ 1e-5 scene units on unit-size objects, `|Δu_radius| ≤ 1e-5 · max p_radius`) and the
/// intersection index by re-tracing; (2) the randomized inversion, whenever it draws the sampled
/// technique, returns the same numbers, index and `p_disk`.
#[test]
fn sample_then_invert_round_trips_on_curved_meshes() {
    let m = material();
    let selection = TechniqueSelection::default();
    let meshes: [(&str, TriangleMesh); 3] = [
        ("sphere", shapes::uv_sphere(1.0, 96, 48)),
        ("torus", shapes::torus(1.0, 0.35, 128, 48)),
        ("bumpy", shapes::bumpy_sphere(1.0, 0.06, 3.0, 7, 5)),
    ];
    let (mut hits_total, mut index_failures, mut same_technique) = (0usize, 0usize, 0usize);
    let mut probes_total = 0;
    for (shape, mesh) in meshes.iter().enumerate().map(|(i, (_, m))| (i as u32, m)) {
        let geometry = Geometry::new(std::slice::from_ref(mesh));
        let mut hits: Vec<Hit> = Vec::new();
        let mut scratch: Vec<Hit> = Vec::new();
        for i in 0..5000u32 {
            probes_total += 1;
            let mut rng = StreamKey::new(i, shape, 0, PURPOSE).stream(2);
            let x1 = random_exit(&geometry, &mut rng, &m);
            let probe = Probe::sample(&selection, rng.next_f32(), rng.next_f32(), rng.next_f32());
            probe.trace(&geometry, &x1, &mut hits);
            let channel = probe.technique.channel;
            let radius_tolerance = 1e-5 * x1.profiles[channel].pdf_radius(0.0);
            for (j, hit) in hits.iter().enumerate() {
                hits_total += 1;
                let x2 = EntryPoint::from_hit(&geometry, hit);
                let inverse = invert_technique(&x1, probe.technique, x2.position);
                let shift = (disk_point(&x1, &inverse) - disk_point(&x1, &probe)).length();
                assert!(
                    shift <= 1e-5,
                    "{}: disk point moved by {shift}",
                    meshes[shape as usize].0
                );
                assert!((inverse.u_radius - probe.u_radius).abs() <= radius_tolerance);
                match find_index(&geometry, &x1, &inverse, &x2, &mut scratch) {
                    Some(k) => assert_eq!(k, j as u32, "re-traced index differs"),
                    None => index_failures += 1,
                }
                let p = p_disk(&x1, &selection, x2.position, x2.geometric_normal);
                if let Ok(sample) = invert(
                    &geometry,
                    &x1,
                    &selection,
                    &x2,
                    rng.next_f32(),
                    &mut scratch,
                ) {
                    assert_eq!(sample.p_disk, p);
                    assert_eq!((sample.prim, sample.bary), (hit.prim, hit.bary));
                    if sample.technique == probe.technique {
                        same_technique += 1;
                        assert_eq!(sample.index, Some(j as u32));
                        assert_eq!(
                            (sample.u_radius, sample.u_angle),
                            (inverse.u_radius, inverse.u_angle)
                        );
                    }
                }
            }
        }
    }
    eprintln!(
        "round trip: {probes_total} probes, {hits_total} hits, {index_failures} index not re-found, \
         {same_technique} randomized inversions drew the sampled technique"
    );
    assert!(probes_total >= 10_000 && hits_total >= 10_000);
    // Re-tracing can miss only for x2 within rounding of a triangle edge.
    assert!(
        index_failures * 10_000 <= hits_total,
        "{index_failures} of {hits_total} indices not re-found"
    );
    assert!(
        same_technique * 4 >= hits_total,
        "inversion rarely drew the sampled technique"
    );
}

/// The per-technique terms of a deliberately wrong `p_disk` (negative controls): without the
/// `|n2·axis|` factor, or without the bitangent techniques.
fn wrong_terms(
    x1: &ExitPoint,
    selection: &TechniqueSelection,
    x2: Vec3,
    n2: Vec3,
    drop_cosine: bool,
) -> [f32; 9] {
    wrong_terms_with(x1, selection, RadiusSampling::Exact, x2, n2, drop_cosine)
}

/// [`wrong_terms`] for techniques whose radii come from `radius`.
fn wrong_terms_with(
    x1: &ExitPoint,
    selection: &TechniqueSelection,
    radius: RadiusSampling,
    x2: Vec3,
    n2: Vec3,
    drop_cosine: bool,
) -> [f32; 9] {
    let mut terms = technique_terms_with(x1, selection, radius, x2, n2);
    for t in Technique::ALL {
        if drop_cosine {
            let cos = n2.dot(x1.disk_basis(t.axis)[2]).abs();
            terms[t.index()] = if cos > 0.0 {
                terms[t.index()] / cos
            } else {
                0.0
            };
        } else if t.axis == Axis::Bitangent {
            terms[t.index()] = 0.0;
        }
    }
    terms
}

/// The posterior over techniques `P(t | x2) = term_t / p_disk` (DESIGN §9) is the conditional law
/// of the sampling technique given the hit, and inversion draws from it. For each probe,
/// `D_t = Σ_hits (1[t_sampled = t] − P(t | x2))` and `D'_t = Σ_hits (1[t_inverted = t] − P(t | x2))`
/// have mean 0; probes are independent. 18 two-sided z-tests, Bonferroni, family α = 1e-3,
/// N = 40 000 probes on a sphere. Negative controls: posteriors from a `p_disk` without `|n2·axis|`
/// and from one missing the bitangent techniques are rejected by the same test.
#[test]
fn inversion_posterior_matches_the_sampling_technique() {
    const N: u32 = 40_000;
    const ALPHA: f64 = 1e-3;
    let m = material();
    let selection = TechniqueSelection::default();
    let geometry = Geometry::new(&[shapes::uv_sphere(1.0, 96, 48)]);
    let mut hits = Vec::new();
    let mut stats = vec![Welford::new(); 3 * 9 + 9];
    for i in 0..N {
        let mut rng = StreamKey::new(i, 0, 1, PURPOSE).stream(3);
        let x1 = random_exit(&geometry, &mut rng, &m);
        let probe = Probe::sample(&selection, rng.next_f32(), rng.next_f32(), rng.next_f32());
        probe.trace(&geometry, &x1, &mut hits);
        let mut d = [0.0f64; 36];
        for hit in &hits {
            let x2 = EntryPoint::from_hit(&geometry, hit);
            let (inverted, _) =
                invert_random_numbers(&x1, &selection, &x2, rng.next_f32()).unwrap();
            let variants = [
                technique_terms(&x1, &selection, x2.position, x2.geometric_normal),
                wrong_terms(&x1, &selection, x2.position, x2.geometric_normal, true),
                wrong_terms(&x1, &selection, x2.position, x2.geometric_normal, false),
            ];
            for (v, terms) in variants.iter().enumerate() {
                let sum: f32 = terms.iter().sum();
                for t in Technique::ALL {
                    let posterior = if sum > 0.0 {
                        (terms[t.index()] / sum) as f64
                    } else {
                        0.0
                    };
                    d[9 * v + t.index()] += (probe.technique == t) as u8 as f64 - posterior;
                    if v == 0 {
                        d[27 + t.index()] += (inverted.technique == t) as u8 as f64 - posterior;
                    }
                }
            }
        }
        for (w, x) in stats.iter_mut().zip(d) {
            w.push(x);
        }
    }
    let z: Vec<f64> = stats
        .iter()
        .map(|w| w.summary())
        .map(|s| {
            if s.std_err > 0.0 {
                s.mean / s.std_err
            } else {
                0.0
            }
        })
        .collect();
    let critical = normal_quantile(1.0 - ALPHA / (2.0 * 18.0));
    let max_abs =
        |range: std::ops::Range<usize>| z[range].iter().fold(0.0f64, |a, &b| a.max(b.abs()));
    let (sampled, no_cosine, no_bitangent, inverted) = (
        max_abs(0..9),
        max_abs(9..18),
        max_abs(18..27),
        max_abs(27..36),
    );
    eprintln!(
        "posterior z (N = {N}, critical {critical:.2}): sampled {sampled:.2}, inverted {inverted:.2}; \
         controls: no |n2·axis| {no_cosine:.1}, no bitangent {no_bitangent:.1}"
    );
    assert!(
        sampled < critical && inverted < critical,
        "posterior rejected at α = {ALPHA} (N = {N}): max |z| sampled {sampled}, inverted {inverted} ≥ {critical}"
    );
    assert!(
        no_cosine >= critical,
        "negative control (no |n2·axis|) not detected: max |z| {no_cosine} (α = {ALPHA}, N = {N})"
    );
    assert!(
        no_bitangent >= critical,
        "negative control (no bitangent) not detected: max |z| {no_bitangent}"
    );
}

/// Composite quadrature of `f` (`D` densities at once) over the triangle `v`: `k²` sub-triangles,
/// each by the Duffy map from its vertex nearest `apex` (removing a 1/r singularity there) with
/// 3×3 Gauss–Legendre.
fn integrate<const D: usize>(
    v: [DVec3; 3],
    apex: DVec3,
    k: usize,
    f: &mut impl FnMut(DVec3) -> [f64; D],
) -> [f64; D] {
    const NODES: [f64; 3] = [0.112_701_665_379_258_3, 0.5, 0.887_298_334_620_741_7];
    const WEIGHTS: [f64; 3] = [5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0];
    let grid = |i: usize, j: usize| {
        v[0] + (i as f64 / k as f64) * (v[1] - v[0]) + (j as f64 / k as f64) * (v[2] - v[0])
    };
    let mut sum = [0.0; D];
    for i in 0..k {
        for j in 0..k - i {
            let mut subs = vec![[grid(i, j), grid(i + 1, j), grid(i, j + 1)]];
            if i + j + 1 < k {
                subs.push([grid(i + 1, j), grid(i + 1, j + 1), grid(i, j + 1)]);
            }
            for mut sub in subs {
                let nearest = (0..3)
                    .min_by(|&a, &b| {
                        (sub[a] - apex)
                            .length()
                            .total_cmp(&(sub[b] - apex).length())
                    })
                    .unwrap();
                sub.rotate_left(nearest);
                let twice_area = (sub[1] - sub[0]).cross(sub[2] - sub[0]).length();
                for (s, ws) in NODES.iter().zip(WEIGHTS) {
                    for (w, ww) in NODES.iter().zip(WEIGHTS) {
                        let x =
                            sub[0] + s * ((1.0 - w) * (sub[1] - sub[0]) + w * (sub[2] - sub[0]));
                        let jacobian = twice_area * s * ws * ww;
                        for (acc, value) in sum.iter_mut().zip(f(x)) {
                            *acc += jacobian * value;
                        }
                    }
                }
            }
        }
    }
    sum
}

/// Where the line `origin + s·axis` meets the plane of `v`, clamped into the triangle (the point
/// of `v` nearest a possible 1/r singularity of the technique terms of `axis`); `None` when the line
/// is parallel to the plane.
fn singular_point(v: [DVec3; 3], origin: DVec3, axis: DVec3) -> Option<DVec3> {
    let n = (v[1] - v[0]).cross(v[2] - v[0]);
    let denominator = n.dot(axis);
    if denominator.abs() <= 1e-9 * n.length() {
        return None;
    }
    let p = origin + (n.dot(v[0] - origin) / denominator) * axis;
    let weights = [(v[1], v[2]), (v[2], v[0]), (v[0], v[1])]
        .map(|(a, b)| ((a - p).cross(b - p).dot(n) / n.length_squared()).max(0.0));
    let total: f64 = weights.iter().sum();
    Some((weights[0] * v[0] + weights[1] * v[1] + weights[2] * v[2]) / total)
}

/// [`integrate`] over `v` split into three triangles at `apex` (a point of `v`).
fn integrate_around<const D: usize>(
    v: [DVec3; 3],
    apex: DVec3,
    k: usize,
    f: &mut impl FnMut(DVec3) -> [f64; D],
) -> [f64; D] {
    let mut sum = [0.0; D];
    for (a, b) in [(v[0], v[1]), (v[1], v[2]), (v[2], v[0])] {
        if (a - apex).cross(b - apex).length() > 1e-14 {
            let part = integrate([apex, a, b], apex, k, f);
            sum.iter_mut().zip(part).for_each(|(s, p)| *s += p);
        }
    }
    sum
}

/// Histogram of sampled x2 against `p_disk` on a sphere. Each probe keeps one hit picked
/// uniformly (so probes are multinomial trials; with all hits kept, the paired hits of tangent
/// chords would correlate the bins), so the kept hit has density `q(x) = Σ_t term_t(x) / n_t(x)`,
/// `n_t(x)` = number of hits on technique t's chord through x (re-traced). Bins: every triangle
/// within r_max of x1 plus one "no hit" cell; expected counts by composite quadrature of `q`
/// (Duffy-mapped at the 1/r singularities: x1 and where the tangent lines through x1 cross a
/// triangle; halving the quadrature step moves the expected counts by far less than √E).
/// Chi-square, α = 1e-3, N = 100 000 probes. Negative controls: `q` from a `p_disk` without
/// `|n2·axis|`, and from one missing the bitangent techniques, are rejected.
#[test]
fn sampled_entry_points_follow_p_disk() {
    entry_point_histogram(RadiusSampling::Exact);
}

/// [`sampled_entry_points_follow_p_disk`] for probes whose radii come from `g(ξ)` [004 Eq. 21],
/// against `p_disk` with the density of `g(U)`. (This histogram cannot tell `g(U)` from Burley's
/// radii at N = 10⁵, p ≈ 0.03; `technique::tests::xie_weighted_estimates_are_unbiased` does.)
#[test]
fn xie_entry_points_follow_their_own_p_disk() {
    entry_point_histogram(RadiusSampling::Xie);
}

/// The histogram test of x2 drawn with `radius`.
fn entry_point_histogram(radius: RadiusSampling) {
    const N: u32 = 100_000;
    const ALPHA: f64 = 1e-3;
    const QUADRATURE_K: usize = 8;
    let m = material();
    let selection = TechniqueSelection::default();
    let geometry = Geometry::new(&[shapes::uv_sphere(1.0, 64, 32)]);
    // x1 at vertex 0 of a triangle near the equator (the 1/r singularity sits on a vertex).
    let prim = 62 * 5 + 32;
    let x1 = exit_at(&geometry, prim, Vec2::ZERO, &m);
    let r_ball = x1.r_max.max_element();
    let bins: Vec<u32> = (0..geometry.triangle_count())
        .filter(|&p| {
            let [a, b, c] = geometry.vertices(p);
            let centroid = (a + b + c) / 3.0;
            let radius = [a, b, c]
                .iter()
                .map(|v| (*v - centroid).length())
                .fold(0.0, f32::max);
            (centroid - x1.position).length() <= r_ball + radius
        })
        .collect();
    let bin_of = |prim: u32| bins.iter().position(|&p| p == prim);

    let mut observed = vec![0.0f64; bins.len() + 1];
    let mut hits = Vec::new();
    for i in 0..N {
        let mut rng = StreamKey::new(i, 0, 2, PURPOSE).stream(4);
        let probe = Probe::sample(&selection, rng.next_f32(), rng.next_f32(), rng.next_f32());
        probe.trace_with(&geometry, &x1, radius, &mut hits);
        match pick_hit(&hits, None, rng.next_f32()) {
            Some((_, hit)) => {
                observed[bin_of(hit.prim).expect("hit outside the r_max ball")] += 1.0
            }
            None => observed[bins.len()] += 1.0,
        }
    }
    let mut chord_hits = Vec::new();
    // The three densities restricted to the techniques of `axis`, at x on a triangle of normal n.
    let mut density = |axis: Axis, x: DVec3, n: Vec3| -> [f64; 3] {
        let x = x.as_vec3();
        let mut per_hit = [0.0f64; 9];
        for t in Technique::ALL.into_iter().filter(|t| t.axis == axis) {
            if let Some(ray) = chord(&x1, t, x1.disk_coordinates(t.axis, x)) {
                trace_probe(&geometry, &x1, &ray, &mut chord_hits);
                per_hit[t.index()] = 1.0 / chord_hits.len().max(1) as f64;
            }
        }
        let weigh = |terms: [f32; 9]| -> f64 {
            terms.iter().zip(per_hit).map(|(&p, w)| p as f64 * w).sum()
        };
        [
            weigh(technique_terms_with(&x1, &selection, radius, x, n)),
            weigh(wrong_terms_with(&x1, &selection, radius, x, n, true)),
            weigh(wrong_terms_with(&x1, &selection, radius, x, n, false)),
        ]
    };
    let mut expected: [Vec<f64>; 3] = std::array::from_fn(|_| vec![0.0f64; bins.len() + 1]);
    let origin = x1.position.as_dvec3();
    for (b, &p) in bins.iter().enumerate() {
        let n = geometry.geometric_normal(p);
        let v = geometry.vertices(p).map(|v| v.as_dvec3());
        for axis in Axis::ALL {
            // Each axis's terms are singular (1/r) where its line through x1 meets the triangle.
            let direction = x1.disk_basis(axis)[2].as_dvec3();
            let apex = singular_point(v, origin, direction).unwrap_or(origin);
            let integral = integrate_around(v, apex, QUADRATURE_K, &mut |x| density(axis, x, n));
            for k in 0..3 {
                expected[k][b] += N as f64 * integral[k];
            }
        }
    }
    for e in &mut expected {
        let hit_total: f64 = e[..bins.len()].iter().sum();
        e[bins.len()] = (N as f64 - hit_total).max(0.0);
    }
    let [right, no_cosine, no_bitangent] = expected.map(|e| chi_square_gof(&observed, &e, 5.0));
    eprintln!(
        "{radius:?} x2 histogram (N = {N}, {} bins): χ² = {:.1}, dof {}, p = {:.3}; \
         controls p = {:.2e} (no |n2·axis|), {:.2e} (no bitangent)",
        bins.len() + 1,
        right.statistic,
        right.dof,
        right.p_value,
        no_cosine.p_value,
        no_bitangent.p_value
    );
    assert!(
        right.p_value > ALPHA,
        "sampled x2 do not follow p_disk: {right:?} (α = {ALPHA}, N = {N})"
    );
    assert!(
        no_cosine.p_value < ALPHA,
        "negative control (no |n2·axis|) not rejected: {no_cosine:?}"
    );
    assert!(
        no_bitangent.p_value < ALPHA,
        "negative control (no bitangent) not rejected: {no_bitangent:?}"
    );
}
