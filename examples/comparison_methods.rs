//! First measurements of the seed-002 and seed-004 methods on the CPU (before their integration in
//! the lab): `cargo run --release --example comparison_methods -- [image-space|adaptive|both] [replicas]
//! [σ0²] [κ] [out_dir]` (defaults: both, 16, 0.001, 0.2, `out/comparison-methods`).
//!
//! On `bumpy` at 128×96, frame 15 (the end of the 16-frame trajectory):
//! * **image-space** (`methods::image_space::cpu`, 4 passes): bias per region against the path
//!   tracer with the dipole profile (4096 spp in 16 batches), relative, with its 99% CI over the
//!   replicas (equivalence test, δ = 1%), and the fraction of entry samples it cannot see;
//! * **adaptive** (`methods::adaptive::cpu`, [004 Fig. 1] parameters unless σ0², κ are given,
//!   16 frames): the mean sample
//!   count per translucent pixel, and MSE against the Burley reference (4096 spp, its own variance
//!   subtracted) compared with fixed-count path tracing with the same `g(ξ)` radii at the rounded
//!   mean count and at b_max (the paper's fixed baseline): MSE ratio and efficiency ratio
//!   `MSE_fixed·n_fixed / (MSE_adaptive·n̄)`, per region, in linear RGB and in the controller's
//!   metric (gamma-corrected luminance), 95% CI by the delta method over the replicas; and the
//!   fraction of translucent pixels whose per-frame variance of that metric (across replicas)
//!   exceeds the target σ0².
//!
//! Regions are the lab's (`lab::regions`). The sample-count map of the last adaptive
//! replica is written to `out_dir/adaptive-counts.png` (count / 64 as grey).

use std::path::PathBuf;

use glam::{DVec3, Vec3};
use methods::adaptive::cpu::{self as adaptive, AdaptiveParams, perceptual_luminance};
use methods::image_space::cpu::{self as image_space, EntryCounts, ImageSpaceSettings};
use restir::stats::{Summary, equivalence, student_t_quantile};
use sss::color::luminance;
use sss::integrator::pt::{self, PtSettings};
use sss::profile::ProfileKind;
use sss::scene::{GBuffer, Scene};

use lab::regions::{Region, Regions};

const FRAME: u32 = 15;
const REFERENCE_BATCHES: u32 = 16;
const REFERENCE_SPP: u32 = 256;
const IMAGE_SPACE_SPP: u32 = 4;

/// `REFERENCE_BATCHES` independent batches of the path tracer.
fn reference_batches(
    scene: &Scene,
    g: &GBuffer,
    settings: &PtSettings,
    seed: u64,
) -> Vec<Vec<DVec3>> {
    (0..REFERENCE_BATCHES)
        .map(|b| pt::render(scene, g, settings, seed, b * REFERENCE_SPP, REFERENCE_SPP).pixels)
        .collect()
}

/// Per pixel, the mean of `f` over the batches and the variance of that mean.
fn batch_moments(batches: &[Vec<DVec3>], f: impl Fn(DVec3) -> f64) -> (Vec<f64>, Vec<f64>) {
    let n = batches.len() as f64;
    (0..batches[0].len())
        .map(|p| {
            let values: Vec<f64> = batches.iter().map(|b| f(b[p])).collect();
            let s = Summary::from_samples(&values);
            (s.mean, s.variance / n)
        })
        .unzip()
}

fn region_mean(values: &[f64], pixels: &[usize]) -> f64 {
    pixels.iter().map(|&p| values[p]).sum::<f64>() / pixels.len() as f64
}

