//! reshift's CPU traversal against Embree 3, side by side (`cargo bench -p traversal-bench`).
//!
//! Same meshes (the built-in `bumpy` scene; a ~100k-triangle scanned-like mesh), same rays
//! (incoherent closest hit and occlusion, shadow segments, SSS probe chords from `sss::bssrdf`:
//! closest hit and all hits on the probed object), single-ray calls, on one thread and on two.
//! Rounds interleave the engines (every 2^16 rays); each figure is the median over rounds with
//! its min–max spread, and per-ray agreement is counted once. Rates are per CPU-second of the
//! measuring threads (robust to other load on a shared machine): with two threads, rays over
//! half their summed CPU time, the rate two free cores would reach.
//!
//! `TRAVERSAL_BENCH_RAYS` (default 2^20) and `TRAVERSAL_BENCH_ROUNDS` (default 5) change the
//! sizes; `TRAVERSAL_BENCH_QUERIES` (comma-separated parts of the query names, e.g. `closest`)
//! measures only the queries whose names contain one of them. Without Embree the reshift columns
//! are still measured.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use geometry::{Geometry, Hit, Ray};
use sss::bssrdf::{ExitPoint, Probe, TechniqueSelection};
use sss::integrator::pt::SHADOW_EPSILON;
use sss::material::{Material, Translucent};
use sss::scene::Scene;
use traversal_bench::{EMBREE_STATUS, rays, scanned};

#[cfg(embree)]
use traversal_bench::embree::Embree;
#[cfg(not(embree))]
/// Stand-in so the benchmark compiles without Embree; never constructed.
enum Embree {}

#[derive(Clone, Copy, PartialEq)]
enum Query {
    Closest,
    Occluded,
    ClosestOnObject,
    AllHitsOnObject,
}

/// Rays per turn of one engine within a round.
const CHUNK: usize = 1 << 16;

struct Workload<'a> {
    name: &'static str,
    query: Query,
    rays: &'a [Ray],
}

fn env_usize(name: &str, default: usize) -> usize {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// CPU time of the calling thread (`CLOCK_THREAD_CPUTIME_ID`, exact to the nanosecond; the
/// `/proc/thread-self/schedstat` counter only advances at scheduler ticks, ~4 ms), else `None`.
#[cfg(unix)]
fn thread_cpu_time() -> Option<Duration> {
    let mut now = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `now` is a valid, writable timespec.
    let status = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut now) };
    (status == 0).then(|| Duration::new(now.tv_sec as u64, now.tv_nsec as u32))
}
#[cfg(not(unix))]
fn thread_cpu_time() -> Option<Duration> {
    None
}

/// One engine's answer to one query, reduced to what the engines must agree on.
#[cfg(embree)]
#[derive(Clone, Debug, PartialEq)]
enum Answer {
    Hit(Option<u32>),
    Occluded(bool),
    Hits(Vec<u32>),
}

struct Scratch {
    hits: Vec<Hit>,
    #[cfg(embree)]
    embree_hits: Vec<(f32, u32)>,
}

impl Scratch {
    fn new() -> Scratch {
        Scratch {
            hits: Vec::new(),
            #[cfg(embree)]
            embree_hits: Vec::new(),
        }
    }
}

/// Runs `query` on reshift; returns a value that depends on the result (so nothing is elided).
#[inline(always)]
fn reshift(geometry: &Geometry, query: Query, object: u32, ray: &Ray, s: &mut Scratch) -> usize {
    match query {
        Query::Closest => geometry.closest_hit(ray).map_or(0, |h| h.prim as usize),
        Query::Occluded => geometry.occluded(ray) as usize,
        Query::ClosestOnObject => geometry
            .closest_hit_on_object(ray, object)
            .map_or(0, |h| h.prim as usize),
        Query::AllHitsOnObject => {
            geometry.all_hits_on_object(ray, object, &mut s.hits);
            s.hits.len()
        }
    }
}

