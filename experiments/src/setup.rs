//! What every experiment shares: its [`Settings`], its [`Report`], its output folder and the
//! equal-time comparison it runs, run and written ([`compare()`]).

use std::path::{Path, PathBuf};

use engine::Backend;
use serde_json::Value;
use sss::InputError;
use sss::limits;

use lab::compare::{
    self, Comparison, DEFAULT_BASELINE, Outcome, frame_reference_spp, parse_methods,
};
use lab::error::Error;
use lab::output::write_text;
use lab::progress::Progress;
use lab::reference_cache::ReferenceSource;
use lab::report::{self, Written};
use lab::scenes::{load_scene, with_resolution};
use methods::Method;

/// Frames of every experiment's camera trajectory.
pub const FRAMES: u32 = 16;

/// Samples per pixel of one reference batch in experiments.
const REFERENCE_BATCH_SPP: u32 = 128;

/// How an experiment runs.
#[derive(Clone, Debug)]
pub struct Settings {
    /// Independent replicas per method.
    pub replicas: u32,
    /// Image size.
    pub resolution: (u32, u32),
    /// Samples per pixel of the references (a multiple ≥ 2× of 128).
    pub reference_spp: u32,
    /// Output folder; `None`: `out/experiment-<name>`.
    pub out: Option<PathBuf>,
    /// Folder of cached references.
    pub cache: PathBuf,
    pub backend: Backend,
    /// The scenes of an experiment that runs several ([`super::Experiment::takes_scenes`]);
    /// empty: its own list.
    pub scenes: Vec<String>,
    /// The methods of an experiment that takes them ([`super::Experiment::takes_methods`]);
    /// empty: its own.
    pub methods: Vec<String>,
}

/// What an experiment produced.
pub struct Report {
    /// Its measurements as Markdown.
    pub table: String,
    /// Its findings table ([`crate::findings::markdown`]).
    pub findings: String,
    /// The folder with every output.
    pub out: PathBuf,
    /// Its measurements as JSON (`reshift-compare/1` for a single comparison).
    pub json: Value,
}

impl Settings {
    /// The replicas and the resolution within [`crate::limits`] and [`sss::limits`].
    pub fn check(&self) -> Result<(), InputError> {
        let origin = Path::new("(experiment settings)");
        let (width, height) = self.resolution;
        lab::limits::replicas(origin, "replicas", self.replicas)?;
        limits::resolution(origin, "resolution", width, height)
    }

    /// The output folder of experiment `name`.
    pub fn out_dir(&self, name: &str) -> PathBuf {
        self.out
            .clone()
            .unwrap_or_else(|| PathBuf::from(format!("out/experiment-{name}")))
    }
}

impl Report {
    /// The report of a single comparison with its findings, which are written to
    /// `findings.md` beside its other outputs.
    pub fn of_comparison(
        outcome: &Outcome,
        written: Written,
        findings: String,
    ) -> Result<Report, Error> {
        write_text(&outcome.out.join("findings.md"), &findings)?;
        Ok(Report {
            table: written.markdown,
            findings,
            json: written.results.to_json(),
            out: outcome.out.clone(),
        })
    }

    /// Writes `table.md` and `findings.md` into `out`.
    pub fn write(self) -> Result<Report, Error> {
        write_text(&self.out.join("table.md"), &self.table)?;
        write_text(&self.out.join("findings.md"), &self.findings)?;
        Ok(self)
    }
}

/// Runs `comparison` ([`compare::run`]) and writes its outputs into its folder
/// ([`report::write`]).
pub fn compare(
    comparison: &Comparison,
    progress: &mut dyn Progress,
) -> Result<(Outcome, Written), Error> {
    let outcome = compare::run(comparison, progress)?;
    let written = report::write(comparison, &outcome)?;
    Ok((outcome, written))
}

/// The comparison of `methods` on built-in `scene` into `out`, the path tracer at the
/// per-frame time of `restir:hybrid` on this scene and backend (the median of 3 runs).
pub fn equal_time_comparison(
    settings: &Settings,
    scene: &str,
    methods: &[&str],
    out: &Path,
) -> Result<Comparison, Error> {
    let loaded = load_scene(scene)?;
    let scene_at = with_resolution(loaded.scene, Some(settings.resolution));
    let hybrid = Method::parse("restir:hybrid")?;
    let mut times = (0..3)
        .map(|seed| {
            Ok(hybrid
                .render_on(&settings.backend, &scene_at, FRAMES, 1_000_000 + seed)?
                .seconds_per_frame)
        })
        .collect::<Result<Vec<f64>, Error>>()?;
    times.sort_by(f64::total_cmp);
    Ok(Comparison {
        scene: scene_at,
        scene_key: loaded.key,
        methods: parse_methods(methods)?,
        baseline: DEFAULT_BASELINE.into(),
        replicas: settings.replicas,
        first_seed: 0,
        frames: FRAMES,
        equal_time: Some(times[1]),
        reference: ReferenceSource::Cache {
            dir: settings.cache.clone(),
            spp: settings.reference_spp,
            batch_spp: REFERENCE_BATCH_SPP,
        },
        frame_reference_spp: Some(frame_reference_spp(
            settings.reference_spp,
            REFERENCE_BATCH_SPP,
        )),
        out: out.to_path_buf(),
        backend: settings.backend.clone(),
        video: false,
        denoise: Vec::new(),
    })
}