/// Ratio `a/b` of two independent replica means with its 95% CI (delta method, Student t with
/// the smaller sample's degrees of freedom).
fn ratio(a: &Summary, b: &Summary) -> (f64, f64, f64) {
    let r = a.mean / b.mean;
    let rel = ((a.std_err / a.mean).powi(2) + (b.std_err / b.mean).powi(2)).sqrt();
    let t = student_t_quantile(0.975, (a.n.min(b.n) - 1) as f64);
    (r, r * (1.0 - t * rel), r * (1.0 + t * rel))
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let usage =
        "usage: comparison_methods [image-space|adaptive|both|mfp] [replicas] [σ0²] [κ] [out_dir]";
    let mode = args.get(1).map_or("both", |s| s.as_str());
    let replicas: u32 = args.get(2).map_or(16, |s| s.parse().expect(usage));
    let params = AdaptiveParams {
        target_variance: args.get(3).map_or(0.001, |s| s.parse().expect(usage)),
        kappa: args.get(4).map_or(0.2, |s| s.parse().expect(usage)),
        ..AdaptiveParams::default()
    };
    if let Err(e) = params.validate() {
        panic!("{e}");
    }
    let out = PathBuf::from(args.get(5).map_or("out/comparison-methods", |s| s.as_str()));
    std::fs::create_dir_all(&out).expect("output folder");

    if mode == "mfp" {
        return image_space_by_mfp(replicas);
    }
    let mut scene = Scene::builtin("bumpy").expect("built-in scene");
    scene.camera = scene.camera.with_resolution(128, 96);
    let g = GBuffer::render(&scene, FRAME);
    let regions = Regions::classify(&scene, &g, 7);
    let pixels: Vec<(Region, Vec<usize>)> = Region::ALL
        .iter()
        .map(|&r| (r, regions.pixels(r)))
        .collect();
    for (r, p) in &pixels {
        println!("region {r}: {} pixels", p.len());
    }
    match mode {
        "image-space" => image_space_bias(&scene, &g, &pixels, replicas),
        "adaptive" => adaptive_efficiency(&scene, &g, &pixels, replicas, &params, &out),
        "both" => {
            image_space_bias(&scene, &g, &pixels, replicas);
            adaptive_efficiency(&scene, &g, &pixels, replicas, &params, &out);
        }
        _ => panic!("{usage}"),
    }
}

/// Image-space against the path tracer with the dipole profile, per region.
fn image_space_bias(scene: &Scene, g: &GBuffer, pixels: &[(Region, Vec<usize>)], replicas: u32) {
    let t = std::time::Instant::now();
    let dipole = PtSettings {
        profile: ProfileKind::Dipole,
        ..PtSettings::default()
    };
    let dipole_batches = reference_batches(scene, g, &dipole, 1_000_001);
    println!("dipole reference: {:.1?}", t.elapsed());
    let lum = |c: DVec3| luminance(c.as_vec3()) as f64;
    let settings = ImageSpaceSettings::default();
    let mut entries = EntryCounts::default();
    let is_lum: Vec<Vec<f64>> = (0..replicas)
        .map(|r| {
            let f = image_space::render(scene, g, &settings, r as u64 + 1, IMAGE_SPACE_SPP);
            assert_eq!(f.image.nonfinite, 0);
            entries.samples += f.entries.samples;
            entries.off_screen += f.entries.off_screen;
            entries.occluded += f.entries.occluded;
            entries.outside += f.entries.outside;
            entries.edge_on += f.entries.edge_on;
            f.image
                .pixels
                .iter()
                .map(|p| luminance(p.as_vec3()) as f64)
                .collect()
        })
        .collect();
    let total = entries.samples as f64;
    println!(
        "\nimage-space ({IMAGE_SPACE_SPP} passes of {} light, {} importance + {} uniform samples; \
         {replicas} replicas) vs pt with the dipole profile ({} spp):",
        settings.irradiance_samples,
        settings.importance_samples,
        settings.uniform_samples,
        REFERENCE_BATCHES * REFERENCE_SPP
    );
    println!(
        "entry samples: {:.1}% off screen, {:.1}% occluded or not on the object, {:.1}% beyond r_max, {:.2}% edge-on",
        100.0 * entries.off_screen as f64 / total,
        100.0 * entries.occluded as f64 / total,
        100.0 * entries.outside as f64 / total,
        100.0 * entries.edge_on as f64 / total
    );
    println!("| region | relative bias | 99% CI | verdict (δ = 1%) |\n|---|---|---|---|");
    for (region, p) in pixels {
        let estimate =
            Summary::from_samples(&is_lum.iter().map(|l| region_mean(l, p)).collect::<Vec<_>>());
        // The reference's region mean over its independent batches.
        let reference = Summary::from_samples(
            &dipole_batches
                .iter()
                .map(|b| region_mean(&b.iter().map(|&c| lum(c)).collect::<Vec<_>>(), p))
                .collect::<Vec<_>>(),
        );
        let e = equivalence(&estimate, &reference, 0.01, 0.99);
        println!(
            "| {region} | {:+.2}% | [{:+.2}%, {:+.2}%] | {:?} |",
            100.0 * e.relative_bias,
            100.0 * e.ci_low,
            100.0 * e.ci_high,
            e.verdict
        );
    }
}

