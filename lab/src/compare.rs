//! A comparison (DESIGN §7): K replicas of several methods on one scene against one reference,
//! measured per region at every frame of the camera trajectory; the job of `reshift compare` and
//! of the experiments built on it.
//!
//! [`run`] takes a [`Plan`], obtains the references ([`crate::reference_cache`]: the plan's at
//! the last frame, and cheaper ones at the earlier frames for the convergence record), renders
//! the replicas (seeds `0..K`; with an equal-time budget a bare `pt` is first calibrated), reduces
//! them to [`MethodResult`]s and writes `table.md`, `table.csv`, `results.json` ([`Results`]),
//! the images ([`crate::images`]), the figures ([`crate::report::plots`]) and `report.html`
//! ([`crate::report::html`]) into the plan's folder.

use std::path::{Path, PathBuf};

use engine::Backend;
use engine::denoise::{self, DenoiseError, Denoiser, Guide};
use sss::limits::{self, IMAGE_BYTES_PER_PIXEL};
use sss::scene::{GBuffer, Scene};

use crate::error::Error;
use crate::images::write_comparison_images;
use crate::method_result::{MethodResult, Replica};
use crate::progress::Progress;
use crate::reference_cache::{self, FrameReference, Obtained, REFERENCE_SEED, ReferenceSource};
use crate::regions::Regions;
use crate::report::results::{FrameReferenceEntry, MethodEntry, ReferenceEntry, Results, RunEntry};
use crate::report::{figure, html, output_dir, plots, tables, write_text};
use methods::pt::Pt;
use methods::{Method, MethodError, SampleCounts};

/// The default method list: the path tracer, the four main presets [001 §5.1], and reshift's
/// best measured configuration, reconnection with Rao-Blackwellised shading and 2 neighbours
/// (docs/experiments.md, issue 10).
pub const DEFAULT_METHODS: &str = "pt,restir:reconnection,restir:delayed,restir:hybrid,\
                                   restir:sequential,restir:reconnection/shade=all/neighbours=2";

/// The method whose samples per pixel an equal-time budget sets: the bare path tracer.
pub const EQUAL_TIME_SPEC: &str = "pt";

/// The default method that efficiency ratios are taken against.
pub const DEFAULT_BASELINE: &str = "pt";

/// What to compare, where, and against what.
pub struct Plan {
    /// The scene with the camera at the comparison's resolution.
    pub scene: Scene,
    /// Names the scene's cached references ([`crate::scenes::LoadedScene::key`]).
    pub scene_key: String,
    /// `(spec as requested, method)`; the spec names the method's rows and files.
    pub methods: Vec<(String, Method)>,
    /// The spec of the method efficiency ratios are taken against; no ratios when it is not
    /// among `methods`.
    pub baseline: String,
    /// Independent replicas per method (seeds `0..replicas`).
    pub replicas: u32,
    /// Frames of the camera trajectory; the tables measure the last one.
    pub frames: u32,
    /// `Some(seconds)`: equal time, [`EQUAL_TIME_SPEC`] is scaled to `seconds` per frame and
    /// every other method keeps its cost; `None`: every method at its own spp.
    pub equal_time: Option<f64>,
    /// The reference of the last frame.
    pub reference: ReferenceSource,
    /// `Some(spp)`: the convergence record measures every frame, against cached references of
    /// `spp` samples per pixel at the earlier frames (a multiple ≥ 2× of the reference's batch;
    /// [`frame_reference_spp`]); `None`, or a reference from a file: the last frame only.
    pub frame_reference_spp: Option<u32>,
    /// The output folder.
    pub out: PathBuf,
    pub backend: Backend,
    /// The denoisers every replica's last frame also passes through (none: raw frames only).
    /// Each adds a row per method, measured like the raw one, with the denoiser's seconds per
    /// frame, which its efficiency counts at equal time (the reference is never denoised).
    pub denoise: Vec<Denoiser>,
}

