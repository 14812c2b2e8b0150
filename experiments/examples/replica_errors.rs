//! Per-replica errors of `reshift compare` with 95% bootstrap intervals (issue 10): the same
//! methods, scene, replicas (seed `k` for replica `k`), frames and cached reference as
//! `compare`, but each replica's MSE and seconds per frame are kept, so every figure gets an
//! interval.
//!
//! Per area (translucent, lit, penumbra, shadowed): MSE (mean over replicas, the reference's
//! own noise `reference_mse` subtracted), the efficiency
//! `1 / (MSE · s)` relative to the first method, and the MSE relative to `--paired-with` (same
//! seeds, so a paired ratio). Intervals: percentile bootstrap over replicas, the same resampled
//! replica indices for every method (10 000 resamples, fixed seed). Replicas run method after
//! method within a replica, so a slow phase of a shared machine hits every method alike; wall
//! times are still noisy, the MSEs are deterministic.
//!
//! `cargo run --release -p experiments --example replica_errors -- <scene> <WxH> <replicas> <methods>
//! [paired-with [reference-spp]]`, e.g. `… bumpy 128x96 8 pt,restir:hybrid,restir:hybrid/shade=all
//! restir:hybrid` (reference 8192 spp by default, in batches of 128, cached in `out/cache`).

use std::path::PathBuf;

use engine::Backend;
use lab::metrics::{Area, area_metrics};
use lab::progress::Silent;
use lab::reference_cache::{self, FrameReference, REFERENCE_SEED, ReferenceSource};
use lab::regions::{Region, Regions};
use lab::scenes::{load_scene, with_resolution};
use methods::{Method, Rendered};
use restir::rng::StreamKey;
use sss::scene::GBuffer;

const FRAMES: u32 = 16;
const RESAMPLES: usize = 10_000;
const AREAS: [Region; 4] = [
    Region::Translucent,
    Region::Lit,
    Region::Penumbra,
    Region::Shadowed,
];

/// Per method: per replica, the MSE of every area of [`AREAS`] and the seconds per frame.
type Errors = Vec<Vec<([f64; 4], f64)>>;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [scene, resolution, replicas, methods, rest @ ..] = &args[..] else {
        return Err(
            "usage: <scene> <WxH> <replicas> <method,method,...> [paired-with [reference-spp]]"
                .into(),
        );
    };
    let (w, h) = resolution
        .split_once('x')
        .and_then(|(w, h)| Some((w.parse().ok()?, h.parse().ok()?)))
        .ok_or("resolution: WxH")?;
    let replicas: u64 = replicas.parse()?;
    let specs: Vec<&str> = methods.split(',').collect();
    let paired_with = rest.first().map(String::as_str).unwrap_or(specs[0]);
    let reference_spp: u32 = rest.get(1).map_or(Ok(8192), |s| s.parse())?;
    let methods: Vec<Method> = specs
        .iter()
        .map(|s| Method::parse(s))
        .collect::<Result<_, _>>()?;
    let loaded = load_scene(scene)?;
    let scene = with_resolution(loaded.scene, Some((w, h)));
    let frame = FRAMES - 1;
    let source = ReferenceSource::Cache {
        dir: PathBuf::from("out/cache"),
        spp: reference_spp,
        batch_spp: 128,
    };
    let reference = reference_cache::obtain(&source, &scene, &loaded.key, frame, &mut Silent)?;
    let frame_reference = FrameReference::new(&reference.reference);
    let regions = Regions::classify(&scene, &GBuffer::render(&scene, frame), REFERENCE_SEED);
    let mut errors: Errors = vec![Vec::new(); methods.len()];
    for seed in 0..replicas {
        for (method, out) in methods.iter().zip(&mut errors) {
            let Rendered {
                image,
                seconds_per_frame,
                nonfinite,
                ..
            } = method.render_on(&Backend::Cpu, &scene, FRAMES, seed)?;
            assert_eq!(nonfinite, 0, "{method}: non-finite values");
            let metrics = area_metrics(&[image], &frame_reference, &regions).ok_or("image size")?;
            let mse = AREAS.map(|r| {
                metrics
                    .iter()
                    .find(|m| m.area == Area::Region(r))
                    .map_or(f64::NAN, |m| m.mse.value)
            });
            eprintln!("replica {seed} {method}: {mse:?}, {seconds_per_frame:.4} s/frame");
            out.push((mse, seconds_per_frame));
        }
    }
    let paired = specs
        .iter()
        .position(|s| *s == paired_with)
        .ok_or("paired-with")?;
    println!(
        "{} {w}×{h}, frame {frame}, {replicas} replicas, reference {reference_spp} spp; 95% percentile bootstrap ({RESAMPLES} resamples)",
        scene.name
    );
    for (a, region) in AREAS.iter().enumerate() {
        println!(
            "\n{region}\n| method | MSE [95% CI] | s/frame | efficiency / {} [95% CI] | MSE / {paired_with} [95% CI] |\n|---|---|---:|---|---|",
            specs[0]
        );
        for (m, spec) in specs.iter().enumerate() {
            let stat = |index: &[usize]| {
                let mean = |i: usize, f: &dyn Fn(&([f64; 4], f64)) -> f64| {
                    index.iter().map(|&k| f(&errors[i][k])).sum::<f64>() / index.len() as f64
                };
                let mse = |i| mean(i, &|e| e.0[a]);
                let seconds = |i| mean(i, &|e| e.1);
                [
                    mse(m),
                    (mse(0) * seconds(0)) / (mse(m) * seconds(m)),
                    mse(m) / mse(paired),
                ]
            };
            let all: Vec<usize> = (0..replicas as usize).collect();
            let point = stat(&all);
            let ci = bootstrap(replicas as usize, &stat);
            let seconds = errors[m].iter().map(|e| e.1).sum::<f64>() / replicas as f64;
            println!(
                "| {spec} | {:.4e} [{:.4e}, {:.4e}] | {seconds:.4} | {:.3} [{:.3}, {:.3}] | {:.3} [{:.3}, {:.3}] |",
                point[0], ci[0].0, ci[0].1, point[1], ci[1].0, ci[1].1, point[2], ci[2].0, ci[2].1
            );
        }
    }
    Ok(())
}

/// 2.5% and 97.5% percentiles of each of `stat`'s values over [`RESAMPLES`] resamples of `n`
/// replica indices with replacement (the same indices for every method: paired).
fn bootstrap(n: usize, stat: &dyn Fn(&[usize]) -> [f64; 3]) -> [(f64, f64); 3] {
    let mut rng = StreamKey::new(0, 0, 0, 0x0B00_7000).stream(10);
    let mut values: [Vec<f64>; 3] = Default::default();
    let mut index = vec![0; n];
    for _ in 0..RESAMPLES {
        for i in &mut index {
            *i = ((rng.next_f32() * n as f32) as usize).min(n - 1);
        }
        for (v, s) in values.iter_mut().zip(stat(&index)) {
            v.push(s);
        }
    }
    values.map(|mut v| {
        v.sort_by(f64::total_cmp);
        let at = |q: f64| v[((q * (v.len() - 1) as f64).round()) as usize];
        (at(0.025), at(0.975))
    })
}
