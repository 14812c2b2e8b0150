//! A comparison (DESIGN §7): K replicas of several methods on one scene against one reference,
//! measured per region at every frame of the camera trajectory; the job of `reshift compare` and
//! of the experiments built on it.
//!
//! [`run`] takes a [`Comparison`], obtains the references ([`crate::reference_cache`]: the
//! comparison's at the last frame, and cheaper ones at the earlier frames for the convergence
//! record), renders the replicas (seeds `S..S+K` from the plan's first seed, in rounds of one seed over every method, each
//! timed on every frame on its backend's clock, [`engine::clock`]; with an equal-time budget a
//! bare `pt` is first calibrated; `render`) and reduces them to [`MethodResult`]s: an
//! [`Outcome`]. It writes
//! nothing but the reference cache; [`crate::report::write`] writes the outcome's tables,
//! `results.json`, images, figures and `report.html` into its folder.

mod render;
pub mod shard;

use std::ops::Range;
use std::path::{Path, PathBuf};

use engine::Backend;
use engine::denoise::Denoiser;
use engine::limits::{IMAGE_BYTES_PER_PIXEL, run_bytes};
use sss::limits;
use sss::scene::{GBuffer, Scene};

use crate::error::Error;
use crate::flicker::reference_change;
use crate::method_result::{MethodResult, Replica};
use crate::metrics::Area;
use crate::output::output_dir;
use crate::progress::Progress;
use crate::reference_cache::{
    self, FrameReference, Obtained, Provenance, REFERENCE_SEED, ReferenceSource,
};
use crate::regions::Regions;
use methods::{Method, MethodError};

pub use render::equal_time_method;
use render::{MethodRuns, Renders, render_replicas};

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
pub struct Comparison {
    /// The scene with the camera at the comparison's resolution.
    pub scene: Scene,
    /// Names the scene's cached references ([`crate::scenes::LoadedScene::key`]).
    pub scene_key: String,
    /// `(spec as requested, method)`; the spec names the method's rows and files.
    pub methods: Vec<(String, Method)>,
    /// The spec of the method efficiency ratios are taken against; no ratios when it is not
    /// among `methods`.
    pub baseline: String,
    /// Independent replicas per method (seeds `first_seed..first_seed + replicas`).
    pub replicas: u32,
    /// The seed of the first replica. Runs whose seed ranges do not overlap draw no random
    /// number in common, so a run from the seed after an earlier run's last is independent of
    /// it (a confirmatory run); 0 in every run that does not ask otherwise.
    pub first_seed: u64,
    /// Frames of the camera trajectory; the tables measure the last one.
    pub frames: u32,
    /// `Some(seconds)`: equal time, [`EQUAL_TIME_SPEC`] is scaled to `seconds` per frame on the
    /// backend's clock ([`engine::clock`]: CPU seconds on the CPU backend) and every other method
    /// keeps its cost; `None`: every method at its own spp.
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
    /// Whether replica 0 of every method keeps its whole trajectory, for the videos of
    /// [`crate::report::video`] ([`Outcome::video`]).
    pub video: bool,
}

/// What a finished (or stopped) comparison measured.
pub struct Outcome {
    /// One row group per method that rendered at least one replica.
    pub rows: Vec<MethodResult>,
    /// Per denoiser of the comparison, the rows of its denoised frames (the methods whose every
    /// replica it denoised), in the order of `rows`.
    pub denoised: Vec<(Denoiser, Vec<MethodResult>)>,
    /// Why a denoiser left out rows, one line each (the raw rows are complete regardless).
    pub denoise_errors: Vec<String>,
    /// Replica 0's last frame of every row that has one: the raw rows', then each denoiser's,
    /// each in the order of its rows.
    pub finals: Vec<Final>,
    /// The reference of the last frame.
    pub reference: Obtained,
    /// The reference of every measured frame, in frame order (the last frame's last).
    pub frame_references: Vec<Provenance>,
    /// The regions of the last frame.
    pub regions: Regions,
    /// The references' own frame-to-frame change per area ([`crate::flicker::reference_change`]):
    /// the scale of the rows' flicker; empty without a convergence record.
    pub reference_flicker: Vec<(Area, f64)>,
    /// Replica 0's trajectories and every frame's reference, with the plan's `video`.
    pub video: Option<Video>,
    /// Whether a stop request ended the rendering before every replica was rendered.
    pub interrupted: bool,
    /// The output folder, created and checked before anything rendered.
    pub out: PathBuf,
}

/// What the videos show ([`crate::report::video`]): replica 0's every frame of each raw row,
/// and the reference of each frame.
pub struct Video {
    /// Per frame of the trajectory, the reference mean: the frame's own where it was measured,
    /// else the last frame's.
    pub references: Vec<engine::Image>,
    /// Whether every frame had its own reference (else some show the last frame's).
    pub own_references: bool,
    /// Replica 0's frames per raw row, in the order of [`Outcome::rows`].
    pub trajectories: Vec<VideoTrajectory>,
}

