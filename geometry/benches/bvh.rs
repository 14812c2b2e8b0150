//! BVH benchmark (`cargo bench -p geometry --bench bvh`): build time, incoherent closest-hit
//! rays/s (one thread and all threads), and SSS probe rays/s (all hits on one object along short
//! chords, as in BSSRDF importance sampling [001 §2.1]). Prints a table; asserts nothing.

use std::time::{Duration, Instant};

use geometry::{Frame, Geometry, Hit, Ray, TriangleMesh, shapes};
use glam::{Vec2, Vec3, Vec3A};
use obvhs::{BvhBuildParams, ray::RayHit};
use rayon::prelude::*;
use restir::rng::{Stream, StreamKey};

const SEED: u64 = 0xBE4C;
const RAYS: usize = 1 << 20;
const PROBES: usize = 1 << 19;

fn unit_vector(rng: &mut Stream) -> Vec3A {
    let z = 1.0 - 2.0 * rng.next_f32();
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = std::f32::consts::TAU * rng.next_f32();
    Vec3A::new(r * phi.cos(), r * phi.sin(), z)
}

/// Origins uniform in the mesh bounds, directions uniform on the sphere.
fn incoherent_rays(mesh: &TriangleMesh) -> Vec<Ray> {
    let (lo, hi) = mesh.bounds();
    let mut rng = StreamKey::new(0, 0, 0, 1).stream(SEED);
    (0..RAYS)
        .map(|_| {
            let u = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
            Ray::new(
                (lo + (hi - lo) * u).into(),
                unit_vector(&mut rng),
                0.0,
                f32::INFINITY,
            )
        })
        .collect()
}

/// BSSRDF-style probes: x1 on a random triangle, axis = normal / tangent / bitangent with
/// probability ½ / ¼ / ¼, disk radius r < r_max, chord of the r_max sphere along the axis
/// [DESIGN §9 "Probe ray"]; r_max = 2.5% of the bounds diagonal (chords ≤ 5% of the object).
fn probe_rays(geometry: &Geometry, mesh: &TriangleMesh) -> Vec<Ray> {
    let (lo, hi) = mesh.bounds();
    let r_max = 0.025 * (hi - lo).length();
    let mut rng = StreamKey::new(0, 0, 0, 2).stream(SEED);
    (0..PROBES)
        .map(|_| {
            let prim = ((rng.next_u32() as u64 * geometry.triangle_count() as u64) >> 32) as u32;
            let (a, b) = (rng.next_f32(), rng.next_f32());
            let bary = if a + b > 1.0 {
                Vec2::new(1.0 - a, 1.0 - b)
            } else {
                Vec2::new(a, b)
            };
            let x1 = geometry.position(prim, bary);
            let frame = Frame::from_normal(geometry.geometric_normal(prim));
            let choice = rng.next_f32();
            let (axis, t, b) = if choice < 0.5 {
                (frame.n, frame.t, frame.b)
            } else if choice < 0.75 {
                (frame.t, frame.b, frame.n)
            } else {
                (frame.b, frame.n, frame.t)
            };
            let (r, phi) = (
                r_max * rng.next_f32(),
                std::f32::consts::TAU * rng.next_f32(),
            );
            let q = x1 + r * (phi.cos() * t + phi.sin() * b);
            let h = (r_max * r_max - r * r).sqrt();
            Ray::segment((q + h * axis).into(), (q - h * axis).into())
        })
        .collect()
}

fn rate(count: usize, time: Duration) -> String {
    format!("{:>8.2} M/s", count as f64 / time.as_secs_f64() / 1e6)
}

/// CPU time this thread has run (Linux `/proc/thread-self/schedstat`), so single-thread rates
/// stay meaningful on a shared machine; `None` elsewhere.
fn thread_cpu_time() -> Option<Duration> {
    let stat = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    Some(Duration::from_nanos(
        stat.split_whitespace().next()?.parse().ok()?,
    ))
}

/// Runs `f` once; returns its output and its duration: thread CPU time where available
/// (single-threaded work), else wall time.
fn time<T>(f: impl FnOnce() -> T) -> (T, Duration) {
    let (start, cpu_start) = (Instant::now(), thread_cpu_time());
    let out = f();
    let cpu = thread_cpu_time()
        .zip(cpu_start)
        .map(|(end, start)| end - start);
    (out, cpu.unwrap_or_else(|| start.elapsed()))
}

/// Runs `f` once on the rayon pool; returns its output and the wall time.
fn wall_time<T>(f: impl FnOnce() -> T) -> (T, Duration) {
    let start = Instant::now();
    let out = f();
    (out, start.elapsed())
}