/// What a finished (or stopped) comparison produced.
pub struct Outcome {
    /// The contents of `results.json`.
    pub results: Results,
    /// One row group per method that rendered at least one replica.
    pub rows: Vec<MethodResult>,
    /// Per denoiser of the plan, the rows of its denoised frames (the methods whose every
    /// replica it denoised), in the order of `rows`.
    pub denoised: Vec<(Denoiser, Vec<MethodResult>)>,
    /// Why a denoiser left out rows, one line each (the raw rows are complete regardless).
    pub denoise_errors: Vec<String>,
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

/// Samples per pixel of the references at frames before the last: 1/32 of the last frame's
/// `spp`, rounded down to whole batches of `batch_spp`, at least 2 batches (their standard
/// error needs 2). Their variance is subtracted from each frame's MSE ([`crate::metrics`]), so
/// they need not be converged, only cheap: 15 of them cost about half the last frame's.
pub fn frame_reference_spp(spp: u32, batch_spp: u32) -> u32 {
    let batch = batch_spp.max(1);
    (spp / 32 / batch * batch).max(2 * batch)
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

    /// The reference source of `frame`: the plan's for the last frame; for an earlier one, the
    /// cache at [`Plan::frame_reference_spp`] (`None` without a cache or a convergence record).
    fn reference_of(&self, frame: u32) -> Option<ReferenceSource> {
        if frame + 1 == self.frames {
            return Some(self.reference.clone());
        }
        match (&self.reference, self.frame_reference_spp) {
            (ReferenceSource::Cache { dir, batch_spp, .. }, Some(spp)) => {
                Some(ReferenceSource::Cache {
                    dir: dir.clone(),
                    spp,
                    batch_spp: *batch_spp,
                })
            }
            _ => None,
        }
    }
}

/// Runs the comparison of `plan`, reporting to `progress` (phases `reference frame F` and
/// `replicas`). A stop request ends it after the current replica with the replicas rendered so
/// far (`results.interrupted`), or, while a reference renders, with [`Error::Interrupted`].
pub fn run(plan: &Plan, progress: &mut dyn Progress) -> Result<Outcome, Error> {
    plan.check()?;
    let out = output_dir(&plan.out)?;
    let scene = &plan.scene;
    // The last frame's reference first: it is the one that matters most, and an interrupted
    // comparison leaves its checkpoint.
    let last_frame = plan.frames - 1;
    let mut references = Vec::new();
    let mut frame_entries = Vec::new();
    let mut last: Option<Obtained> = None;
    for frame in std::iter::once(last_frame).chain(0..last_frame) {
        let Some(source) = plan.reference_of(frame) else {
            continue;
        };
        let obtained = reference_cache::obtain(&source, scene, &plan.scene_key, frame, progress)?;
        let regions = Regions::classify(scene, &GBuffer::render(scene, frame), REFERENCE_SEED);
        frame_entries.push(FrameReferenceEntry::new(&obtained));
        references.push((FrameReference::new(&obtained.reference), regions));
        if frame == last_frame {
            last = Some(obtained);
        }
    }
    references.rotate_left(1);
    frame_entries.rotate_left(1);
    let last = last.expect("the last frame always has a reference");
    let frames: Vec<u32> = references.iter().map(|(r, _)| r.frame).collect();
    let renders = render_replicas(plan, &frames, progress)?;
    let interrupted = progress.stop_requested();

    let mut rows = Vec::new();
    for r in renders.runs.iter().filter(|r| !r.replicas.is_empty()) {
        let row = MethodResult::from_replicas(&r.spec, r.method.spp(), &r.replicas, &references)
            .ok_or_else(|| {
                Error::Invalid(format!("{}: image size differs from the reference", r.spec))
            })?;
        rows.push(row);
    }
    let denoised: Vec<(Denoiser, Vec<MethodResult>)> = plan
        .denoise
        .iter()
        .map(|&d| {
            let complete: Vec<(&MethodRuns, &Vec<Replica>)> = renders
                .runs
                .iter()
                .filter_map(|r| {
                    let (_, replicas) = r.denoised.iter().find(|(e, _)| *e == d)?;
                    let whole = !replicas.is_empty() && replicas.len() == r.replicas.len();
                    whole.then_some((r, replicas))
                })
                .collect();
            let counted = plan.equal_time.map(|_| {
                let times: Vec<f64> = complete
                    .iter()
                    .flat_map(|(_, replicas)| replicas.iter().map(|r| r.denoiser_seconds_per_frame))
                    .collect();
                times.iter().sum::<f64>() / times.len().max(1) as f64
            });
            let group = complete
                .iter()
                .filter_map(|(r, replicas)| {
                    let spp = r.method.spp();
                    MethodResult::denoised(&r.spec, spp, d, replicas, &references, counted)
                })
                .collect();
            (d, group)
        })
        .collect();
    let baseline = rows.iter().find(|r| r.method == plan.baseline);
    // Every row with its replica-0 last frame: the raw rows, then each denoiser's.
    let groups: Vec<(Option<Denoiser>, &[MethodResult])> = std::iter::once((None, &rows[..]))
        .chain(denoised.iter().map(|(d, g)| (Some(*d), &g[..])))
        .collect();
    let mut labelled = Vec::new();
    for (denoiser, group) in &groups {
        for row in group.iter() {
            let run = renders.runs.iter().find(|r| r.spec == row.method);
            let replicas = match denoiser {
                None => run.map(|r| &r.replicas),
                Some(d) => run.and_then(|r| r.denoised.iter().find(|(e, _)| e == d).map(|x| &x.1)),
            };
            if let Some(image) = replicas.and_then(|r| r.first()?.frames.last()) {
                labelled.push((row, row.label(), image));
            }
        }
    }
    let finals: Vec<(&str, &engine::Image)> =
        labelled.iter().map(|(_, l, i)| (l.as_str(), *i)).collect();
    let (images, scale) = write_comparison_images(&out, &finals, &last.reference)?;
    let (_, regions) = references.last().expect("the last frame");
    let bands: Vec<figure::Band> = groups
        .iter()
        .map(|(denoiser, group)| figure::Band {
            denoiser: *denoiser,
            rows: group,
            baseline: group.iter().find(|r| r.method == plan.baseline),
            finals: labelled
                .iter()
                .filter(|(r, _, _)| r.denoiser == *denoiser)
                .map(|(r, _, i)| (r.method.as_str(), *i))
                .collect(),
        })
        .collect();
    let figures = plots::write_figures(&out, &rows, &bands, &last.reference, regions)?;
    let mut markdown = String::new();
    let mut csv = String::new();
    for (denoiser, group) in &groups {
        let base = group.iter().find(|r| r.method == plan.baseline);
        if let Some(d) = denoiser {
            let counted = if plan.equal_time.is_some() {
                "counted in ms/frame and efficiency (equal time), as its mean over these rows"
            } else {
                "not counted in ms/frame and efficiency (equal spp)"
            };
            markdown.push_str(&format!(
                "\nDenoised with {d} (last frame of every replica; ratios to {}; the denoiser's \
                 time {counted}):\n\n",
                base.map_or("-".into(), |b| b.label())
            ));
        }
        markdown.push_str(&format!(
            "{}\n{}",
            tables::markdown(group, base),
            tables::verdict(group, base)
        ));
        if denoiser.is_some() {
            markdown.push_str(&format!("\n{}", tables::denoiser_time(group)));
        }
        let table = tables::csv(group, base);
        let skip = if csv.is_empty() { 0 } else { 1 };
        for line in table.lines().skip(skip) {
            csv.push_str(line);
            csv.push('\n');
        }
    }
    let all_rows: Vec<MethodResult> = groups.iter().flat_map(|(_, g)| g.iter().cloned()).collect();
    markdown.push_str(&format!("\n{}", tables::perceptual(&all_rows)));
    for e in &renders.denoise_errors {
        markdown.push_str(&format!("\nDenoiser: {e}\n"));
    }
    write_text(&out.join("table.md"), &markdown)?;
    write_text(&out.join("table.csv"), &csv)?;
    write_text(
        &out.join("convergence.csv"),
        &tables::convergence_csv(&rows),
    )?;
    let run = RunEntry {
        scene: scene.name.clone(),
        backend: plan.backend.to_string(),
        width: last.reference.width,
        height: last.reference.height,
        frames: plan.frames,
        replicas: plan.replicas,
        equal_time: plan.equal_time,
        baseline: baseline.map(|b| b.method.clone()),
        interrupted,
    };
    let entries = labelled
        .iter()
        .zip(images)
        .map(|((r, _, _), files)| {
            let base = groups
                .iter()
                .find(|(d, _)| *d == r.denoiser)
                .and_then(|(_, g)| g.iter().find(|b| b.method == plan.baseline));
            MethodEntry::new(r, base, files)
        })
        .collect();
    let reference_entry = ReferenceEntry::new(&last.reference, &last.path, last.cached);
    let results = Results::new(
        run,
        reference_entry,
        frame_entries,
        regions,
        scale,
        figures,
        denoised.iter().map(|(d, _)| d.name().to_string()).collect(),
        renders.denoise_errors.clone(),
        entries,
    );
    write_text(&out.join("results.json"), &results.to_json_pretty())?;
    write_text(&out.join("report.html"), &html::report(&results, &out)?)?;
    Ok(Outcome {
        results,
        rows,
        denoised,
        denoise_errors: renders.denoise_errors,
        markdown,
        out,
    })
}

/// One method's replicas as rendered.
struct MethodRuns {
    spec: String,
    method: Method,
    /// The measured frames of each replica.
    replicas: Vec<Replica>,
    /// Per denoiser that denoised every replica so far, the denoised last frames.
    denoised: Vec<(Denoiser, Vec<Replica>)>,
}

/// What [`render_replicas`] rendered.
struct Renders {
    runs: Vec<MethodRuns>,
    denoise_errors: Vec<String>,
}

/// The replicas of every method, in order, each with its images at `frames` (ascending, the
/// last frame last) and its last frame through each denoiser of the plan; after a stop request
/// the list ends with the method that was rendering, with the replicas it finished. A denoiser
/// that fails on a replica leaves that method's denoised row out with one line in
/// `denoise_errors`; one that is not installed is left out of every method with one line.
fn render_replicas(
    plan: &Plan,
    frames: &[u32],
    progress: &mut dyn Progress,
) -> Result<Renders, Error> {
    let seconds_per_spp = match plan.equal_time {
        Some(_) if plan.methods.iter().any(|(s, _)| s == EQUAL_TIME_SPEC) => {
            calibrate_pt(&plan.backend, &plan.scene, plan.frames)?
        }
        _ => 0.0,
    };
    let guides = if plan.denoise.is_empty() {
        Vec::new()
    } else {
        Guide::trajectory(&plan.scene, plan.frames)
    };
    let whole_trajectory = plan.denoise.iter().any(|d| d.temporal());
    let mut denoisers = plan.denoise.clone();
    let mut denoise_errors = Vec::new();
    // Untimed warm-up: loading a library, creating a device or compiling kernels is not the
    // per-frame cost a renderer pays.
    if let Some(guide) = guides.last() {
        let black = engine::Image::black(guide.width, guide.height);
        for &d in &plan.denoise {
            let _ = denoise::denoise(d, &plan.backend, &guides, std::slice::from_ref(&black));
        }
    }
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
        let mut run = MethodRuns {
            spec: spec.clone(),
            method: method.clone(),
            replicas: Vec::new(),
            denoised: denoisers.iter().map(|&d| (d, Vec::new())).collect(),
        };
        for seed in 0..plan.replicas as u64 {
            if progress.stop_requested() {
                runs.push(run);
                break 'methods;
            }
            let (replica, trajectory) =
                render_replica(plan, &method, frames, seed, whole_trajectory)?;
            let mut failed = Vec::new();
            for (d, denoised) in &mut run.denoised {
                match denoise_replica(*d, &plan.backend, &guides, &trajectory, &replica) {
                    Ok(r) => denoised.push(r),
                    Err(e) => failed.push((*d, e)),
                }
            }
            for (d, e) in failed {
                run.denoised.retain(|(x, _)| *x != d);
                if matches!(e, DenoiseError::Unavailable(_)) {
                    denoisers.retain(|x| *x != d);
                    denoise_errors.push(format!("{d}: {e}; its rows are left out"));
                } else {
                    denoise_errors.push(format!(
                        "{spec}, replica {seed}: {e}; its {d} row is left out"
                    ));
                }
            }
            run.replicas.push(replica);
            progress.step();
        }
        runs.push(run);
    }
    progress.end();
    Ok(Renders {
        runs,
        denoise_errors,
    })
}