/// One method's frames in a [`Video`]: as rendered, and through each denoiser of the
/// comparison (every frame as the denoiser gives it when that frame is the last,
/// [`engine::denoise::denoise_every_frame`]), or why that failed.
pub struct VideoTrajectory {
    pub spec: String,
    pub frames: Vec<engine::Image>,
    pub denoised: Vec<(Denoiser, Result<Vec<engine::Image>, String>)>,
}

/// Replica 0's last frame of one row: its method's spec and its denoiser (`None`: raw).
pub struct Final {
    pub method: String,
    pub denoiser: Option<Denoiser>,
    pub image: engine::Image,
}

impl Outcome {
    /// Every row group: the raw rows, then each denoiser's.
    pub fn groups(&self) -> Vec<(Option<Denoiser>, &[MethodResult])> {
        std::iter::once((None, &self.rows[..]))
            .chain(self.denoised.iter().map(|(d, g)| (Some(*d), &g[..])))
            .collect()
    }
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

impl Comparison {
    /// The plan's counts within [`sss::limits`], [`crate::limits`] and [`engine::limits`], and the replicas' final frames (kept until the
    /// table is made), replica 0's trajectory with `video`, and one run within the memory
    /// budget.
    fn check(&self) -> Result<(), Error> {
        let invalid = |reason: &str| Err(Error::Invalid(format!("comparison plan: {reason}")));
        if self.methods.is_empty() {
            return invalid("no method given");
        }
        let origin = Path::new("(comparison plan)");
        crate::limits::replicas(origin, "replicas", self.replicas)?;
        if self.first_seed.checked_add(self.replicas as u64).is_none() {
            return invalid(&format!(
                "first seed {} + {} replicas passes the largest seed",
                self.first_seed, self.replicas
            ));
        }
        limits::frames(origin, "frames", self.frames)?;
        if self.equal_time.is_some_and(|t| !(t.is_finite() && t > 0.0)) {
            return invalid("the equal-time budget must be a positive number of seconds");
        }
        let pixels = self.scene.camera.width() as u64 * self.scene.camera.height() as u64;
        // With `video`, replica 0's every frame is kept too.
        let video = if self.video { self.frames as u64 } else { 0 };
        let kept = (self.methods.len() as u64)
            .checked_mul(self.replicas as u64 + video)
            .and_then(|n| n.checked_mul(pixels * IMAGE_BYTES_PER_PIXEL));
        let needed = kept.zip(run_bytes(pixels, self.frames));
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

    /// The seeds of the replicas, `first_seed..first_seed + replicas` (checked by `check`).
    pub fn seeds(&self) -> Range<u64> {
        self.first_seed..self.first_seed.saturating_add(self.replicas as u64)
    }

    /// The reference source of `frame`: the plan's for the last frame; for an earlier one, the
    /// cache at [`Comparison::frame_reference_spp`] (`None` without a cache or a convergence record).
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
/// `replicas`): [`references`], the replicas of the plan's seeds (`render`) and [`reduce`]. A
/// stop request ends it after the current replica with the whole rounds of replicas rendered so
/// far (the first k seeds of every method, `render`; [`Outcome::interrupted`]), or, while a reference
/// renders, with [`Error::Interrupted`].
pub fn run(plan: &Comparison, progress: &mut dyn Progress) -> Result<Outcome, Error> {
    plan.check()?;
    let out = output_dir(&plan.out)?;
    let references = references(plan, progress)?;
    let renders = render_replicas(plan, &references.frames(), plan.seeds(), progress)?;
    let interrupted = progress.stop_requested();
    reduce(plan, references, renders, interrupted, out)
}

/// A comparison's references: the last frame's, and each measured frame's with its regions.
struct References {
    /// The reference of the last frame.
    reference: Obtained,
    /// The provenance of every measured frame's reference, in frame order.
    provenance: Vec<Provenance>,
    /// Every measured frame's reference and regions, in frame order (the last frame last).
    measured: Vec<(FrameReference, Regions)>,
}

impl References {
    /// The measured frames, ascending (the last frame last).
    fn frames(&self) -> Vec<u32> {
        self.measured.iter().map(|(r, _)| r.frame).collect()
    }
}

/// The references of `plan` from its source ([`crate::reference_cache::obtain`]: read from the
/// cache, or rendered into it): the last frame's first, then the earlier frames' of the
/// convergence record.
fn references(plan: &Comparison, progress: &mut dyn Progress) -> Result<References, Error> {
    let scene = &plan.scene;
    // The last frame's reference first: it is the one that matters most, and an interrupted
    // comparison leaves its checkpoint.
    let last_frame = plan.frames - 1;
    let mut measured = Vec::new();
    let mut provenance = Vec::new();
    let mut last: Option<Obtained> = None;
    for frame in std::iter::once(last_frame).chain(0..last_frame) {
        let Some(source) = plan.reference_of(frame) else {
            continue;
        };
        let obtained = reference_cache::obtain(&source, scene, &plan.scene_key, frame, progress)?;
        let regions = Regions::classify(scene, &GBuffer::render(scene, frame), REFERENCE_SEED);
        provenance.push(obtained.provenance());
        measured.push((FrameReference::new(&obtained.reference), regions));
        if frame == last_frame {
            last = Some(obtained);
        }
    }
    measured.rotate_left(1);
    provenance.rotate_left(1);
    Ok(References {
        reference: last.expect("the last frame always has a reference"),
        provenance,
        measured,
    })
}

/// The [`Outcome`] of `renders` (replicas in seed order) against `references`: the rows, the
/// denoised rows, the references' flicker, the video and the final frames.
fn reduce(
    plan: &Comparison,
    references: References,
    renders: Renders,
    interrupted: bool,
    out: PathBuf,
) -> Result<Outcome, Error> {
    let References {
        reference,
        provenance,
        measured: mut references,
    } = references;
    let mut rows = Vec::new();
    for r in renders.runs.iter().filter(|r| !r.replicas.is_empty()) {
        let row = MethodResult::from_replicas(&r.spec, r.method.spp(), &r.replicas, &references)
            .ok_or_else(|| {
                Error::Invalid(format!("{}: image size differs from the reference", r.spec))
            })?;
        rows.push(row);
    }
    let denoised = denoised_rows(plan, &renders.runs, &references);
    let reference_flicker = reference_change(&references);
    let video = plan.video.then(|| video(plan, &renders.runs, &references));
    let (_, regions) = references.pop().expect("the last frame");
    let mut outcome = Outcome {
        rows,
        denoised,
        denoise_errors: renders.denoise_errors.into_iter().map(|f| f.line).collect(),
        finals: Vec::new(),
        reference,
        frame_references: provenance,
        regions,
        reference_flicker,
        video,
        interrupted,
        out,
    };
    outcome.finals = finals(&outcome, &renders.runs);
    Ok(outcome)
}

/// Per denoiser of `plan`, the rows of its denoised frames: the methods of `runs` whose every
/// replica it denoised, measured against `references` (at equal time its seconds counted as one
/// figure, the mean of its timings over these rows).
fn denoised_rows(
    plan: &Comparison,
    runs: &[MethodRuns],
    references: &[(FrameReference, Regions)],
) -> Vec<(Denoiser, Vec<MethodResult>)> {
    plan.denoise
        .iter()
        .map(|&d| {
            let complete: Vec<(&MethodRuns, &Vec<Replica>)> = runs
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
        .collect()
}

/// The [`Video`] of `runs`: replica 0's trajectory of every method that kept one, and per frame
/// of the plan its reference among `references` (the last one's where it has none).
fn video(
    plan: &Comparison,
    runs: &[MethodRuns],
    references: &[(FrameReference, Regions)],
) -> Video {
    let (last, _) = references
        .last()
        .expect("the last frame always has a reference");
    let image = |r: &FrameReference| engine::Image {
        width: plan.scene.camera.width(),
        height: plan.scene.camera.height(),
        pixels: r.mean.iter().map(|p| p.as_vec3()).collect(),
    };
    let mut own = true;
    let frames = (0..plan.frames)
        .map(|f| match references.iter().find(|(r, _)| r.frame == f) {
            Some((r, _)) => image(r),
            None => {
                own = false;
                image(last)
            }
        })
        .collect();
    Video {
        references: frames,
        own_references: own,
        trajectories: runs
            .iter()
            .filter(|r| !r.trajectory.is_empty())
            .map(|r| VideoTrajectory {
                spec: r.spec.clone(),
                frames: r.trajectory.clone(),
                denoised: r.denoised_trajectory.clone(),
            })
            .collect(),
    }
}

/// Replica 0's last frame of every row of `outcome` that has one, from the `runs` it measured,
/// in the order of [`Outcome::groups`].
fn finals(outcome: &Outcome, runs: &[MethodRuns]) -> Vec<Final> {
    let mut finals = Vec::new();
    for (denoiser, group) in outcome.groups() {
        for row in group {
            let run = runs.iter().find(|r| r.spec == row.method);
            let replicas = match denoiser {
                None => run.map(|r| &r.replicas),
                Some(d) => run.and_then(|r| r.denoised.iter().find(|(e, _)| *e == d).map(|x| &x.1)),
            };
            if let Some(image) = replicas.and_then(|r| r.first()?.frames.last()) {
                finals.push(Final {
                    method: row.method.clone(),
                    denoiser,
                    image: image.clone(),
                });
            }
        }
    }
    finals
}

#[cfg(test)]
mod tests;
