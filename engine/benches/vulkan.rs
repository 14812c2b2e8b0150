//! Per-pass GPU time (timestamp queries around each dispatch) of every preset on the built-in
//! `bumpy` scene at 512×512 and 1920×1080, on the Vulkan device the backend picks
//! (`RESHIFT_VULKAN_DEVICE` chooses another). Without Vulkan it says why and exits cleanly.
//!
//! `cargo bench -p engine --bench vulkan`. Frames default to 4 (frame 0 has no temporal
//! history; the table averages over all frames run); `RESHIFT_BENCH_FRAMES` (1..=16) changes
//! them, `RESHIFT_BENCH_SIZES` (e.g. `512x512,1920x1080`) the resolutions, and
//! `RESHIFT_BENCH_SHADE=all` runs every preset with Rao-Blackwellised shading (`<preset>/shade=all`),
//! `RESHIFT_BENCH_NEIGHBOURS=<n>` with `n` spatial neighbours (`<preset>/neighbours=<n>`), and
//! `RESHIFT_BENCH_PRESETS` (e.g. `hybrid,sequential`) only the presets it names.

use engine::vulkan::VulkanError;
use engine::{Backend, PipelineError, RunConfig};
use sss::scene::Scene;

mod common;

use common::{frames, presets};

fn sizes() -> Result<Vec<(u32, u32)>, String> {
    let text = std::env::var("RESHIFT_BENCH_SIZES").unwrap_or_else(|_| "512x512,1920x1080".into());
    text.split(',')
        .map(|s| common::size(s, "RESHIFT_BENCH_SIZES"))
        .collect()
}

fn main() -> Result<(), String> {
    let (frames, sizes, presets) = (frames()?, sizes()?, presets()?);
    let backend = match Backend::vulkan(None, false) {
        Ok(b) => b,
        Err(e) => {
            println!("vulkan bench skipped: {e}");
            return Ok(());
        }
    };
    let timestamps = backend
        .renderer()
        .is_some_and(|r| r.context().has_timestamps());
    if !timestamps {
        println!("vulkan bench skipped: {backend} writes no timestamps on its compute queue");
        return Ok(());
    }
    println!("{backend}: bumpy, {frames} frames, GPU ms per frame (timestamps)");
    println!("| resolution | preset | pass | ms/frame |\n|---|---|---|---:|");
    for (width, height) in sizes {
        let mut scene = Scene::builtin("bumpy").ok_or("built-in scene `bumpy` is missing")?;
        scene.camera = scene.camera.with_resolution(width, height);
        let config = RunConfig {
            seed: 0,
            frames,
            collect_diagnostics: false,
        };
        for preset in &presets {
            let run = match backend.run(&scene, preset, &config) {
                Ok(run) => run,
                // lavapipe's maxStorageBufferRange is 128 MiB: 80-byte-per-pixel buffers at
                // 1920×1080 do not fit, GPUs allow 4 GiB.
                Err(PipelineError::Vulkan(e @ VulkanError::BufferTooLarge { .. })) => {
                    println!("| {width}×{height} | (all) | skipped: {e} | |");
                    break;
                }
                Err(e) => return Err(format!("{} at {width}×{height}: {e}", preset.name)),
            };
            let per_frame = |s: f64| 1e3 * s / frames as f64;
            for t in &run.timings {
                println!(
                    "| {width}×{height} | {} | {} | {:.2} |",
                    preset.name,
                    t.label,
                    per_frame(t.seconds)
                );
            }
            let total: f64 = run.timings.iter().map(|t| t.seconds).sum();
            println!(
                "| {width}×{height} | {} | **total** | **{:.2}** |",
                preset.name,
                per_frame(total)
            );
        }
    }
    Ok(())
}