/// `replica`'s last frame through `denoiser`, from the frames of its `trajectory` (the last
/// frames of the trajectory that `guides` guide), with the denoiser's seconds per frame (a
/// temporal filter's time over every frame it filtered, per frame).
fn denoise_replica(
    denoiser: Denoiser,
    backend: &Backend,
    guides: &[Guide],
    trajectory: &[engine::Image],
    replica: &Replica,
) -> Result<Replica, DenoiseError> {
    let d = denoise::denoise(denoiser, backend, guides, trajectory)?;
    let per_frame = if denoiser.temporal() {
        d.seconds / trajectory.len() as f64
    } else {
        d.seconds
    };
    Ok(Replica {
        frames: vec![d.image],
        denoiser_seconds_per_frame: per_frame,
        ..replica.clone()
    })
}

/// Replica `seed` of `method` at `frames`, and the frames a denoiser reads: the whole
/// trajectory when earlier frames are measured or `whole_trajectory` is asked for (a temporal
/// denoiser), else only the last frame (which a memoryless method renders alone).
fn render_replica(
    plan: &Plan,
    method: &Method,
    frames: &[u32],
    seed: u64,
    whole_trajectory: bool,
) -> Result<(Replica, Vec<engine::Image>), Error> {
    let (backend, scene) = (&plan.backend, &plan.scene);
    if frames.len() == 1 && !whole_trajectory {
        let r = method.render_on(backend, scene, plan.frames, seed)?;
        let replica = Replica {
            frames: vec![r.image.clone()],
            seconds_per_frame: r.seconds_per_frame,
            denoiser_seconds_per_frame: 0.0,
            frames_rendered: r.frames_rendered,
            nonfinite: r.nonfinite,
            spp: r.spp,
        };
        return Ok((replica, vec![r.image]));
    }
    let (trajectory, seconds_per_frame) =
        method.render_trajectory_on(backend, scene, plan.frames, seed)?;
    let images = (0..)
        .zip(&trajectory.frames)
        .filter_map(|(f, image)| frames.contains(&f).then(|| image.clone()))
        .collect();
    let replica = Replica {
        frames: images,
        seconds_per_frame,
        denoiser_seconds_per_frame: 0.0,
        frames_rendered: trajectory.frames_rendered,
        nonfinite: trajectory.nonfinite,
        spp: trajectory
            .counts
            .as_ref()
            .map_or(method.spp() as f64, SampleCounts::mean),
    };
    Ok((replica, trajectory.frames))
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

    /// A replica whose last frame holds a NaN is not denoised: one line naming the frame and
    /// the count, and its seconds are left alone.
    #[test]
    fn a_nan_frame_is_refused_by_every_denoiser() {
        let scene = with_resolution(Scene::builtin("bumpy").unwrap(), Some((8, 6)));
        let guides = Guide::trajectory(&scene, 2);
        let mut frames = vec![engine::Image::black(8, 6); 2];
        frames[1].pixels[5].y = f32::NAN;
        let replica = Replica {
            frames: vec![frames[1].clone()],
            seconds_per_frame: 0.5,
            denoiser_seconds_per_frame: 0.0,
            frames_rendered: 2,
            nonfinite: 1,
            spp: 1.0,
        };
        for d in Denoiser::ALL {
            let e = denoise_replica(d, &Backend::Cpu, &guides, &frames, &replica).unwrap_err();
            assert_eq!(
                e.to_string(),
                "frame 1: 1 pixel(s) with a NaN or infinite value, not denoised"
            );
        }
    }

    /// A whole comparison through the library: every file is written, the document agrees with
    /// the rows, every frame is measured, a second run reuses the cached references and
    /// reproduces the errors, and measuring the last frame alone gives the same last-frame
    /// errors (a trajectory's last frame is the frame a single render returns).
    #[test]
    fn a_comparison_writes_its_outputs_and_reuses_the_reference() {
        let dir = std::env::temp_dir().join(format!("reshift-compare-{}", std::process::id()));
        let plan = Plan {
            scene: with_resolution(Scene::builtin("bumpy").unwrap(), Some((12, 9))),
            scene_key: "bumpy".into(),
            methods: parse_methods(&["pt:2", "restir:hybrid"]).unwrap(),
            baseline: "pt:2".into(),
            replicas: 3,
            frames: 3,
            equal_time: None,
            reference: ReferenceSource::Cache {
                dir: dir.join("cache"),
                spp: 8,
                batch_spp: 4,
            },
            frame_reference_spp: Some(8),
            out: dir.join("out"),
            backend: Backend::Cpu,
            denoise: vec![Denoiser::Svgf],
        };
        let first = run(&plan, &mut Silent).unwrap();
        // The denoised rows: one per method, measured at the last frame, their seconds the raw
        // ones (equal spp: the denoiser's are reported, not counted), their ratios to the
        // baseline's denoised row.
        let (d, denoised) = &first.denoised[0];
        assert_eq!(*d, Denoiser::Svgf);
        assert_eq!(denoised.len(), 2);
        for (row, raw) in denoised.iter().zip(&first.rows) {
            assert_eq!(row.label(), format!("{}+svgf", raw.method));
            assert_eq!(row.convergence.len(), 1);
            let extra = row.denoiser_seconds.as_ref().unwrap().value;
            assert!(extra > 0.0);
            assert_eq!(row.seconds, raw.seconds);
            assert_ne!(row.metrics, raw.metrics);
        }
        assert!(
            first.denoise_errors.is_empty(),
            "{:?}",
            first.denoise_errors
        );
        assert_eq!(first.results.methods.len(), 4);
        assert_eq!(first.results.denoisers, ["svgf"]);
        assert!(
            first.markdown.contains("Denoised with svgf"),
            "{}",
            first.markdown
        );
        assert!(
            first.markdown.contains("| pt:2+svgf |"),
            "{}",
            first.markdown
        );
        assert_eq!(first.rows.len(), 2);
        assert!(!first.results.reference.cached && !first.results.interrupted);
        for file in [
            "table.md",
            "table.csv",
            "convergence.csv",
            "results.json",
            "reference.exr",
            "figure.png",
            "convergence.png",
            "report.html",
            "restir-hybrid-abs-error.png",
            "restir-hybrid-flip.png",
            "restir-hybrid-low-frequency.png",
            "restir-hybrid-svgf.png",
            "restir-hybrid-svgf-flip.png",
        ] {
            assert!(first.out.join(file).is_file(), "{file}");
        }
        let written = std::fs::read_to_string(first.out.join("results.json")).unwrap();
        assert_eq!(written, first.results.to_json_pretty());
        assert_eq!(first.results.frame_references.len(), 3);
        for row in &first.rows {
            let frames: Vec<u32> = row.convergence.iter().map(|f| f.frame).collect();
            assert_eq!(frames, [0, 1, 2], "{}", row.method);
            assert_eq!(row.convergence[2].metrics, row.metrics);
            assert_eq!(row.seconds.replicas(), 3);
        }
        assert_eq!(first.results.baseline.as_deref(), Some("pt:2"));
        assert!(
            first.markdown.contains("Efficiency over pt:2"),
            "{}",
            first.markdown
        );
        let again = run(&plan, &mut Silent).unwrap();
        assert!(again.results.reference.cached);
        assert!(again.results.frame_references.iter().all(|f| f.cached));
        assert_eq!(again.rows[1].metrics, first.rows[1].metrics);
        assert_eq!(
            again.denoised[0].1[1].metrics,
            first.denoised[0].1[1].metrics
        );
        let last_only = Plan {
            frame_reference_spp: None,
            baseline: "none".into(),
            denoise: Vec::new(),
            ..plan
        };
        let last = run(&last_only, &mut Silent).unwrap();
        assert!(last.results.baseline.is_none());
        for (a, b) in last.rows.iter().zip(&first.rows) {
            assert_eq!(a.metrics, b.metrics, "{}", a.method);
            assert_eq!(a.convergence.len(), 1);
        }
        // Equal time counts the denoiser: every denoised row's seconds are its rendering's plus
        // one figure shared by the denoiser's rows (the mean of its timings).
        let timed = Plan {
            equal_time: Some(0.01),
            denoise: vec![Denoiser::Svgf],
            ..last_only
        };
        let counted = run(&timed, &mut Silent).unwrap();
        let (_, denoised) = &counted.denoised[0];
        let added: Vec<f64> = denoised
            .iter()
            .zip(&counted.rows)
            .map(|(d, raw)| d.seconds.value - raw.seconds.value)
            .collect();
        let pooled: Vec<f64> = denoised
            .iter()
            .map(|d| d.denoiser_seconds.as_ref().unwrap().value)
            .collect();
        let mean = pooled.iter().sum::<f64>() / pooled.len() as f64;
        for a in &added {
            assert!((a - mean).abs() < 1e-12, "{added:?} vs {mean}");
        }
        assert!(counted.markdown.contains("counted in ms/frame"));
        let empty = Plan {
            methods: Vec::new(),
            ..timed
        };
        assert!(matches!(run(&empty, &mut Silent), Err(Error::Invalid(_))));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
