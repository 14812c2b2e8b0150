//! What the GLSL twins cost to compile on the device. Lavapipe compiles a compute pipeline in
//! two steps: SPIR-V → NIR at pipeline creation, NIR → LLVM → machine code at the first dispatch
//! (llvmpipe builds shader variants lazily). So this bench measures, on a fresh device per
//! repeat, the process CPU seconds of (1) creating every pass pipeline (not the kernels of the
//! `methods` crate) and (2) a first
//! one-frame run of the `sequential` and `hybrid` presets at 8×8 (every pass kernel's first
//! dispatch) minus the same run repeated warm. It prints mean ± sd over
//! `RESHIFT_BENCH_REPEATS` (default 3) and the SPIR-V sizes. Run it with Mesa's disk cache
//! off, or every repeat after the first is a cache hit:
//!
//! `MESA_SHADER_CACHE_DISABLE=true cargo bench -p engine --bench shader_compile`
//!
//! CPU seconds, not wall seconds: they include lavapipe's compiler threads and do not grow when
//! other processes share the machine. Without Vulkan it says why and exits cleanly.

use engine::vulkan::{
    CANDIDATES, Context, GBUFFER, Kernel, Renderer, SHADE, SPATIAL, Shader, TEMPORAL,
};
use engine::{Preset, RunConfig};
use sss::scene::Scene;

/// CPU seconds of the process, all threads (`/proc/self/stat` utime + stime, clock ticks of
/// 10 ms). Lavapipe compiles on its own threads.
fn cpu_seconds() -> Result<f64, String> {
    let stat = std::fs::read_to_string("/proc/self/stat").map_err(|e| e.to_string())?;
    let after = stat.rsplit_once(')').ok_or("unreadable /proc/self/stat")?.1;
    let fields: Vec<&str> = after.split_whitespace().collect();
    // `after` starts at field 3 (state), so utime (14) and stime (15) are at 11 and 12.
    let ticks = |i: usize| fields.get(i).and_then(|f| f.parse::<f64>().ok());
    match (ticks(11), ticks(12)) {
        (Some(u), Some(s)) => Ok((u + s) / 100.0),
        _ => Err("unreadable /proc/self/stat".into()),
    }
}

fn timed<T>(f: impl FnOnce() -> Result<T, String>) -> Result<(T, f64), String> {
    let start = cpu_seconds()?;
    let value = f()?;
    Ok((value, cpu_seconds()? - start))
}

fn mean_sd(v: &[f64]) -> String {
    let n = v.len().max(1) as f64;
    let mean = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
    format!("{mean:.2} ± {:.2}", var.sqrt())
}

const SHADERS: [Shader; 5] = [GBUFFER, CANDIDATES, TEMPORAL, SPATIAL, SHADE];
const PRESETS: [&str; 2] = ["sequential", "hybrid"];

fn main() -> Result<(), String> {
    let repeats = match std::env::var("RESHIFT_BENCH_REPEATS") {
        Err(_) => 3,
        Ok(v) => v
            .parse::<usize>()
            .ok()
            .filter(|&n| n > 0)
            .ok_or_else(|| format!("RESHIFT_BENCH_REPEATS = {v:?}: need a positive integer"))?,
    };
    let device = match Context::new() {
        Ok(c) => c.device().name.clone(),
        Err(e) => {
            println!("shader_compile bench skipped: {e}");
            return Ok(());
        }
    };
    let mut scene = Scene::builtin("bumpy").ok_or("built-in scene `bumpy` is missing")?;
    scene.camera = scene.camera.with_resolution(8, 8);
    let config = RunConfig {
        seed: 0,
        frames: 1,
        collect_diagnostics: false,
    };
    let mut create = vec![Vec::new(); SHADERS.len()];
    let mut first_run = vec![Vec::new(); PRESETS.len()];
    for _ in 0..repeats {
        let context = Context::new().map_err(|e| e.to_string())?;
        for (shader, seconds) in SHADERS.iter().zip(&mut create) {
            let (_, s) =
                timed(|| Kernel::for_shader(&context, *shader).map_err(|e| e.to_string()))?;
            seconds.push(s);
        }
        for (name, seconds) in PRESETS.iter().zip(&mut first_run) {
            let preset = Preset::named(name).ok_or("unknown preset")?;
            // A fresh device: its pipelines are created and compiled anew.
            let mut renderer = Renderer::new(Context::new().map_err(|e| e.to_string())?);
            renderer.upload(&scene).map_err(|e| e.to_string())?;
            let mut run = || {
                timed(|| {
                    renderer
                        .run(&scene, &preset, &config)
                        .map_err(|e| e.to_string())
                })
            };
            let (_, cold) = run()?;
            let (_, warm) = run()?;
            seconds.push(cold - warm);
        }
    }
    let cache = std::env::var("MESA_SHADER_CACHE_DISABLE").unwrap_or_default();
    println!("{device}, {repeats} repeats, MESA_SHADER_CACHE_DISABLE={cache:?}");
    println!("| kernel | SPIR-V bytes | pipeline creation, CPU s |\n|---|---:|---:|");
    for (shader, seconds) in SHADERS.iter().zip(&create) {
        let bytes = shader.spirv().map_err(|e| e.to_string())?.len();
        println!("| {} | {bytes} | {} |", shader.name, mean_sd(seconds));
    }
    println!(
        "\n| preset | first run − warm run (pipelines + first dispatches), CPU s |\n|---|---:|"
    );
    for (name, seconds) in PRESETS.iter().zip(&first_run) {
        println!("| {name} | {} |", mean_sd(seconds));
    }
    Ok(())
}