/// Image-space against the dipole path tracer per channel over the translucent pixels of the
/// `mfp-*` scenes (bumpy with ℓ scaled by 0.25, 1, 4) at 64×48, frame 15: the bias from entry
/// points the image cannot show grows with the profile's reach.
fn image_space_by_mfp(replicas: u32) {
    let dipole = PtSettings {
        profile: ProfileKind::Dipole,
        ..PtSettings::default()
    };
    println!("| scene | channel | relative bias | 99% CI |\n|---|---|---|---|");
    for name in ["mfp-0.25", "mfp-1", "mfp-4"] {
        let mut scene = Scene::builtin(name).expect("built-in scene");
        scene.camera = scene.camera.with_resolution(64, 48);
        let g = GBuffer::render(&scene, FRAME);
        let translucent = Regions::classify(&scene, &g, 7).pixels(Region::Translucent);
        let region_mean = |img: &[DVec3]| {
            translucent.iter().map(|&p| img[p]).sum::<DVec3>() / translucent.len() as f64
        };
        let reference: Vec<DVec3> = reference_batches(&scene, &g, &dipole, 1_000_003)
            .iter()
            .map(|b| region_mean(b))
            .collect();
        let estimates: Vec<DVec3> = (0..replicas)
            .map(|r| {
                let f = image_space::render(
                    &scene,
                    &g,
                    &ImageSpaceSettings::default(),
                    r as u64 + 1,
                    8,
                );
                region_mean(&f.image.pixels)
            })
            .collect();
        for c in 0..3 {
            let summary =
                |v: &[DVec3]| Summary::from_samples(&v.iter().map(|x| x[c]).collect::<Vec<_>>());
            let e = equivalence(&summary(&estimates), &summary(&reference), 0.01, 0.99);
            println!(
                "| {name} | {c} | {:+.2}% | [{:+.2}%, {:+.2}%] |",
                100.0 * e.relative_bias,
                100.0 * e.ci_low,
                100.0 * e.ci_high
            );
        }
    }
}