/// Stock obvhs 0.4 closest hit for comparison (its node test and Möller–Trumbore triangles).
fn stock_obvhs_closest(
    bvh: &obvhs::cwbvh::CwBvh,
    triangles: &[obvhs::triangle::Triangle],
    ray: &Ray,
) -> bool {
    let mut hit = RayHit::none();
    let stock = obvhs::ray::Ray::new(ray.origin, ray.dir, ray.t_min, ray.t_max);
    bvh.ray_traverse(stock, &mut hit, |r, slot| triangles[slot].intersect(r))
}

fn bench(name: &str, mesh: TriangleMesh) {
    println!(
        "\n{name}: {} triangles (1-thread rates per CPU-second of the thread)",
        mesh.triangle_count()
    );
    let meshes = [mesh];
    let presets = [
        ("fast", BvhBuildParams::fast_build()),
        ("medium", BvhBuildParams::medium_build()),
        ("slow", BvhBuildParams::slow_build()),
    ];
    for (preset, params) in presets {
        let (geometry, build) = time(|| Geometry::with_build_params(&meshes, params));
        let rays = incoherent_rays(&meshes[0]);
        let (_, single) = time(|| {
            rays.iter()
                .filter(|r| geometry.closest_hit(r).is_some())
                .count()
        });
        println!(
            "  {:<44} {:>8.1} ms, closest hit {}",
            format!("BVH build, {preset} preset, 1 thread"),
            build.as_secs_f64() * 1e3,
            rate(RAYS, single)
        );
    }
    let (geometry, _) = time(|| Geometry::new(&meshes));
    let mesh = &meshes[0];

    let rays = incoherent_rays(mesh);
    let (hits, single) = time(|| {
        rays.iter()
            .filter(|r| geometry.closest_hit(r).is_some())
            .count()
    });
    println!(
        "  {:<44} {}  ({:.0}% hit)",
        "closest hit, incoherent, 1 thread",
        rate(RAYS, single),
        100.0 * hits as f64 / RAYS as f64
    );
    let (_, parallel) = wall_time(|| {
        rays.par_iter()
            .filter(|r| geometry.closest_hit(r).is_some())
            .count()
    });
    println!(
        "  {:<44} {}  ({} threads, wall clock)",
        "closest hit, incoherent, rayon",
        rate(RAYS, parallel),
        rayon::current_num_threads()
    );
    let (_, occlusion) = time(|| rays.iter().filter(|r| geometry.occluded(r)).count());
    println!(
        "  {:<44} {}",
        "occluded, incoherent, 1 thread",
        rate(RAYS, occlusion)
    );

    let leaf_triangles: Vec<obvhs::triangle::Triangle> = geometry
        .bvh()
        .primitive_indices
        .iter()
        .map(|&prim| {
            let [v0, v1, v2] = geometry.vertices(prim).map(Vec3A::from);
            obvhs::triangle::Triangle { v0, v1, v2 }
        })
        .collect();
    let (_, stock) = time(|| {
        rays.iter()
            .filter(|r| stock_obvhs_closest(geometry.bvh(), &leaf_triangles, r))
            .count()
    });
    println!(
        "  {:<44} {}",
        "closest hit, incoherent, stock obvhs 0.4",
        rate(RAYS, stock)
    );

    let probes = probe_rays(&geometry, mesh);
    let mut out: Vec<Hit> = Vec::new();
    let (total, probe_time) = time(|| {
        probes
            .iter()
            .map(|r| {
                geometry.all_hits_on_object(r, 0, &mut out);
                out.len()
            })
            .sum::<usize>()
    });
    println!(
        "  {:<44} {}  ({:.2} hits/probe)",
        "SSS probe (all hits on object), 1 thread",
        rate(PROBES, probe_time),
        total as f64 / PROBES as f64
    );
    let (_, probe_parallel) = wall_time(|| {
        probes
            .par_iter()
            .map_init(Vec::new, |out, r| {
                geometry.all_hits_on_object(r, 0, out);
                out.len()
            })
            .sum::<usize>()
    });
    println!(
        "  {:<44} {}  (wall clock)",
        "SSS probe (all hits on object), rayon",
        rate(PROBES, probe_parallel)
    );
}

fn main() {
    bench(
        "bumpy sphere (icosphere 7, displaced)",
        shapes::bumpy_sphere(1.0, 0.08, 4.0, 3, 7),
    );
    bench(
        "torus knot (2,3)",
        shapes::torus_knot(2, 3, 1.0, 0.12, 2048, 64),
    );
    // Small enough to stay in L2: the kernels' speed without DRAM latency.
    bench(
        "bumpy sphere (icosphere 5), cache-resident",
        shapes::bumpy_sphere(1.0, 0.08, 4.0, 3, 5),
    );
}
