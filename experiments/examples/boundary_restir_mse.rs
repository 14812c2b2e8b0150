//! Equal-spp MSE of `single-scatter:1` with and without `/restir` (ReSTIR on paper 000's boundary
//! term, `methods::single_scatter::boundary_reuse`) at frames 0 and 15 of a scene's trajectory: of the
//! boundary term alone and of the whole method, on the translucent pixels, against each term's
//! own converged value (the plain estimator at many samples per pixel, so the model error of
//! `R − R1` is not part of the error).
//!
//! * Replica `k` runs with seed `k`; both methods draw their single and multiple scattering from
//!   the same streams, so the whole method's ratio is paired by seed ([`lab::uncertainty`]).
//! * Per replica: the mean over translucent pixels and RGB channels of the squared error, minus
//!   the reference's own variance (per-pixel variance of the batch means / batches; it is
//!   reported and is below 0.5% of every MSE at the defaults).
//! * Printed: MSE per method with its 95% CI, and the ratio restir / plain with its 95% CI on the
//!   log scale.
//!
//! `cargo run --release -p experiments --example boundary_restir_mse -- [scene] [WxH] [replicas] [ref spp]
//! [mfp scale]` (defaults: `slab 64x48 32 4096 1`; the scale multiplies every translucent
//! material's `scale`).

use glam::{DVec3, Vec3};
use methods::single_scatter::boundary_reuse::{
    self, BoundaryDomain, DEFAULT_CAP, ReuseSettings, SameVertices,
};
use rayon::prelude::*;
use sss::integrator::pt;
use sss::integrator::single_scatter::{self, Shading, SingleScatterSettings, sample_stream};
use sss::material::Material;
use sss::random_walk::Medium;
use sss::scene::{FRAMES, GBuffer, Scene};

use lab::regions::{Region, Regions};
use lab::uncertainty::Estimate;
use methods::single_scatter::exit_lighting;

/// Seeds of the references: far above every replica's.
const REFERENCE_SEED: u64 = 1 << 40;
/// Batches of each reference (its per-pixel variance).
const BATCHES: u32 = 16;
const MEASURED: [u32; 2] = [0, FRAMES - 1];

/// Per pixel: the plain estimator's `(boundary term, whole method)` means over `samples`, with
/// the exits' light selection keyed by `seed`.
fn plain(
    scene: &Scene,
    media: &[Option<Medium>],
    gbuffer: &GBuffer,
    seed: u64,
    samples: std::ops::Range<u32>,
    light_seed: u64,
) -> (Vec<DVec3>, Vec<DVec3>) {
    let settings = SingleScatterSettings::default();
    let frame = gbuffer.frame;
    let pass = |zero_only: bool| {
        pt::render_pixels(
            gbuffer,
            samples.clone(),
            |pixel, x1| {
                let reused = BoundaryDomain::new(scene, media, x1).is_some();
                let lighting = exit_lighting(scene, pixel, frame, light_seed);
                (Shading::new(scene, media, x1), lighting, reused)
            },
            |(shading, lighting, reused), pixel, sample, hits| {
                let mut rng = sample_stream(pixel, frame, sample, seed);
                let orders =
                    single_scatter::estimate(scene, shading, &settings, lighting, &mut rng, hits);
                match (zero_only, reused) {
                    (true, true) => orders.zero,
                    (true, false) => Vec3::ZERO,
                    (false, _) => orders.total(),
                }
            },
        )
        .pixels
    };
    (pass(true), pass(false))
}

/// Mean and per-pixel variance of the mean over [`BATCHES`] batches.
fn mean_and_variance(batches: &[Vec<DVec3>]) -> (Vec<DVec3>, Vec<f64>) {
    let n = batches.len() as f64;
    let pixels = batches[0].len();
    let mean: Vec<DVec3> = (0..pixels)
        .map(|p| batches.iter().map(|b| b[p]).sum::<DVec3>() / n)
        .collect();
    let variance = (0..pixels)
        .map(|p| {
            let ss: f64 = batches
                .iter()
                .map(|b| (b[p] - mean[p]).length_squared())
                .sum();
            ss / 3.0 / (n - 1.0) / n
        })
        .collect();
    (mean, variance)
}

