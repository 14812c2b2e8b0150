//! Per-pass time of every preset and of the 1-spp path-traced baseline on the built-in `bumpy`
//! scene (one large quad light), reservoir bytes per pixel, and the cost of one spatial
//! neighbour as a fraction of a path-traced sample.
//!
//! `cargo bench -p engine --bench pipeline`. The path tracer and the presets run in turn, round
//! after round (`RESHIFT_BENCH_ROUNDS`, default 3), so a change in the machine's load falls on
//! all of them alike. Times are the process's CPU time ([`engine::clock`]; both rayon threads'
//! time, so about twice the wall time on two busy threads), which other processes do not add to;
//! the last round's wall time is printed beside it.
//!
//! **Neighbour cost**, as a fraction of `pt`'s traced part per sample (G-buffer excluded), per
//! round: the preset's spatial passes' CPU time per pixel-neighbour ("pass": every spatial
//! neighbour the passes take, with the passes' per-pixel work), and the marginal cost of a
//! neighbour ("marginal": the spatial passes' time with every pass taking twice its neighbours,
//! less their time as registered, per added neighbour), which is the shift, target and MIS
//! back-shift a neighbour adds. Printed as means over rounds with 95% t intervals (geometric, on
//! the per-round log ratios, where every round's ratio is positive).
//!
//! **Reciprocal pairs.** Every preset also runs with `/pairs=reciprocal` (`engine::reciprocal`:
//! a pair's two shifts serve both pixels) in the same rounds, and a third table prints both
//! marginal costs and their ratio, reciprocal / independent, per round (the path-traced sample
//! cancels), with its geometric 95% t interval.
//!
//! Environment: `RESHIFT_BENCH_FRAMES` (1..=16, default 4; frame 0 has no temporal history and
//! the table averages all frames), `RESHIFT_BENCH_SIZE` (`N` for N×N, or `WxH`; default 512),
//! `RESHIFT_BENCH_PRESETS` (comma-separated preset names, default all), `RESHIFT_BENCH_SHADE=all`
//! (every preset with Rao-Blackwellised shading, `<preset>/shade=all`) and
//! `RESHIFT_BENCH_NEIGHBOURS=<n>` (every spatial pass with `n` neighbours,
//! `<preset>/neighbours=<n>`; the marginal cost then doubles `n`).

mod common;

use engine::{PassSpec, PixelReservoir, Preset, Run, RunConfig, run, run_pt};
use restir::stats::student_t_quantile;
use shifts::SssSample;
use shifts::preset::Pairs;
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

/// CPU seconds of the passes whose label `keep` accepts, summed over the run's frames.
fn cpu_seconds(run: &Run, keep: impl Fn(&str) -> bool) -> f64 {
    run.timings
        .iter()
        .filter(|t| keep(&t.label))
        .map(|t| t.cpu_seconds.unwrap_or(f64::NAN))
        .sum()
}

fn print_run(method: &str, run: &Run) {
    let frames = run.frames.len().max(1) as f64;
    let ms = |s: f64| 1e3 * s / frames;
    for t in &run.timings {
        println!(
            "| {method} | {} | {:.1} | {:.1} |",
            t.label,
            ms(t.cpu_seconds.unwrap_or(f64::NAN)),
            ms(t.seconds)
        );
    }
    let wall: f64 = run.timings.iter().map(|t| t.seconds).sum();
    println!(
        "| {method} | **total** | **{:.1}** | **{:.1}** |",
        ms(cpu_seconds(run, |_| true)),
        ms(wall)
    );
}

/// The spatial neighbours a pixel takes over all of `preset`'s spatial passes.
fn spatial_neighbours(preset: &Preset) -> u32 {
    preset
        .passes
        .iter()
        .map(|p| match p {
            PassSpec::Spatial { neighbours, .. } => *neighbours,
            _ => 0,
        })
        .sum()
}

/// `preset` with every spatial pass taking twice as many neighbours as its largest pass.
fn doubled(preset: &Preset) -> Preset {
    let most = preset
        .passes
        .iter()
        .map(|p| match p {
            PassSpec::Spatial { neighbours, .. } => *neighbours,
            _ => 0,
        })
        .max()
        .unwrap_or(0);
    preset.clone().with_neighbours(2 * most)
}

/// CPU seconds of `result`'s spatial passes.
fn spatial_seconds(result: &Run) -> f64 {
    cpu_seconds(result, |l| l.starts_with("spatial"))
}

/// The mean of `ratios` with a 95% t interval (`None` for one round): geometric, on their
/// logs, where all are positive; arithmetic otherwise (a marginal cost lost in noise can be ≤ 0).
fn interval(ratios: &[f64]) -> (f64, Option<(f64, f64)>) {
    let log = ratios.iter().all(|&r| r > 0.0);
    let values: Vec<f64> = ratios
        .iter()
        .map(|&r| if log { r.ln() } else { r })
        .collect();
    let back = |v: f64| if log { v.exp() } else { v };
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    if values.len() < 2 {
        return (back(mean), None);
    }
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
    let half = student_t_quantile(0.975, n - 1.0) * (var / n).sqrt();
    (back(mean), Some((back(mean - half), back(mean + half))))
}

