//! A comparison (DESIGN §7): K replicas of several methods on one scene against one reference,
//! measured per region; the job of `reshift compare` and of the experiments built on it.
//!
//! [`run`] takes a [`Plan`], obtains the reference ([`crate::reference_cache`]), renders the
//! replicas (seeds `0..K`; with an equal-time budget a bare `pt` is first calibrated), reduces
//! them to [`MethodResult`]s and writes `table.md`, `table.csv`, `results.json` ([`Results`])
//! and the images ([`crate::images`]) into the plan's folder.

use std::path::{Path, PathBuf};

use engine::Backend;
use sss::limits::{self, IMAGE_BYTES_PER_PIXEL};
use sss::scene::{GBuffer, Scene};

use crate::error::Error;
use crate::images::write_comparison_images;
use crate::method_result::MethodResult;
use crate::methods::pt::Pt;
use crate::methods::{Method, MethodError, Rendered};
use crate::progress::Progress;
use crate::reference_cache::{self, REFERENCE_SEED, ReferenceSource};
use crate::regions::Regions;
use crate::report::results::{MethodEntry, ReferenceEntry, Results, RunEntry};
use crate::report::{output_dir, tables, write_text};

/// The default method list: the path tracer and the four main presets [001 §5.1].
pub const DEFAULT_METHODS: &str =
    "pt,restir:reconnection,restir:delayed,restir:hybrid,restir:sequential";

/// The method whose samples per pixel an equal-time budget sets: the bare path tracer.
pub const EQUAL_TIME_SPEC: &str = "pt";

/// What to compare, where, and against what.
pub struct Plan {
    /// The scene with the camera at the comparison's resolution.
    pub scene: Scene,
    /// Names the scene's cached references ([`crate::scenes::LoadedScene::key`]).
    pub scene_key: String,
    /// `(spec as requested, method)`; the spec names the method's rows and files.
    pub methods: Vec<(String, Method)>,
    /// Independent replicas per method (seeds `0..replicas`).
    pub replicas: u32,
    /// Frames of the camera trajectory; errors are measured on the last one.
    pub frames: u32,
    /// `Some(seconds)`: equal time, [`EQUAL_TIME_SPEC`] is scaled to `seconds` per frame and
    /// every other method keeps its cost; `None`: every method at its own spp.
    pub equal_time: Option<f64>,
    pub reference: ReferenceSource,
    /// The output folder.
    pub out: PathBuf,
    pub backend: Backend,
}

/// What a finished (or stopped) comparison produced.
pub struct Outcome {
    /// The contents of `results.json`.
    pub results: Results,
    /// One row group per method that rendered at least one replica.
    pub rows: Vec<MethodResult>,
    /// The contents of `table.md`.
    pub markdown: String,
    pub out: PathBuf,
}

/// `(spec, method)` of every spec, in order.
pub fn parse_methods<S: AsRef<str>>(specs: &[S]) -> Result<Vec<(String, Method)>, MethodError> {
    specs
        .iter()
        .map(|s| Ok((s.as_ref().to_string(), Method::parse(s.as_ref())?)))
        .collect()
}

impl Plan {
    /// The plan's counts within [`sss::limits`], and the replicas' final frames (kept until the
    /// table is made) and one run within the memory budget.
    fn check(&self) -> Result<(), Error> {
        let invalid = |reason: &str| Err(Error::Invalid(format!("comparison plan: {reason}")));
        if self.methods.is_empty() {
            return invalid("no method given");
        }
        let origin = Path::new("(comparison plan)");
        limits::replicas(origin, "replicas", self.replicas)?;
        limits::frames(origin, "frames", self.frames)?;
        if self.equal_time.is_some_and(|t| !(t.is_finite() && t > 0.0)) {
            return invalid("the equal-time budget must be a positive number of seconds");
        }
        let pixels = self.scene.camera.width() as u64 * self.scene.camera.height() as u64;
        let kept = (self.methods.len() as u64)
            .checked_mul(self.replicas as u64)
            .and_then(|n| n.checked_mul(pixels * IMAGE_BYTES_PER_PIXEL));
        let needed = kept.zip(limits::run_bytes(pixels, self.frames));
        let value = format!(
            "{} methods × {} replicas × {} frames at {}×{}",
            self.methods.len(),
            self.replicas,
            self.frames,
            self.scene.camera.width(),
            self.scene.camera.height()
        );
        limits::memory(
            origin,
            "replicas",
            &value,
            needed.and_then(|(a, b)| a.checked_add(b)),
            "the comparison",
        )?;
        Ok(())
    }
}

