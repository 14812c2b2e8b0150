//! Per-pass time of every preset and of the 1-spp path-traced baseline at 512×512 on the
//! built-in `bumpy` scene (one large quad light), and reservoir bytes per pixel.
//!
//! `cargo bench -p engine --bench pipeline`. Frames default to 4 (frame 0 has no temporal
//! history; the table averages over all frames run); set `RESHIFT_BENCH_FRAMES` (1..=16) and
//! `RESHIFT_BENCH_SIZE` to change them.

use engine::{PixelReservoir, Preset, Run, RunConfig, run, run_pt};
use shifts::SssSample;
use sss::scene::Scene;

fn env_u32(name: &str, default: u32) -> Result<u32, String> {
    match std::env::var(name) {
        Err(_) => Ok(default),
        Ok(v) => match v.parse::<u32>() {
            Ok(n) if n > 0 => Ok(n),
            _ => Err(format!("{name} = {v:?}: need a positive integer")),
        },
    }
}

fn print_run(method: &str, run: &Run) {
    let frames = run.frames.len().max(1) as f64;
    let total: f64 = run.timings.iter().map(|t| t.seconds).sum::<f64>() / frames;
    for t in &run.timings {
        println!(
            "| {method} | {} | {:.1} |",
            t.label,
            1e3 * t.seconds / frames
        );
    }
    println!("| {method} | **total** | **{:.1}** |", 1e3 * total);
}

fn main() -> Result<(), String> {
    let frames = env_u32("RESHIFT_BENCH_FRAMES", 4)?.min(16);
    let size = env_u32("RESHIFT_BENCH_SIZE", 512)?;
    let mut scene = Scene::builtin("bumpy").ok_or("built-in scene `bumpy` is missing")?;
    scene.camera = scene.camera.with_resolution(size, size);
    let config = RunConfig {
        seed: 0,
        frames,
        collect_diagnostics: false,
    };
    println!(
        "bumpy {size}×{size}, {frames} frames, {} threads; ms per frame",
        rayon::current_num_threads()
    );
    println!("| method | pass | ms/frame |\n|---|---|---|");
    print_run("pt 1 spp", &run_pt(&scene, 1, &config));
    for preset in Preset::all() {
        let result = run(&scene, &preset, &config).map_err(|e| e.to_string())?;
        print_run(&format!("restir:{}", preset.name), &result);
    }
    println!(
        "reservoir: {} bytes per pixel per buffer (sample {} B + W, c, flag, pad); the CPU \
         backend holds 3 buffers (ping, pong, previous frame)",
        PixelReservoir::BYTES,
        SssSample::BYTES
    );
    Ok(())
}