/// Mean over `pixels` and channels of the squared error of `image` against `reference`.
fn mse(image: &[DVec3], reference: &[DVec3], pixels: &[usize]) -> f64 {
    pixels
        .iter()
        .map(|&p| (image[p] - reference[p]).length_squared() / 3.0)
        .sum::<f64>()
        / pixels.len() as f64
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let name = args.get(1).map_or("slab", |s| s.as_str());
    let size = args.get(2).map_or("64x48", |s| s.as_str());
    let replicas: u64 = args.get(3).map_or(32, |s| s.parse().unwrap());
    let reference_spp: u32 = args.get(4).map_or(4096, |s| s.parse().unwrap());
    let mfp_scale: f32 = args.get(5).map_or(1.0, |s| s.parse().unwrap());
    let (w, h) = size.split_once('x').unwrap();
    let mut scene = Scene::builtin(name).unwrap();
    for material in &mut scene.materials {
        if let Material::Translucent(t) = material {
            t.scale *= mfp_scale;
        }
    }
    scene.camera = scene
        .camera
        .with_resolution(w.parse().unwrap(), h.parse().unwrap());
    let media = boundary_reuse::check_materials(&scene).unwrap();
    let per_batch = reference_spp / BATCHES;

    // References per measured frame: (pixels, [boundary, whole] means and variances).
    let references: Vec<_> = MEASURED
        .iter()
        .map(|&frame| {
            let gbuffer = GBuffer::render(&scene, frame);
            let pixels = Regions::classify(&scene, &gbuffer, 0x5E61).pixels(Region::Translucent);
            let batches: Vec<(Vec<DVec3>, Vec<DVec3>)> = (0..BATCHES)
                .map(|b| {
                    let samples = b * per_batch..(b + 1) * per_batch;
                    plain(
                        &scene,
                        &media,
                        &gbuffer,
                        REFERENCE_SEED,
                        samples,
                        REFERENCE_SEED + b as u64,
                    )
                })
                .collect();
            let zero: Vec<Vec<DVec3>> = batches.iter().map(|b| b.0.clone()).collect();
            let whole: Vec<Vec<DVec3>> = batches.iter().map(|b| b.1.clone()).collect();
            (
                gbuffer,
                pixels,
                [mean_and_variance(&zero), mean_and_variance(&whole)],
            )
        })
        .collect();

    // Per replica and measured frame: [plain boundary, plain whole, restir boundary, restir whole].
    let errors: Vec<Vec<[f64; 4]>> = (0..replicas)
        .into_par_iter()
        .map(|seed| {
            let reuse = ReuseSettings {
                candidates: 1,
                cap: DEFAULT_CAP,
            };
            let restir = boundary_reuse::render(
                &scene,
                &SingleScatterSettings::default(),
                &reuse,
                seed,
                FRAMES,
                0,
                1,
                |pixel, frame| exit_lighting(&scene, pixel, frame, seed),
                &SameVertices,
            )
            .unwrap();
            MEASURED
                .iter()
                .zip(&references)
                .map(|(&frame, (gbuffer, pixels, [zero, whole]))| {
                    let (p_zero, p_whole) = plain(&scene, &media, gbuffer, seed, 0..1, seed);
                    let r = &restir[frame as usize];
                    let r_zero: Vec<DVec3> = r.boundary.iter().map(|v| v.as_dvec3()).collect();
                    [
                        mse(&p_zero, &zero.0, pixels),
                        mse(&p_whole, &whole.0, pixels),
                        mse(&r_zero, &zero.0, pixels),
                        mse(&r.image.pixels, &whole.0, pixels),
                    ]
                })
                .collect()
        })
        .collect();

    println!(
        "{name} (mfp × {mfp_scale}) {size}, {replicas} replicas, references {reference_spp} spp \
         ({BATCHES} batches), translucent pixels; MSE per pixel and channel, 95% CIs"
    );
    println!("| frame | term | plain | /restir | ratio /restir ÷ plain | reference variance |");
    println!("|---:|---|---:|---:|---:|---:|");
    for (i, (&frame, (_, pixels, refs))) in MEASURED.iter().zip(&references).enumerate() {
        for (t, term) in ["boundary", "whole"].iter().enumerate() {
            let ref_variance =
                pixels.iter().map(|&p| refs[t].1[p]).sum::<f64>() / pixels.len() as f64;
            let estimate = |column: usize| {
                let samples: Vec<f64> = errors.iter().map(|e| e[i][column]).collect();
                Estimate::mean(&samples).minus_constant(ref_variance, 0.0)
            };
            let (p, r) = (estimate(t), estimate(2 + t));
            let ratio = r.ln().unwrap().minus(&p.ln().unwrap()).unwrap();
            let ci = |e: &Estimate| {
                let i = e.interval(0.95).unwrap();
                format!("{:.4e} [{:.4e}, {:.4e}]", e.value, i.lo, i.hi)
            };
            let ri = ratio.exp_interval(0.95).unwrap();
            println!(
                "| {frame} | {term} ({} px) | {} | {} | {:.3} [{:.3}, {:.3}] | {ref_variance:.2e} |",
                pixels.len(),
                ci(&p),
                ci(&r),
                ratio.value.exp(),
                ri.lo,
                ri.hi
            );
        }
    }
}