fn main() -> Result<(), String> {
    let frames = common::frames()?;
    let text = std::env::var("RESHIFT_BENCH_SIZE").unwrap_or_else(|_| "512".into());
    let (width, height) = match text.parse::<u32>() {
        Ok(n) if n > 0 => (n, n),
        _ => common::size(&text, "RESHIFT_BENCH_SIZE")
            .map_err(|_| format!("RESHIFT_BENCH_SIZE = {text:?}: need N or WxH, positive"))?,
    };
    let rounds = env_u32("RESHIFT_BENCH_ROUNDS", 3)?;
    let mut scene = Scene::builtin("bumpy").ok_or("built-in scene `bumpy` is missing")?;
    scene.camera = scene.camera.with_resolution(width, height);
    let presets = common::presets()?;
    let config = RunConfig {
        seed: 0,
        frames,
        collect_diagnostics: false,
    };
    println!(
        "bumpy {width}×{height}, {frames} frames, {} threads, {rounds} rounds; ms per frame of the \
         last round (CPU: the process's CPU time, all threads; wall beside it)",
        rayon::current_num_threads()
    );
    // Per preset and pairing (independent, reciprocal), per round: (pass, marginal) neighbour
    // cost over a path-traced sample.
    let pairings = [Pairs::Independent, Pairs::Reciprocal];
    let variants: Vec<Preset> = presets
        .iter()
        .flat_map(|preset| {
            pairings.map(|pairs| match pairs {
                Pairs::Independent => preset.clone(),
                _ => Preset {
                    name: format!("{}/pairs={}", preset.name, pairs.name()),
                    ..preset.clone().with_pairs(pairs)
                },
            })
        })
        .collect();
    let mut ratios = vec![(Vec::new(), Vec::new()); variants.len()];
    let mut last = Vec::new();
    for _ in 0..rounds {
        last.clear();
        let pt = run_pt(&scene, 1, &config);
        let pt_sample = cpu_seconds(&pt, |l| l == "pt");
        for (preset, (pass, marginal)) in variants.iter().zip(&mut ratios) {
            let run_preset = |p: &Preset| run(&scene, p, &config).map_err(|e| e.to_string());
            let result = run_preset(preset)?;
            let more = doubled(preset);
            let more_result = run_preset(&more)?;
            let (n, n_more) = (spatial_neighbours(preset), spatial_neighbours(&more));
            pass.push(spatial_seconds(&result) / n.max(1) as f64 / pt_sample);
            let added = (spatial_seconds(&more_result) - spatial_seconds(&result))
                / n_more.saturating_sub(n).max(1) as f64;
            marginal.push(added / pt_sample);
            last.push(result);
        }
        last.insert(0, pt);
    }
    println!("| method | pass | CPU ms/frame | wall ms/frame |\n|---|---|---:|---:|");
    print_run("pt 1 spp", &last[0]);
    for (preset, result) in variants.iter().zip(&last[1..]) {
        print_run(&format!("restir:{}", preset.name), result);
    }
    println!(
        "\none spatial neighbour / one path-traced sample (CPU time; mean over rounds, geometric \
         where every round is positive, 95% t CI)\n| preset | neighbours | pass | 95% CI | marginal | 95% CI |\n\
         |---|---:|---:|---|---:|---|"
    );
    let show = |ratios: &[f64]| {
        let (mean, ci) = interval(ratios);
        let ci = ci.map_or("—".into(), |(lo, hi)| format!("[{lo:.3}, {hi:.3}]"));
        format!("{mean:.3} | {ci}")
    };
    for (preset, (pass, marginal)) in variants.iter().zip(&ratios) {
        println!(
            "| restir:{} | {} | {} | {} |",
            preset.name,
            spatial_neighbours(preset),
            show(pass),
            show(marginal)
        );
    }
    println!(
        "\nmarginal cost of one spatial neighbour, independent and reciprocal pairs (over one \
         path-traced sample), and reciprocal / independent per round (geometric mean, 95% t CI)\n\
         | preset | independent | 95% CI | reciprocal | 95% CI | reciprocal / independent | 95% CI |\n\
         |---|---:|---|---:|---|---:|---|"
    );
    for (preset, pair) in presets.iter().zip(ratios.chunks(pairings.len())) {
        let (independent, reciprocal) = (&pair[0].1, &pair[1].1);
        let per_round: Vec<f64> = reciprocal
            .iter()
            .zip(independent)
            .map(|(r, i)| r / i)
            .collect();
        println!(
            "| restir:{} | {} | {} | {} |",
            preset.name,
            show(independent),
            show(reciprocal),
            show(&per_round)
        );
    }
    println!(
        "\nreservoir: {} bytes per pixel per buffer (sample {} B + W, c, flag, pad); the CPU \
         backend holds 3 buffers (ping, pong, previous frame)",
        PixelReservoir::BYTES,
        SssSample::BYTES
    );
    Ok(())
}
