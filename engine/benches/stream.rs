//! Long streams: CPU time per frame and peak memory of a preset's stream at 16 and at 256
//! frames, side by side, on a built-in scene (`bumpy`; `RESHIFT_BENCH_SCENE=passing` for one
//! whose object moves, posed and its BVH rebuilt every frame of its motion). A stream keeps no frame
//! ([`engine::Keep::Last`]), so neither figure should grow with the frame count.
//!
//! `cargo bench -p engine --bench stream`. Each measurement is a child process (this bench run
//! again with `RESHIFT_BENCH_STREAM_CHILD=<frames>`), so that its peak resident memory (Linux
//! `VmHWM`) is its own; the two lengths alternate, round after round (`RESHIFT_BENCH_ROUNDS`,
//! default 3), so a change in the machine's load falls on both. Time is the child's process
//! CPU time over the stream's frames ([`engine::clock`]), G-buffer included; per frame it is
//! printed as the mean over rounds with a 95% t interval, and the ratio of 256 frames' to 16
//! frames' per round as a geometric mean with its interval.
//!
//! Environment: `RESHIFT_BENCH_SCENE` (a built-in scene, default bumpy), `RESHIFT_BENCH_SIZE`
//! (`WxH`, default 128x96) and the presets' knobs the other
//! benches take (`RESHIFT_BENCH_PRESETS`, comma-separated names, default every registered
//! preset; `RESHIFT_BENCH_SHADE`, `RESHIFT_BENCH_NEIGHBOURS`).

mod common;

use std::process::Command;

use engine::clock::Stopwatch;
use engine::{Backend, Keep, Preset, RunConfig, Stream};
use restir::stats::{Summary, student_t_quantile};
use sss::scene::Scene;

const CHILD: &str = "RESHIFT_BENCH_STREAM_CHILD";
const LENGTHS: [u32; 2] = [16, 256];

/// The child: one stream of `frames` frames; prints `cpu_seconds wall_seconds peak_kib`.
fn child(frames: u32, preset: &Preset, size: (u32, u32)) -> Result<(), String> {
    let name = std::env::var("RESHIFT_BENCH_SCENE").unwrap_or_else(|_| "bumpy".into());
    let mut scene = Scene::builtin(&name).ok_or(format!("no built-in scene {name}"))?;
    scene.camera = scene.camera.with_resolution(size.0, size.1);
    let config = RunConfig {
        seed: 1,
        frames,
        collect_diagnostics: false,
    };
    let watch = Stopwatch::start(&Backend::Cpu);
    let run = Stream::new(&Backend::Cpu, &scene, preset, &config)
        .and_then(|s| s.run(frames, Keep::Last))
        .map_err(|e| e.to_string())?;
    let time = watch.read();
    assert_eq!(run.frames.len(), 1);
    let peak = peak_kib().map_or("n/a".into(), |k| k.to_string());
    println!("{} {} {peak}", time.seconds, time.wall_seconds);
    Ok(())
}

/// The process's peak resident set (`VmHWM` of `/proc/self/status`), in KiB.
fn peak_kib() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

/// One child's `(cpu seconds, peak KiB)` for preset `index` of [`common::presets`].
fn measure(frames: u32, index: usize) -> Result<(f64, Option<u64>), String> {
    let exe = std::env::current_exe().map_err(|e| e.to_string())?;
    let out = Command::new(exe)
        .env(CHILD, format!("{frames}:{index}"))
        .output()
        .map_err(|e| e.to_string())?;
    let text = String::from_utf8_lossy(&out.stdout);
    let line = text.lines().last().unwrap_or("");
    let fields: Vec<&str> = line.split_whitespace().collect();
    match (out.status.success(), fields.as_slice()) {
        (true, [cpu, _wall, peak]) => Ok((
            cpu.parse().map_err(|_| format!("child printed {line:?}"))?,
            peak.parse().ok(),
        )),
        _ => Err(format!(
            "child for {frames} frames failed: {}",
            String::from_utf8_lossy(&out.stderr)
        )),
    }
}

/// `mean [lo, hi]` of `xs` with a 95% t interval.
fn interval(xs: &[f64]) -> String {
    let s = Summary::from_samples(xs);
    let t = student_t_quantile(0.975, (xs.len().max(2) - 1) as f64);
    format!(
        "{:.3} [{:.3}, {:.3}]",
        s.mean,
        s.mean - t * s.std_err,
        s.mean + t * s.std_err
    )
}

fn main() -> Result<(), String> {
    let size = match std::env::var("RESHIFT_BENCH_SIZE") {
        Ok(text) => common::size(&text, "RESHIFT_BENCH_SIZE")?,
        Err(_) => (128, 96),
    };
    let presets = common::presets()?;
    if let Ok(text) = std::env::var(CHILD) {
        let parsed = text
            .split_once(':')
            .and_then(|(f, i)| Some((f.parse().ok()?, presets.get(i.parse::<usize>().ok()?)?)));
        let (frames, preset) = parsed.ok_or(format!("{CHILD} = {text:?}"))?;
        return child(frames, preset, size);
    }
    let rounds = common::rounds(3)?;
    let scene = std::env::var("RESHIFT_BENCH_SCENE").unwrap_or_else(|_| "bumpy".into());
    println!(
        "# streams on {scene} at {}x{}, {rounds} rounds, CPU time",
        size.0, size.1
    );
    println!(
        "| preset | ms/frame at {} | ms/frame at {} | ratio | peak KiB at {} | peak KiB at {} |",
        LENGTHS[0], LENGTHS[1], LENGTHS[0], LENGTHS[1]
    );
    println!("|---|---|---|---|---|---|");
    for (index, preset) in presets.iter().enumerate() {
        let mut ms = [Vec::new(), Vec::new()];
        let mut peaks = [Vec::new(), Vec::new()];
        for _ in 0..rounds {
            for (i, &frames) in LENGTHS.iter().enumerate() {
                let (cpu, peak) = measure(frames, index)?;
                ms[i].push(1e3 * cpu / frames as f64);
                peaks[i].extend(peak);
            }
        }
        let log_ratios: Vec<f64> = (ms[1].iter().zip(&ms[0]))
            .map(|(long, short)| (long / short).ln())
            .collect();
        let s = Summary::from_samples(&log_ratios);
        let t = student_t_quantile(0.975, (rounds - 1) as f64);
        let span = |p: &[u64]| match (p.iter().min(), p.iter().max()) {
            (Some(lo), Some(hi)) => format!("{lo}–{hi}"),
            _ => "n/a".into(),
        };
        println!(
            "| restir:{} | {} | {} | {:.3} [{:.3}, {:.3}] | {} | {} |",
            preset.name,
            interval(&ms[0]),
            interval(&ms[1]),
            s.mean.exp(),
            (s.mean - t * s.std_err).exp(),
            (s.mean + t * s.std_err).exp(),
            span(&peaks[0]),
            span(&peaks[1]),
        );
    }
    Ok(())
}