/// Runs the comparison of `plan`, reporting to `progress` (phases `reference` and `replicas`).
/// A stop request ends it after the current replica with the replicas rendered so far
/// (`results.interrupted`), or, while the reference renders, with [`Error::Interrupted`].
pub fn run(plan: &Plan, progress: &mut dyn Progress) -> Result<Outcome, Error> {
    plan.check()?;
    let out = output_dir(&plan.out)?;
    let frame = plan.frames - 1;
    let scene = &plan.scene;
    let reference =
        reference_cache::obtain(&plan.reference, scene, &plan.scene_key, frame, progress)?;
    let regions = Regions::classify(scene, &GBuffer::render(scene, frame), REFERENCE_SEED);
    let runs = render_replicas(plan, progress)?;
    let interrupted = progress.stop_requested();

    let mut rows = Vec::new();
    for (spec, method, replicas) in runs.iter().filter(|r| !r.2.is_empty()) {
        let row = MethodResult::from_replicas(
            spec,
            method.spp(),
            replicas,
            &reference.reference,
            &regions,
        )
        .ok_or_else(|| Error::Invalid(format!("{spec}: image size differs from the reference")))?;
        rows.push(row);
    }
    let finals: Vec<(&str, &engine::Image)> = runs
        .iter()
        .filter_map(|(spec, _, replicas)| Some((spec.as_str(), &replicas.first()?.image)))
        .collect();
    let (images, scale) = write_comparison_images(&out, &finals, &reference.reference)?;
    let markdown = tables::markdown(&rows);
    write_text(&out.join("table.md"), &markdown)?;
    write_text(&out.join("table.csv"), &tables::csv(&rows))?;
    let run = RunEntry {
        scene: scene.name.clone(),
        backend: plan.backend.to_string(),
        width: reference.reference.width,
        height: reference.reference.height,
        frames: plan.frames,
        replicas: plan.replicas,
        equal_time: plan.equal_time,
        interrupted,
    };
    let entries = rows
        .iter()
        .zip(images)
        .map(|(r, files)| MethodEntry::new(r, files))
        .collect();
    let reference_entry =
        ReferenceEntry::new(&reference.reference, &reference.path, reference.cached);
    let results = Results::new(run, reference_entry, &regions, scale, entries);
    write_text(&out.join("results.json"), &results.to_json_pretty())?;
    Ok(Outcome {
        results,
        rows,
        markdown,
        out,
    })
}

/// The replicas of every method, in order; after a stop request the list ends with the method
/// that was rendering, with the replicas it finished.
fn render_replicas(
    plan: &Plan,
    progress: &mut dyn Progress,
) -> Result<Vec<(String, Method, Vec<Rendered>)>, Error> {
    let seconds_per_spp = match plan.equal_time {
        Some(_) if plan.methods.iter().any(|(s, _)| s == EQUAL_TIME_SPEC) => {
            calibrate_pt(&plan.backend, &plan.scene, plan.frames)?
        }
        _ => 0.0,
    };
    progress.begin(
        "replicas",
        plan.methods.len() as u64 * plan.replicas as u64,
        0,
    );
    let mut runs = Vec::new();
    'methods: for (spec, method) in &plan.methods {
        // `pt:N` pins its spp; a bare `pt` is scaled to the budget.
        let method = match plan.equal_time {
            Some(b) if spec == EQUAL_TIME_SPEC => equal_time_method(method, b, seconds_per_spp),
            _ => method.clone(),
        };
        progress.item(&method.name());
        let mut replicas = Vec::new();
        for seed in 0..plan.replicas as u64 {
            if progress.stop_requested() {
                runs.push((spec.clone(), method, replicas));
                break 'methods;
            }
            replicas.push(method.render_on(&plan.backend, &plan.scene, plan.frames, seed)?);
            progress.step();
        }
        runs.push((spec.clone(), method, replicas));
    }
    progress.end();
    Ok(runs)
}

