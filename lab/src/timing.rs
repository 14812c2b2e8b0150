//! Paper 001's timing protocol (§6): a preset's stream warms up for `warmup` frames at the
//! trajectory's first pose (temporal reuse reaches its steady state), then `timed` frames follow
//! the camera's trajectory and are timed pass by pass; the whole is repeated `repeats` times,
//! each repeat a fresh stream. Each pass is summarised over every timed frame of every repeat by
//! its median and spread. Times are on the backend's clock: each pass's process CPU time on the
//! CPU backend, the device's timestamps on Vulkan; the frame row is the host's time for the
//! whole frame (on Vulkan wall time, submission and read-back included).

use engine::clock::{Clock, Stopwatch};
use engine::{Backend, PipelineError, Preset, RunConfig, Stream};
use sss::scene::{Scene, Trajectory};

/// The protocol's frame counts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Protocol {
    pub warmup: u32,
    pub timed: u32,
    pub repeats: u32,
}

impl Default for Protocol {
    /// The paper's: 128 warm-up frames, 16 timed frames, 4 repeats.
    fn default() -> Self {
        Protocol {
            warmup: 128,
            timed: 16,
            repeats: 4,
        }
    }
}

/// One row of the table: a pass (or the whole frame) over every timed frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    pub label: String,
    /// Seconds per frame: median, quartiles, extremes, over `samples` timed frames.
    pub median: f64,
    pub quartiles: (f64, f64),
    pub range: (f64, f64),
    pub samples: usize,
}

impl Row {
    /// The row of `label` from its per-frame seconds (not empty).
    fn of(label: &str, mut seconds: Vec<f64>) -> Row {
        seconds.sort_by(f64::total_cmp);
        let at = |q: f64| {
            // Linear interpolation between the order statistics (type 7 quantiles).
            let x = q * (seconds.len() - 1) as f64;
            let (lo, hi) = (x.floor() as usize, x.ceil() as usize);
            seconds[lo] + (x - lo as f64) * (seconds[hi] - seconds[lo])
        };
        Row {
            label: label.to_string(),
            median: at(0.5),
            quartiles: (at(0.25), at(0.75)),
            range: (seconds[0], seconds[seconds.len() - 1]),
            samples: seconds.len(),
        }
    }
}

/// The protocol's result.
#[derive(Clone, Debug, PartialEq)]
pub struct Timing {
    /// The clock of the frame row, and of the passes on the CPU backend (process CPU time); on
    /// Vulkan the passes are the device's timestamps and the frame row is wall time.
    pub clock: Clock,
    /// One row per pass of the preset's plan, in execution order (none on a device queue that
    /// writes no timestamps), then `frame`.
    pub rows: Vec<Row>,
}

/// `scene`'s camera on the protocol's path: `warmup` frames at pose 0, then poses
/// `0..timed` of its trajectory.
pub fn protocol_scene(mut scene: Scene, protocol: &Protocol) -> Scene {
    let camera = &scene.camera;
    let poses = (0..protocol.warmup)
        .map(|_| camera.pose(0))
        .chain((0..protocol.timed).map(|f| camera.pose(f)))
        .collect();
    let path = Trajectory { vfov: None, poses };
    scene.camera = camera.with_trajectory(&path);
    scene
}