/// Adaptive against fixed counts of the same estimator, per region.
fn adaptive_efficiency(
    scene: &Scene,
    g: &GBuffer,
    pixels: &[(Region, Vec<usize>)],
    replicas: u32,
    params: &AdaptiveParams,
    out: &std::path::Path,
) {
    let t = std::time::Instant::now();
    let burley_batches = reference_batches(scene, g, &PtSettings::default(), 1_000_002);
    println!("\nBurley reference: {:.1?}", t.elapsed());
    let channel = |c: usize| move |x: DVec3| x[c];
    let moments: Vec<(Vec<f64>, Vec<f64>)> = (0..3)
        .map(|c| batch_moments(&burley_batches, channel(c)))
        .collect();
    let perceptual = |c: DVec3| perceptual_luminance(c.as_vec3()) as f64;
    let (ref_perceptual, ref_perceptual_var) = batch_moments(&burley_batches, perceptual);
    let translucent = &pixels[0].1;
    let mut last_counts = None;
    let adaptive_runs: Vec<(Vec<DVec3>, f64)> = (0..replicas)
        .map(|r| {
            let mut per_frame = Vec::new();
            let last = adaptive::run(scene, params, r as u64 + 101, FRAME + 1, |f| {
                let g = GBuffer::render(scene, f.frame);
                let (n, sum) = g
                    .pixels
                    .iter()
                    .zip(&f.counts)
                    .filter(|(x, _)| x.is_some_and(|x| x.object == 0))
                    .fold((0u64, 0u64), |(n, s), (_, c)| (n + 1, s + *c as u64));
                per_frame.push(sum as f64 / n as f64);
            })
            .expect("frames");
            if r == 0 {
                println!(
                    "adaptive mean count per translucent pixel, frames 0–15 (replica 0): {}",
                    per_frame
                        .iter()
                        .map(|c| format!("{c:.1}"))
                        .collect::<Vec<_>>()
                        .join(" ")
                );
            }
            assert_eq!(last.image.nonfinite, 0);
            let mean_count = translucent
                .iter()
                .map(|&p| last.counts[p] as f64)
                .sum::<f64>()
                / translucent.len() as f64;
            last_counts = Some(last.count_image());
            (last.image.pixels, mean_count)
        })
        .collect();
    let mean_count = Summary::from_samples(&adaptive_runs.iter().map(|r| r.1).collect::<Vec<_>>());
    let fixed_spp = mean_count.mean.round() as u32;
    println!(
        "adaptive ({replicas} replicas × 16 frames, {:.1?}): mean count at frame 15 over translucent pixels {:.2} ± {:.2}",
        t.elapsed(),
        mean_count.mean,
        mean_count.std_err
    );
    let xie = params.pt_settings();
    let fixed = |spp: u32| -> Vec<Vec<DVec3>> {
        (0..replicas)
            .map(|r| pt::render(scene, g, &xie, r as u64 + 201, 0, spp).pixels)
            .collect()
    };
    let fixed_runs = [
        (fixed_spp, fixed(fixed_spp)),
        (params.b_max, fixed(params.b_max)),
    ];

    // Squared error per pixel minus the reference's own variance (both estimators unbiased).
    let rgb_error = |img: &[DVec3], p: usize| {
        (0..3)
            .map(|c| (img[p][c] - moments[c].0[p]).powi(2) - moments[c].1[p])
            .sum::<f64>()
    };
    let perceptual_error = |img: &[DVec3], p: usize| {
        (perceptual(img[p]) - ref_perceptual[p]).powi(2) - ref_perceptual_var[p]
    };
    let adaptive_images: Vec<&[DVec3]> = adaptive_runs.iter().map(|r| r.0.as_slice()).collect();
    for (spp, runs) in &fixed_runs {
        println!(
            "\nadaptive vs fixed {spp} spp (pt, g(ξ) radii), frame 15, MSE over the region, \
             ratio > 1 favours adaptive (95% CI):"
        );
        println!(
            "| region | metric | MSE fixed / adaptive | efficiency ratio (cost-normalised) |\n|---|---|---|---|"
        );
        let fixed_images: Vec<&[DVec3]> = runs.iter().map(|r| r.as_slice()).collect();
        for (region, p) in pixels {
            for (metric, err) in [
                ("linear RGB", &rgb_error as &dyn Fn(&[DVec3], usize) -> f64),
                ("Y^(1/2.2)", &perceptual_error),
            ] {
                let mse = |images: &[&[DVec3]]| {
                    let per_replica: Vec<f64> = images
                        .iter()
                        .map(|img| p.iter().map(|&q| err(img, q)).sum::<f64>() / p.len() as f64)
                        .collect();
                    Summary::from_samples(&per_replica)
                };
                let (r, lo, hi) = ratio(&mse(&fixed_images), &mse(&adaptive_images));
                let cost = *spp as f64 / mean_count.mean;
                println!(
                    "| {region} | {metric} | {r:.3} [{lo:.3}, {hi:.3}] | {:.3} [{:.3}, {:.3}] |",
                    r * cost,
                    lo * cost,
                    hi * cost
                );
            }
        }
    }
    // The controller's own goal: per-pixel variance of the frame's perceptual value ≤ σ0².
    let over_target = |images: &[&[DVec3]]| {
        let over = translucent
            .iter()
            .filter(|&&q| {
                let values: Vec<f64> = images.iter().map(|img| perceptual(img[q])).collect();
                Summary::from_samples(&values).variance > params.target_variance as f64
            })
            .count();
        100.0 * over as f64 / translucent.len() as f64
    };
    println!(
        "\ntranslucent pixels whose Y^(1/2.2) variance across the {replicas} replicas exceeds σ0² = {}: \
         adaptive {:.1}%, fixed {fixed_spp} spp {:.1}%, fixed {} spp {:.1}%",
        params.target_variance,
        over_target(&adaptive_images),
        over_target(
            &fixed_runs[0]
                .1
                .iter()
                .map(|r| r.as_slice())
                .collect::<Vec<_>>()
        ),
        params.b_max,
        over_target(
            &fixed_runs[1]
                .1
                .iter()
                .map(|r| r.as_slice())
                .collect::<Vec<_>>()
        ),
    );
    if let Some(counts) = last_counts {
        let image = engine::Image {
            width: counts.width,
            height: counts.height,
            pixels: counts
                .pixels
                .iter()
                .map(|c| Vec3::splat((c.x / params.b_max as f64) as f32))
                .collect(),
        };
        let path = out.join("adaptive-counts.png");
        match image.write_png(&path) {
            Ok(()) => println!("\nsample-count map: {}", path.display()),
            Err(e) => eprintln!("{e}"),
        }
    }
}