#[cfg(embree)]
#[inline(always)]
fn embree(engine: &Embree, query: Query, object: u32, ray: &Ray, s: &mut Scratch) -> usize {
    match query {
        Query::Closest => engine.closest_hit(ray).map_or(0, |h| h.0 as usize),
        Query::Occluded => engine.occluded(ray) as usize,
        Query::ClosestOnObject => engine
            .closest_hit_on_object(ray, object)
            .map_or(0, |h| h.0 as usize),
        Query::AllHitsOnObject => {
            engine.all_hits_on_object(ray, object, &mut s.embree_hits);
            s.embree_hits.len()
        }
    }
}
#[cfg(not(embree))]
fn embree(engine: &Embree, _: Query, _: u32, _: &Ray, _: &mut Scratch) -> usize {
    match *engine {}
}

#[cfg(embree)]
fn reshift_answer(geometry: &Geometry, query: Query, object: u32, ray: &Ray) -> Answer {
    match query {
        Query::Closest => Answer::Hit(geometry.closest_hit(ray).map(|h| h.prim)),
        Query::Occluded => Answer::Occluded(geometry.occluded(ray)),
        Query::ClosestOnObject => {
            Answer::Hit(geometry.closest_hit_on_object(ray, object).map(|h| h.prim))
        }
        Query::AllHitsOnObject => {
            let mut hits = Vec::new();
            geometry.all_hits_on_object(ray, object, &mut hits);
            let mut prims: Vec<u32> = hits.iter().map(|h| h.prim).collect();
            prims.sort_unstable();
            Answer::Hits(prims)
        }
    }
}

#[cfg(embree)]
fn embree_answer(engine: &Embree, query: Query, object: u32, ray: &Ray) -> Answer {
    match query {
        Query::Closest => Answer::Hit(engine.closest_hit(ray).map(|h| h.0)),
        Query::Occluded => Answer::Occluded(engine.occluded(ray)),
        Query::ClosestOnObject => {
            Answer::Hit(engine.closest_hit_on_object(ray, object).map(|h| h.0))
        }
        Query::AllHitsOnObject => {
            let mut hits = Vec::new();
            engine.all_hits_on_object(ray, object, &mut hits);
            let mut prims: Vec<u32> = hits.iter().map(|h| h.1).collect();
            prims.sort_unstable();
            Answer::Hits(prims)
        }
    }
}

/// Rays of `workload` on which both engines give the same answer, as `same of total`.
#[cfg(embree)]
fn agreement(geometry: &Geometry, engine: &Embree, workload: &Workload, object: u32) -> String {
    let same = workload
        .rays
        .iter()
        .filter(|r| {
            reshift_answer(geometry, workload.query, object, r)
                == embree_answer(engine, workload.query, object, r)
        })
        .count();
    format!("{same} of {}", workload.rays.len())
}
#[cfg(not(embree))]
fn agreement(_: &Geometry, engine: &Embree, _: &Workload, _: u32) -> String {
    match *engine {}
}

/// `f` over `rays` on the calling thread: its CPU time (wall clock where unavailable).
fn run_on_this_thread(rays: &[Ray], f: &(dyn Fn(&Ray, &mut Scratch) -> usize + Sync)) -> Duration {
    let (start, cpu_start) = (Instant::now(), thread_cpu_time());
    let mut scratch = Scratch::new();
    let sum: usize = rays.iter().map(|r| f(r, &mut scratch)).sum();
    std::hint::black_box(sum);
    thread_cpu_time()
        .zip(cpu_start)
        .map_or_else(|| start.elapsed(), |(end, begin)| end - begin)
}

/// Seconds `f` takes over `rays` on `threads` threads pulling batches of 1024 rays, as if each
/// had a core to itself: the threads' summed CPU time divided by `threads` (the machine is
/// shared, so wall clock would measure the other load).
fn seconds(rays: &[Ray], threads: usize, f: &(dyn Fn(&Ray, &mut Scratch) -> usize + Sync)) -> f64 {
    if threads == 1 {
        return run_on_this_thread(rays, f).as_secs_f64();
    }
    let next = AtomicUsize::new(0);
    let batches = || {
        std::iter::from_fn(|| {
            let first = next.fetch_add(1024, Ordering::Relaxed);
            (first < rays.len()).then(|| &rays[first..(first + 1024).min(rays.len())])
        })
    };
    let busy: Duration = std::thread::scope(|scope| {
        let workers: Vec<_> = (0..threads)
            .map(|_| {
                scope.spawn(|| {
                    batches()
                        .map(|batch| run_on_this_thread(batch, f))
                        .sum::<Duration>()
                })
            })
            .collect();
        workers
            .into_iter()
            .map(|w| w.join().expect("benchmark thread"))
            .sum::<Duration>()
    });
    busy.as_secs_f64() / threads as f64
}