/// Runs `protocol` for `preset` on `scene` (its camera put on the protocol's path) with replica
/// `seed` (every repeat the same seed: the same work, timed again) on `backend`. Every count
/// must be ≥ 1 (the CLI checks them).
pub fn measure(
    backend: &Backend,
    scene: Scene,
    preset: &Preset,
    seed: u64,
    protocol: &Protocol,
) -> Result<Timing, PipelineError> {
    let scene = protocol_scene(scene, protocol);
    let config = RunConfig {
        seed,
        frames: protocol.warmup + protocol.timed,
        collect_diagnostics: false,
    };
    let mut labels = Vec::new();
    let mut passes: Vec<Vec<f64>> = Vec::new();
    let mut frames = Vec::new();
    let mut timestamps = true;
    for _ in 0..protocol.repeats {
        let mut stream = Stream::new(backend, &scene, preset, &config)?;
        if labels.is_empty() {
            labels = stream.labels().to_vec();
            passes = vec![Vec::new(); labels.len()];
        }
        for _ in 0..protocol.warmup {
            stream.frame()?;
        }
        for _ in 0..protocol.timed {
            let watch = Stopwatch::start(backend);
            let frame = stream.frame()?;
            frames.push(watch.read().seconds);
            timestamps &= frame.steps.len() == labels.len();
            for (seconds, timing) in passes.iter_mut().zip(&frame.steps) {
                seconds.push(timing.seconds);
            }
        }
    }
    let mut rows: Vec<Row> = match timestamps {
        true => (labels.iter().zip(passes))
            .map(|(label, seconds)| Row::of(label, seconds))
            .collect(),
        false => Vec::new(),
    };
    rows.push(Row::of("frame", frames));
    Ok(Timing {
        clock: Clock::of(backend),
        rows,
    })
}

impl Timing {
    /// The table, in milliseconds per frame, as markdown.
    pub fn table(&self) -> String {
        let ms = |s: f64| format!("{:.3}", 1e3 * s);
        let mut out = String::from(
            "| pass | median ms | quartiles ms | range ms | frames |\n|---|---|---|---|---|\n",
        );
        for row in &self.rows {
            out += &format!(
                "| {} | {} | {} – {} | {} – {} | {} |\n",
                row.label,
                ms(row.median),
                ms(row.quartiles.0),
                ms(row.quartiles.1),
                ms(row.range.0),
                ms(row.range.1),
                row.samples
            );
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bumpy() -> Scene {
        let mut scene = Scene::builtin("bumpy").unwrap();
        scene.camera = scene.camera.with_resolution(16, 12);
        scene
    }

    /// The protocol's camera rests at the first pose for the warm-up, then follows the
    /// trajectory from its start, pose for pose.
    #[test]
    fn the_camera_warms_up_at_rest_then_follows_the_trajectory() {
        let scene = bumpy();
        let protocol = Protocol {
            warmup: 5,
            timed: 16,
            repeats: 1,
        };
        let timed = protocol_scene(bumpy(), &protocol);
        for f in 0..5 {
            assert_eq!(
                timed.camera.pose(f),
                scene.camera.pose(0),
                "warm-up frame {f}"
            );
        }
        for f in 0..16 {
            assert_eq!(
                timed.camera.pose(5 + f),
                scene.camera.pose(f),
                "timed frame {f}"
            );
        }
    }

    /// A row per pass of the plan and one for the frame, each over `timed × repeats` frames,
    /// its statistics in order.
    #[test]
    fn every_pass_is_timed_over_every_timed_frame() {
        let preset = Preset::named("hybrid").unwrap();
        let protocol = Protocol {
            warmup: 3,
            timed: 4,
            repeats: 2,
        };
        let timing = measure(&Backend::Cpu, bumpy(), &preset, 1, &protocol).unwrap();
        let labels: Vec<&str> = timing.rows.iter().map(|r| r.label.as_str()).collect();
        assert_eq!(labels.first(), Some(&"gbuffer"));
        assert_eq!(
            labels.iter().rev().take(2).collect::<Vec<_>>(),
            [&"frame", &"shade"]
        );
        for row in &timing.rows {
            assert_eq!(row.samples, 8, "{}", row.label);
            let (q1, q3) = row.quartiles;
            assert!(
                row.range.0 <= q1 && q1 <= row.median && row.median <= q3 && q3 <= row.range.1,
                "{row:?}"
            );
        }
        assert!(timing.table().lines().count() == timing.rows.len() + 2);
    }

    /// Quantiles interpolate between order statistics.
    #[test]
    fn quantiles_interpolate() {
        let row = Row::of("x", vec![4.0, 1.0, 3.0, 2.0]);
        assert_eq!(row.median, 2.5);
        assert_eq!(row.quartiles, (1.75, 3.25));
        assert_eq!(row.range, (1.0, 4.0));
    }
}
