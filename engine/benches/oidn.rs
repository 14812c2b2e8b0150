//! OIDN's cost per frame with its filter kept against a filter created for the call, side by
//! side: `cargo bench -p engine --bench oidn`. One 1-spp `bumpy` frame with its guide (default
//! 512×384, `RESHIFT_BENCH_SIZE=WxH`), denoised round after round (`RESHIFT_BENCH_ROUNDS`,
//! default 5): "kept" is a call at the frame's size right after another at that size (the
//! library keeps the filter); "created" is a call at that size after calls at two other sizes
//! (one and two rows fewer), which evict it, so the call creates and first commits a new filter.
//! Process CPU time (OIDN's threads are the process's) and wall time per call, means over rounds
//! with 95% t intervals, and the ratio created : kept per round.

mod common;

use engine::clock::Stopwatch;
use engine::denoise::Guide;
use engine::denoise::oidn::{aux_images, library};
use engine::{Backend, Image, RunConfig, run_pt};
use restir::stats::{Summary, student_t_quantile};
use sss::scene::Scene;

/// `mean [lo, hi]` of `xs` with a 95% t interval, scaled by `scale`.
fn interval(xs: &[f64], scale: f64) -> String {
    let s = Summary::from_samples(xs);
    let t = student_t_quantile(0.975, (xs.len().max(2) - 1) as f64);
    let (lo, hi) = (s.mean - t * s.std_err, s.mean + t * s.std_err);
    format!(
        "{:.1} [{:.1}, {:.1}]",
        scale * s.mean,
        scale * lo,
        scale * hi
    )
}

fn main() -> Result<(), String> {
    let (width, height) = match std::env::var("RESHIFT_BENCH_SIZE") {
        Ok(text) => common::size(&text, "RESHIFT_BENCH_SIZE")?,
        Err(_) => (512, 384),
    };
    if height < 3 {
        return Err("RESHIFT_BENCH_SIZE: need a height of at least 3".into());
    }
    let rounds = common::rounds(5)?;
    let oidn = library::shared().map_err(|e| e.to_string())?;
    let mut scene = Scene::builtin("bumpy").ok_or("no built-in scene bumpy")?;
    scene.camera = scene.camera.with_resolution(width, height);
    let guide = Guide::trajectory(&scene, 1).remove(0);
    let config = RunConfig {
        seed: 1,
        frames: 1,
        collect_diagnostics: false,
    };
    let frame = run_pt(&scene, 1, &config).frames.remove(0);
    let mut output = Image::black(width, height);
    // One call on the first `rows` rows of the frame and its guide.
    let mut call = |rows: u32| -> Result<(f64, f64), String> {
        let n = (width * rows) as usize;
        let mut inputs = vec![(c"color", &frame.pixels[..n])];
        inputs.extend(aux_images(&guide).map(|(name, image)| (name, &image[..n])));
        let watch = Stopwatch::start(&Backend::Cpu);
        oidn.run(
            c"RT",
            (width, rows),
            &inputs,
            &[(c"hdr", true), (c"cleanAux", false)],
            &mut output.pixels[..n],
        )
        .map_err(|e| e.to_string())?;
        let time = watch.read();
        Ok((time.seconds, time.wall_seconds))
    };
    let (mut kept, mut created) = ((Vec::new(), Vec::new()), (Vec::new(), Vec::new()));
    call(height)?;
    for _ in 0..rounds {
        let (cpu, wall) = call(height)?;
        kept.0.push(cpu);
        kept.1.push(wall);
        call(height - 1)?;
        call(height - 2)?;
        let (cpu, wall) = call(height)?;
        created.0.push(cpu);
        created.1.push(wall);
    }
    let ratios: Vec<f64> = (created.0.iter().zip(&kept.0))
        .map(|(c, k)| (c / k).ln())
        .collect();
    let s = Summary::from_samples(&ratios);
    let t = student_t_quantile(0.975, (rounds - 1) as f64);
    println!(
        "# OIDN {} on bumpy {width}x{height}, {rounds} rounds",
        oidn.version_string()
    );
    println!("| filter | CPU ms per call | wall ms per call |\n|---|---|---|");
    println!(
        "| kept | {} | {} |",
        interval(&kept.0, 1e3),
        interval(&kept.1, 1e3)
    );
    println!(
        "| created | {} | {} |",
        interval(&created.0, 1e3),
        interval(&created.1, 1e3)
    );
    println!(
        "created : kept (CPU time) {:.2} [{:.2}, {:.2}]",
        s.mean.exp(),
        (s.mean - t * s.std_err).exp(),
        (s.mean + t * s.std_err).exp()
    );
    Ok(())
}