fn median(values: &[f64]) -> f64 {
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// `median [min–max]`.
fn summary(values: &[f64]) -> String {
    let min = values.iter().copied().fold(f64::INFINITY, f64::min);
    let max = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    format!("{:.2} [{min:.2}–{max:.2}]", median(values))
}

fn material(scene: &Scene, object: u32) -> Translucent {
    match scene.material_of_object(object) {
        Material::Translucent(t) => *t,
        Material::Lambert(_) => panic!("object {object} of bumpy is not translucent"),
    }
}

/// SSS probe chords: exit points x1 uniform on `object`, techniques and random numbers drawn as
/// `sss::bssrdf::Probe::sample` does, chords from `Probe::ray`.
fn probes(geometry: &Geometry, object: u32, material: &Translucent, count: usize) -> Vec<Ray> {
    let selection = TechniqueSelection::default();
    rays::chords(geometry, object, count, |prim, bary, rng| {
        let n = geometry.geometric_normal(prim);
        let x1 = ExitPoint::new(
            geometry.position(prim, bary),
            n,
            geometry.shading_normal(prim, bary),
            n,
            object,
            material,
        );
        let probe = Probe::sample(&selection, rng.next_f32(), rng.next_f32(), rng.next_f32());
        probe.ray(&x1)
    })
}

#[cfg(embree)]
/// One mesh per object, as triangle soup with the exact vertices `geometry` holds (for Embree).
fn object_meshes(geometry: &Geometry) -> Vec<geometry::TriangleMesh> {
    let mut meshes = vec![geometry::TriangleMesh::default(); geometry.object_count() as usize];
    for prim in 0..geometry.triangle_count() {
        let mesh = &mut meshes[geometry.object_of(prim) as usize];
        let base = mesh.positions.len() as u32;
        mesh.positions.extend(geometry.vertices(prim));
        mesh.indices.push([base, base + 1, base + 2]);
    }
    meshes
}

fn bench(
    name: &str,
    geometry: &Geometry,
    object: u32,
    jade: &Translucent,
    count: usize,
    rounds: usize,
) {
    let incoherent = rays::incoherent(geometry, object, count);
    let shadow = rays::shadow(geometry, object, count, SHADOW_EPSILON);
    let probes = probes(geometry, object, jade, count);
    let only = std::env::var("TRAVERSAL_BENCH_QUERIES").unwrap_or_default();
    let workloads: Vec<Workload> = [
        Workload {
            name: "closest hit, incoherent",
            query: Query::Closest,
            rays: &incoherent,
        },
        Workload {
            name: "occluded, incoherent",
            query: Query::Occluded,
            rays: &incoherent,
        },
        Workload {
            name: "occluded, shadow segments",
            query: Query::Occluded,
            rays: &shadow,
        },
        Workload {
            name: "SSS probe, closest on object",
            query: Query::ClosestOnObject,
            rays: &probes,
        },
        Workload {
            name: "SSS probe, all hits on object",
            query: Query::AllHitsOnObject,
            rays: &probes,
        },
    ]
    .into_iter()
    .filter(|w| only.split(',').any(|part| w.name.contains(part)))
    .collect();
    println!(
        "\n## {name}: {} triangles, {} objects; {count} rays per set, probed object {object}\n",
        geometry.triangle_count(),
        geometry.object_count()
    );

    #[cfg(embree)]
    let engine = {
        let start = Instant::now();
        let engine = Embree::new(&object_meshes(geometry)).expect("Embree scene");
        println!(
            "Embree build (2 scenes, 2 threads): {:.1} ms\n",
            start.elapsed().as_secs_f64() * 1e3
        );
        Some(engine)
    };
    #[cfg(not(embree))]
    let engine: Option<Embree> = None;

    // Per-ray agreement, once (untimed).
    let agreement: Vec<String> = workloads
        .iter()
        .map(|w| match &engine {
            Some(engine) => agreement(geometry, engine, w, object),
            None => "—".to_string(),
        })
        .collect();

    // rates[workload][engine][threads] over rounds. Within a round the engines alternate every
    // CHUNK rays, so both run under the same machine load.
    let mut rates = vec![[[Vec::new(), Vec::new()], [Vec::new(), Vec::new()]]; workloads.len()];
    for round in 0..rounds {
        for (w, workload) in workloads.iter().enumerate() {
            for (t, threads) in [1, 2].into_iter().enumerate() {
                let (query, rays) = (workload.query, workload.rays);
                let mut secs = [0.0f64; 2];
                for chunk in rays.chunks(CHUNK) {
                    // Alternate which engine goes first.
                    for e in [round % 2, 1 - round % 2] {
                        secs[e] += match (e, &engine) {
                            (0, _) => seconds(chunk, threads, &|r, s| {
                                reshift(geometry, query, object, r, s)
                            }),
                            (_, Some(engine)) => {
                                seconds(chunk, threads, &|r, s| embree(engine, query, object, r, s))
                            }
                            (_, None) => continue,
                        };
                    }
                }
                for e in 0..2 {
                    if secs[e] > 0.0 {
                        rates[w][e][t].push(rays.len() as f64 / secs[e] / 1e6);
                    }
                }
            }
        }
    }

    println!(
        "| query | threads | reshift M rays/s | Embree M rays/s | reshift / Embree | agreement |"
    );
    println!("|---|---:|---:|---:|---:|---:|");
    for (w, workload) in workloads.iter().enumerate() {
        for (t, threads) in [1, 2].into_iter().enumerate() {
            let ours = &rates[w][0][t];
            let theirs = &rates[w][1][t];
            let (embree_col, ratio_col) = if theirs.is_empty() {
                ("—".to_string(), "—".to_string())
            } else {
                let per_round: Vec<f64> = ours.iter().zip(theirs).map(|(a, b)| a / b).collect();
                (summary(theirs), summary(&per_round))
            };
            println!(
                "| {} | {threads} | {} | {embree_col} | {ratio_col} | {} |",
                workload.name,
                summary(ours),
                if t == 0 { agreement[w].as_str() } else { "" }
            );
        }
    }
}

fn main() {
    let count = env_usize("TRAVERSAL_BENCH_RAYS", 1 << 20);
    let rounds = env_usize("TRAVERSAL_BENCH_ROUNDS", 5).max(1);
    println!("# CPU traversal: reshift vs Embree\n");
    println!("Embree: {EMBREE_STATUS}");
    #[cfg(not(embree))]
    println!("Measuring reshift alone: the Embree, ratio and agreement columns stay empty.");
    #[cfg(embree)]
    if let Ok(engine) = Embree::new(&[]) {
        println!("Embree library version {}", engine.version());
    }
    println!(
        "{rounds} rounds, engines alternating every {CHUNK} rays; figures are median [min–max] \
         over rounds; the ratio column is the median of per-round ratios. Rates per CPU-second of \
         the measuring threads (2 threads: rays over half their summed CPU time)."
    );

    let scene = Scene::builtin("bumpy").expect("built-in bumpy scene");
    let jade = material(&scene, 0);
    bench(
        "bumpy (built-in scene)",
        &scene.geometry,
        0,
        &jade,
        count,
        rounds,
    );

    let start = Instant::now();
    let mesh = scanned::scanned_like(104);
    let generated = start.elapsed();
    let start = Instant::now();
    let geometry = Geometry::new(std::slice::from_ref(&mesh));
    println!(
        "\n(scanned-like mesh generated in {:.0} ms; reshift BVH build {:.1} ms)",
        generated.as_secs_f64() * 1e3,
        start.elapsed().as_secs_f64() * 1e3
    );
    bench(
        "scanned-like bunny (procedural)",
        &geometry,
        0,
        &jade,
        count,
        rounds,
    );
}
