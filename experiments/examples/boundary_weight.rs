//! What the BSSRDF's boundary weight changes: reshift's normalised dielectric transmittance
//! `F_t(μ) = (1 − F(μ, η)) / (1 − F_dr(η))` (`sss::material::fresnel`) against the weight of
//! paper 001's implementation, Disney's `w(μ) = 1 − ½(1 − μ)⁵` (no normalisation, no ior), at
//! both ends of the path: `S = (A/π) R̄(r) · F_t(μo) F_t(μi)` against `(A/π) R̄(r) · w(μo) w(μi)`.
//!
//! * Both images are the path tracer's (BSSRDF importance sampling, NEE) on the same random
//!   streams (each sample's estimator runs twice on copies of its stream), so each replica's
//!   ratio of region means is paired: replica `k` runs with seed `k`,
//!   its translucent pixels are split into the lab's regions (lit, penumbra, shadowed), and per
//!   region and channel the ratio `mean(w) / mean(F_t)` is averaged over the replicas on the log
//!   scale with its 95% interval ([`lab::uncertainty`]).
//! * Printed: per region and channel (R, G, B, luminance) the ratio and its interval.
//!
//! `cargo run --release -p experiments --example boundary_weight -- [scene] [WxH] [replicas]
//! [spp]` (defaults: `ajax 90x135 16 16`; `ajax` needs the asset directory, `--assets` being a
//! flag of `reshift` only: set `RESHIFT_ASSETS`).

use glam::{DVec3, Vec3};
use lab::regions::{Region, Regions};
use lab::uncertainty::{CONFIDENCE, Estimate};
use rayon::prelude::*;
use sss::bssrdf::contribution;
use sss::color::luminance;
use sss::integrator::PtSettings;
use sss::integrator::pt::{self, Shading, sample_stream};
use sss::scene::{FRAMES, GBuffer, Scene};

/// Disney's diffuse transmission weight `1 − ½ (1 − μ)⁵` of paper 001's implementation.
fn disney_weight(mu: f32) -> f32 {
    let b = (1.0 - mu).clamp(0.0, 1.0);
    1.0 - 0.5 * b.powi(5)
}

/// One pixel's estimate under both weights, `(reshift's, Disney's)`: the estimator twice on
/// copies of one stream, so both draw the same probe, hits and light samples.
fn both(scene: &Scene, shading: &Shading, rng: &mut restir::rng::Stream) -> (Vec3, Vec3) {
    let Shading::Translucent { material, x1, .. } = shading else {
        return (Vec3::ZERO, Vec3::ZERO);
    };
    let mut hits = Vec::new();
    let settings = PtSettings::default();
    let mut copy = rng.clone();
    let reshift = pt::estimate_bssrdf(scene, x1, &settings, rng, &mut hits, |x2, wi, le| {
        contribution(material, x1, x2, wi, le)
    });
    let mu_o = x1.shading_normal.dot(x1.view);
    let disney = pt::estimate_bssrdf(scene, x1, &settings, &mut copy, &mut hits, |x2, wi, le| {
        let mu_i = x2.shading_normal.dot(wi);
        let ft = x1.fresnel_out * x1.fresnel.eval(mu_i);
        let f = contribution(material, x1, x2, wi, le);
        if ft > 0.0 {
            f * (disney_weight(mu_o) * disney_weight(mu_i) / ft)
        } else {
            Vec3::ZERO
        }
    });
    (reshift, disney)
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let arg = |i: usize, default: &str| args.get(i).cloned().unwrap_or(default.into());
    let name = arg(0, "ajax");
    let (w, h) = arg(1, "90x135")
        .split_once('x')
        .map(|(w, h)| (w.parse().unwrap(), h.parse().unwrap()))
        .expect("WxH");
    let replicas: u64 = arg(2, "16").parse().unwrap();
    let spp: u32 = arg(3, "16").parse().unwrap();
    let mut scene = match Scene::named(&name) {
        Some(loaded) => loaded.unwrap_or_else(|e| panic!("{e}")),
        None => Scene::load(std::path::Path::new(&name)).unwrap_or_else(|e| panic!("{e}")),
    };
    scene.camera = scene.camera.with_resolution(w, h);
    let frame = FRAMES - 1;
    let gbuffer = GBuffer::render(&scene, frame);
    let regions = Regions::classify(&scene, &gbuffer, 0);
    let areas = [
        Region::Translucent,
        Region::Lit,
        Region::Penumbra,
        Region::Shadowed,
    ];
    // Per replica, per area: (sum F_t, sum w) over the area's pixels.
    let sums: Vec<Vec<(DVec3, DVec3)>> = (0..replicas)
        .into_par_iter()
        .map(|seed| {
            let mut per_area = vec![(DVec3::ZERO, DVec3::ZERO); areas.len()];
            for (pixel, g) in gbuffer.pixels.iter().enumerate() {
                let Some(g) = g else { continue };
                let shading = Shading::new(&scene, g);
                let (mut a, mut b) = (Vec3::ZERO, Vec3::ZERO);
                for sample in 0..spp {
                    let mut rng = sample_stream(pixel as u32, frame, sample, seed);
                    let (x, y) = both(&scene, &shading, &mut rng);
                    (a, b) = (a + x, b + y);
                }
                for (k, &area) in areas.iter().enumerate() {
                    if regions.contains(area, pixel) {
                        per_area[k].0 += a.as_dvec3();
                        per_area[k].1 += b.as_dvec3();
                    }
                }
            }
            per_area
        })
        .collect();
    println!(
        "{name} at {w}×{h}, frame {frame}, {replicas} replicas × {spp} spp: Disney's weight \
         over reshift's F_t (ratio of region means, {:.0}% interval)",
        100.0 * CONFIDENCE
    );
    println!("| region | pixels | R | G | B | luminance |\n|---|---|---|---|---|---|");
    for (k, area) in areas.iter().enumerate() {
        let channel = |f: &dyn Fn(DVec3) -> f64| -> String {
            let logs: Vec<f64> = sums
                .iter()
                .map(|r| (f(r[k].1) / f(r[k].0)).ln())
                .filter(|v| v.is_finite())
                .collect();
            if logs.len() < 2 {
                return "n/a".into();
            }
            let e = Estimate::mean(&logs);
            let i = e.exp_interval(CONFIDENCE).expect("an interval");
            format!("{:.4} [{:.4}, {:.4}]", e.value.exp(), i.lo, i.hi)
        };
        let count = (0..gbuffer.pixels.len())
            .filter(|&p| regions.contains(*area, p))
            .count();
        println!(
            "| {area} | {count} | {} | {} | {} | {} |",
            channel(&|v| v.x),
            channel(&|v| v.y),
            channel(&|v| v.z),
            channel(&|v| luminance(v.as_vec3()) as f64)
        );
    }
}
