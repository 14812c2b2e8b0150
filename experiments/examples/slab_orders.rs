//! Scattering orders of `single-scatter` [000] against the volumetric random walk on a scene's
//! translucent pixels (issue 13): the walk's radiance split by collisions (0, 1, ≥ 2) beside
//! single-scatter's zero, single and multiple (`R − R1` diffusion) terms, and the path-traced
//! BSSRDF with the full profile `R`; region means with 95% CIs over replicas (seed `i` for
//! replica `i`, each method's own streams). It tells a model error of the diffusion term from a
//! defect of the path-traced orders.
//!
//! `cargo run --release -p experiments --example slab_orders -- [scene] [WxH] [replicas] [spp]`
//! (defaults: `slab 40x30 8 32`, frame 15).

use glam::DVec3;
use rayon::prelude::*;
use sss::integrator::single_scatter::{self, SingleScatterSettings};
use sss::random_walk::{Medium, WalkEnd, WalkSettings, estimate_exitant_with};
use sss::scene::{GBuffer, Scene};

use lab::regions::{Region, Regions};
use methods::random_walk::PixelWalk;
use methods::single_scatter::exit_lighting;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let name = args.get(1).map_or("slab", |s| s.as_str());
    let size = args.get(2).map_or("40x30", |s| s.as_str());
    let replicas: u64 = args.get(3).map_or(8, |s| s.parse().unwrap());
    let spp: u32 = args.get(4).map_or(16, |s| s.parse().unwrap());
    let (w, h) = size.split_once('x').unwrap();
    let mut scene = Scene::builtin(name).unwrap();
    scene.camera = scene
        .camera
        .with_resolution(w.parse().unwrap(), h.parse().unwrap());
    let frame = 15;
    let gbuffer = GBuffer::render(&scene, frame);
    let regions = Regions::classify(&scene, &gbuffer, 0x5E61);
    let pixels = regions.pixels(Region::Translucent);
    let media = Medium::of_scene(&scene).unwrap();
    let settings = SingleScatterSettings::default();
    // Per replica: [walk 0, walk 1, walk ≥2, ss zero, ss single, ss multiple], region means.
    let rows: Vec<[DVec3; 7]> = (0..replicas)
        .map(|seed| {
            let sums: Vec<[DVec3; 7]> = pixels
                .par_iter()
                .map(|&index| {
                    let g = gbuffer.pixels[index].as_ref().unwrap();
                    let material = scene.objects[g.object as usize].material as usize;
                    let medium = media[material].unwrap();
                    let PixelWalk {
                        boundary,
                        n1,
                        lighting,
                        mut stream,
                    } = PixelWalk::new(&scene, g, index as u32, frame, seed);
                    let mut out = [DVec3::ZERO; 7];
                    for _ in 0..spp {
                        let s = estimate_exitant_with(
                            &boundary,
                            &medium,
                            g.position,
                            n1,
                            g.view,
                            &lighting,
                            &WalkSettings::default(),
                            &mut stream,
                        );
                        let order = match s.end {
                            WalkEnd::Exited(exit) => exit.scatter_count.min(2) as usize,
                            _ => 2,
                        };
                        out[order] += s.radiance.as_dvec3();
                    }
                    let shading = single_scatter::Shading::new(&scene, &media, g);
                    let ss_lighting = exit_lighting(&scene, index as u32, frame, seed);
                    let mut hits = Vec::new();
                    for sample in 0..spp {
                        let mut rng =
                            single_scatter::sample_stream(index as u32, frame, sample, seed);
                        let o = single_scatter::estimate(
                            &scene,
                            &shading,
                            &settings,
                            &ss_lighting,
                            &mut rng,
                            &mut hits,
                        );
                        out[3] += o.zero.as_dvec3();
                        out[4] += o.single.as_dvec3();
                        out[5] += o.multiple.as_dvec3();
                    }
                    let pt_shading = sss::integrator::pt::Shading::new(&scene, g);
                    for sample in 0..spp {
                        let mut rng =
                            sss::integrator::pt::sample_stream(index as u32, frame, sample, seed);
                        out[6] += sss::integrator::pt::estimate(
                            &scene,
                            &pt_shading,
                            &settings.diffusion,
                            &mut rng,
                            &mut hits,
                        )
                        .as_dvec3();
                    }
                    out.map(|v| v / spp as f64)
                })
                .collect();
            let mut mean = [DVec3::ZERO; 7];
            for s in &sums {
                for k in 0..7 {
                    mean[k] += s[k] / sums.len() as f64;
                }
            }
            mean
        })
        .collect();
    let names = [
        "walk 0",
        "walk 1",
        "walk ≥2",
        "ss zero",
        "ss single",
        "ss multiple",
        "pt (full R)",
    ];
    println!(
        "{name} {size}, {} translucent pixels, {replicas} replicas × {spp} spp, frame {frame}",
        pixels.len()
    );
    let n = rows.len() as f64;
    for k in 0..7 {
        let m = rows.iter().map(|r| r[k]).sum::<DVec3>() / n;
        let var = rows.iter().map(|r| (r[k] - m) * (r[k] - m)).sum::<DVec3>() / (n - 1.0);
        let half = 1.96 * (var / n).map(f64::sqrt);
        println!(
            "{:<12} R {:.5} ± {:.5}  G {:.5} ± {:.5}  B {:.5} ± {:.5}",
            names[k], m.x, half.x, m.y, half.y, m.z, half.z
        );
    }
}
