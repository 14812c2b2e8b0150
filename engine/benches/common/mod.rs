//! The environment knobs the CPU (`pipeline`) and Vulkan (`vulkan`) benches share: which presets
//! run, with which shading and neighbour count, over how many frames; and the image size the
//! `stream` bench takes too.

#![allow(dead_code)] // each bench uses a different part of this module

use engine::{Preset, Shade};

/// Frames per run: `RESHIFT_BENCH_FRAMES` (1..=16), else 4 (frame 0 has no temporal history; the
/// tables average every frame run).
pub fn frames() -> Result<u32, String> {
    match std::env::var("RESHIFT_BENCH_FRAMES") {
        Err(_) => Ok(4),
        Ok(v) => match v.parse::<u32>() {
            Ok(n) if (1..=16).contains(&n) => Ok(n),
            _ => Err(format!(
                "RESHIFT_BENCH_FRAMES = {v:?}: need an integer in 1..=16"
            )),
        },
    }
}

/// `width×height` from `WxH`.
pub fn size(text: &str, variable: &str) -> Result<(u32, u32), String> {
    text.split_once('x')
        .and_then(|(w, h)| Some((w.trim().parse::<u32>().ok()?, h.trim().parse::<u32>().ok()?)))
        .filter(|&(w, h)| w > 0 && h > 0)
        .ok_or_else(|| format!("{variable}: {text:?} is not WxH"))
}

/// The presets to run, each as the method the CLI names `restir:<preset>[/shade=all]
/// [/neighbours=<n>]`: every registered preset, or those `RESHIFT_BENCH_PRESETS` names
/// (comma-separated); `RESHIFT_BENCH_SHADE=all` gives each Rao-Blackwellised shading and
/// `RESHIFT_BENCH_NEIGHBOURS=<n>` gives each spatial pass `n` neighbours.
pub fn presets() -> Result<Vec<Preset>, String> {
    let registered = match std::env::var("RESHIFT_BENCH_PRESETS") {
        Err(_) => Preset::all(),
        Ok(names) => names
            .split(',')
            .map(|n| {
                Preset::named(n.trim())
                    .ok_or_else(|| format!("RESHIFT_BENCH_PRESETS: no preset {n:?}"))
            })
            .collect::<Result<_, _>>()?,
    };
    let shade = match std::env::var("RESHIFT_BENCH_SHADE").as_deref() {
        Err(_) | Ok("selected") => Shade::Selected,
        Ok("all") => Shade::AllInputs,
        Ok(v) => return Err(format!("RESHIFT_BENCH_SHADE = {v:?}: need selected or all")),
    };
    let neighbours = match std::env::var("RESHIFT_BENCH_NEIGHBOURS") {
        Err(_) => None,
        Ok(v) => Some(
            v.parse::<u32>()
                .map_err(|_| format!("RESHIFT_BENCH_NEIGHBOURS = {v:?}: need a whole number"))?,
        ),
    };
    Ok(registered
        .into_iter()
        .map(|mut preset| {
            if shade == Shade::AllInputs {
                preset.name = format!("{}/shade=all", preset.name);
                preset.shade = shade;
            }
            if let Some(n) = neighbours {
                preset = preset.with_neighbours(n);
                preset.name = format!("{}/neighbours={n}", preset.name);
            }
            preset
        })
        .collect())
}

/// Rounds of a bench that alternates its measurements: `RESHIFT_BENCH_ROUNDS` (≥ 2, so that each
/// figure has an interval), else `default`.
pub fn rounds(default: usize) -> Result<usize, String> {
    match std::env::var("RESHIFT_BENCH_ROUNDS") {
        Ok(v) => v
            .parse::<usize>()
            .ok()
            .filter(|&n| n >= 2)
            .ok_or(format!("RESHIFT_BENCH_ROUNDS = {v:?}: need an integer ≥ 2")),
        Err(_) => Ok(default),
    }
}