/// Seconds per sample per pixel of the path tracer on this scene (median of 3 runs at 4 spp).
fn calibrate_pt(backend: &Backend, scene: &Scene, frames: u32) -> Result<f64, Error> {
    let pt = Method::new(Pt { spp: 4 });
    let mut times = Vec::new();
    for seed in 0..3 {
        times.push(
            pt.render_on(backend, scene, frames, 1_000_000 + seed)?
                .seconds_per_frame
                / 4.0,
        );
    }
    times.sort_by(f64::total_cmp);
    Ok(times[1])
}

/// Equal time: `method` at the spp that fits `budget` seconds per frame, from its measured
/// `seconds_per_spp` (at least 1 spp); methods of fixed cost are returned unchanged.
pub fn equal_time_method(method: &Method, budget: f64, seconds_per_spp: f64) -> Method {
    if seconds_per_spp > 0.0 && budget.is_finite() {
        let spp = (budget / seconds_per_spp).round().clamp(1.0, 1e6) as u32;
        method.with_spp(spp)
    } else {
        method.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::progress::Silent;
    use crate::scenes::with_resolution;

    #[test]
    fn equal_time_scales_the_spp_of_a_path_tracer() {
        let pt = Method::parse("pt").unwrap();
        assert_eq!(
            equal_time_method(&pt, 0.1, 0.02),
            Method::parse("pt:5").unwrap()
        );
        assert_eq!(equal_time_method(&pt, 0.001, 0.02), pt, "at least 1 spp");
        let hybrid = Method::parse("restir:hybrid").unwrap();
        assert_eq!(equal_time_method(&hybrid, 0.1, 0.02), hybrid);
    }

    /// A whole comparison through the library: every file is written, the document agrees with
    /// the rows, and a second run reuses the cached reference and reproduces the errors.
    #[test]
    fn a_comparison_writes_its_outputs_and_reuses_the_reference() {
        let dir = std::env::temp_dir().join(format!("reshift-compare-{}", std::process::id()));
        let plan = Plan {
            scene: with_resolution(Scene::builtin("bumpy").unwrap(), Some((12, 9))),
            scene_key: "bumpy".into(),
            methods: parse_methods(&["pt:2", "restir:hybrid"]).unwrap(),
            replicas: 2,
            frames: 2,
            equal_time: None,
            reference: ReferenceSource::Cache {
                dir: dir.join("cache"),
                spp: 8,
                batch_spp: 4,
            },
            out: dir.join("out"),
            backend: Backend::Cpu,
        };
        let first = run(&plan, &mut Silent).unwrap();
        assert_eq!(first.rows.len(), 2);
        assert_eq!(first.results.methods.len(), 2);
        assert!(!first.results.reference.cached && !first.results.interrupted);
        for file in ["table.md", "table.csv", "results.json", "reference.exr"] {
            assert!(first.out.join(file).is_file(), "{file}");
        }
        let written = std::fs::read_to_string(first.out.join("results.json")).unwrap();
        assert_eq!(written, first.results.to_json_pretty());
        let again = run(&plan, &mut Silent).unwrap();
        assert!(again.results.reference.cached);
        assert_eq!(again.rows[1].metrics, first.rows[1].metrics);
        let empty = Plan {
            methods: Vec::new(),
            ..plan
        };
        assert!(matches!(run(&empty, &mut Silent), Err(Error::Invalid(_))));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
