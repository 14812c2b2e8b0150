//! `cargo bench -p sss --bench frame`: time of one 512×512, 1-spp path-tracing baseline frame on
//! the `bumpy` built-in scene (one large quad light), G-buffer excluded, both hit policies.
//! Prints a table; not a test.

use std::time::Instant;

use sss::integrator::pt::render;
use sss::integrator::{HitPolicy, PtSettings};
use sss::scene::{GBuffer, Scene};

fn main() {
    let mut scene = Scene::builtin("bumpy").expect("built-in scene `bumpy`");
    scene.camera = scene.camera.with_resolution(512, 512);
    let start = Instant::now();
    let gbuffer = GBuffer::render(&scene, 0);
    let gbuffer_ms = start.elapsed().as_secs_f64() * 1e3;
    let covered = gbuffer.pixels.iter().filter(|p| p.is_some()).count();
    println!(
        "bumpy 512×512, {} rayon threads; G-buffer {gbuffer_ms:.1} ms, {covered} pixels with a primary hit",
        rayon::current_num_threads()
    );
    println!("| hit policy | frame (median of 5) | min | NaN/inf samples |");
    println!("|---|---|---|---|");
    for hits in [HitPolicy::All, HitPolicy::UniformOne] {
        let settings = PtSettings {
            hits,
            ..PtSettings::default()
        };
        render(&scene, &gbuffer, &settings, 0, 0, 1);
        let mut times = Vec::new();
        let mut nonfinite = 0;
        for frame_seed in 1..=5 {
            let start = Instant::now();
            let image = render(&scene, &gbuffer, &settings, frame_seed, 0, 1);
            times.push(start.elapsed().as_secs_f64() * 1e3);
            nonfinite += image.nonfinite;
        }
        times.sort_by(f64::total_cmp);
        println!(
            "| {hits:?} | {:.1} ms | {:.1} ms | {nonfinite} |",
            times[2], times[0]
        );
    }
}
