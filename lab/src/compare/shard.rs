//! Shards of a comparison (`reshift compare --shard i/n`, docs/cluster.md): shard `i` obtains
//! the references as one run does (from the shared cache, rendering what is missing) and renders
//! the replicas of its seeds ([`crate::shard::seeds`]) of every method. Its metrics need every
//! replica's frames at every pixel, so the shard keeps them whole: a JSON header
//! ([`CompareShard`], schema [`SHARD_SCHEMA`]: the plan, each replica's timings, counts and
//! spp) and beside it a binary payload (`shard-i-of-n.bin`) of raw little-endian `f32` images.
//! [`merge`] reads the shards in seed order, obtains the references again and reduces them with
//! the function [`super::run`] uses, so every measured figure and image is that of one run bit
//! for bit; only the timings are measurements, kept per replica as each shard measured them.

use std::path::{Path, PathBuf};

use engine::Backend;
use engine::denoise::Denoiser;
use glam::Vec3;
use methods::Method;
use serde::{Deserialize, Serialize};
use serde_json::Value;

use super::render::{DenoiseFailure, MethodRuns, Renders, render_replicas};
use super::{Comparison, Outcome, reduce, references};
use crate::error::Error;
use crate::method_result::Replica;
use crate::output::output_dir;
use crate::progress::Progress;
use crate::reference_cache::ReferenceSource;
use crate::scenes::{load_scene, with_resolution};
use crate::shard::{CODE_VERSION, Exact, MAX_SHARD_BYTES, Part, Shard, check_set, seeds};

/// The schema name of a comparison shard's header file.
pub const SHARD_SCHEMA: &str = "reshift-compare-shard/1";

/// Everything that determines a comparison's measured figures: shards of different plans do
/// not merge.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ShardPlan {
    /// The version of the code (`reshift --version`).
    pub version: String,
    /// The scene's cache key: its built-in name, or the scene file's stem and text hash (and
    /// the trajectory's).
    pub scene: String,
    /// The method specs, in the comparison's order.
    pub methods: Vec<String>,
    pub baseline: String,
    /// `WxH`.
    pub resolution: String,
    pub frames: u32,
    /// N: the seeds `S..S+N` over all shards.
    pub replicas: u32,
    /// S, the seed of the first replica (absent in shards that predate it: 0).
    #[serde(default)]
    pub first_seed: u64,
    /// The frames every replica keeps (the convergence record's), ascending.
    pub measured_frames: Vec<u32>,
    /// The last frame's reference: `cache, S spp in batches of B` or `file <path>`.
    pub reference: String,
    /// Samples per pixel of the earlier frames' references (none: the last frame only).
    pub frame_reference_spp: Option<u32>,
    pub denoisers: Vec<String>,
    /// `cpu` or `vulkan (<device>)`: the backends' images differ in their last bits.
    pub backend: String,
    pub video: bool,
    /// The shard count n.
    pub shards: u32,
}

/// One shard of a comparison as its header file holds it; its images are in the payload beside
/// it, in the order [`payload_images`] gives.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct CompareShard {
    /// [`SHARD_SCHEMA`].
    pub schema: String,
    /// This shard's index i (its count n is the plan's `shards`).
    pub index: u32,
    pub plan: ShardPlan,
    /// The seeds it rendered, `start..end`.
    pub seeds: [u64; 2],
    /// The scene as named when the shard ran, and the trajectory file it replayed, for the
    /// merge to load them again; the plan's `scene` checks that they are the same.
    pub scene_path: String,
    pub trajectory: Option<String>,
    /// The folder of cached references (none: the reference is a file, named in the plan).
    pub cache: Option<String>,
    /// Per method, in the plan's order.
    pub methods: Vec<MethodPart>,
    /// The denoisers that failed, in the order they failed.
    pub(super) denoise_errors: Vec<DenoiseFailure>,
}

/// One method's replicas of a shard, without their images.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct MethodPart {
    /// Per replica in seed order.
    pub replicas: Vec<Measured>,
    /// Per denoiser that denoised every replica, its denoised replicas in seed order.
    pub denoised: Vec<(String, Vec<Measured>)>,
    /// Whether the payload holds replica 0's whole trajectory (the shard of the first seed, with
    /// video).
    pub trajectory: bool,
    /// Replica 0's trajectory through each denoiser: in the payload, or why it failed.
    pub denoised_trajectory: Vec<(String, Result<(), String>)>,
}

/// What a replica measured besides its images.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Measured {
    pub seconds_per_frame: Exact,
    pub wall_seconds_per_frame: Exact,
    pub denoiser_seconds_per_frame: Exact,
    pub frames_rendered: u32,
    pub nonfinite: u64,
    pub spp: Exact,
}

impl Part for CompareShard {
    fn plan(&self) -> Value {
        serde_json::to_value(&self.plan).expect("plain data serializes")
    }

    fn shard(&self) -> Shard {
        Shard {
            index: self.index,
            count: self.plan.shards,
        }
    }
}

/// The payload file of the header file `path`: `shard-i-of-n.bin` beside `shard-i-of-n.json`.
pub fn payload_path(path: &Path) -> PathBuf {
    path.with_extension("bin")
}

impl Measured {
    fn of(r: &Replica) -> Measured {
        Measured {
            seconds_per_frame: Exact(r.seconds_per_frame),
            wall_seconds_per_frame: Exact(r.wall_seconds_per_frame),
            denoiser_seconds_per_frame: Exact(r.denoiser_seconds_per_frame),
            frames_rendered: r.frames_rendered,
            nonfinite: r.nonfinite,
            spp: Exact(r.spp),
        }
    }

    fn replica(&self, frames: Vec<engine::Image>) -> Replica {
        Replica {
            frames,
            seconds_per_frame: self.seconds_per_frame.0,
            wall_seconds_per_frame: self.wall_seconds_per_frame.0,
            denoiser_seconds_per_frame: self.denoiser_seconds_per_frame.0,
            frames_rendered: self.frames_rendered,
            nonfinite: self.nonfinite,
            spp: self.spp.0,
        }
    }
}

/// The plan of `plan` as shard `shard` of it states it.
fn shard_plan(plan: &Comparison, measured_frames: Vec<u32>, shard: Shard) -> ShardPlan {
    ShardPlan {
        version: CODE_VERSION.to_string(),
        scene: plan.scene_key.clone(),
        methods: plan.methods.iter().map(|(s, _)| s.clone()).collect(),
        baseline: plan.baseline.clone(),
        resolution: format!(
            "{}x{}",
            plan.scene.camera.width(),
            plan.scene.camera.height()
        ),
        frames: plan.frames,
        replicas: plan.replicas,
        first_seed: plan.first_seed,
        measured_frames,
        reference: match &plan.reference {
            ReferenceSource::Cache { spp, batch_spp, .. } => {
                format!("cache, {spp} spp in batches of {batch_spp}")
            }
            ReferenceSource::File(path) => format!("file {}", path.display()),
        },
        frame_reference_spp: plan.frame_reference_spp,
        denoisers: plan.denoise.iter().map(Denoiser::to_string).collect(),
        backend: plan.backend.to_string(),
        video: plan.video,
        shards: shard.count,
    }
}

/// Renders shard `shard` of `plan` (the scene named `scene_path`, replaying `trajectory`) and
/// writes its header `<out>/shard-i-of-n.json` and payload `shard-i-of-n.bin` (the payload
/// first: a header names a whole shard); returns the header's path. Equal time is refused (its
/// calibration is a measurement of one process); a stop request before the last replica is
/// [`Error::Interrupted`] and writes nothing.
pub fn run_shard(
    plan: &Comparison,
    scene_path: &str,
    trajectory: Option<&Path>,
    shard: Shard,
    progress: &mut dyn Progress,
) -> Result<PathBuf, Error> {
    if plan.equal_time.is_some() {
        return Err(Error::Invalid(
            "--equal-time with --shard: the budget is calibrated by one process's clock, so \
             shards would not share it; run an equal-time comparison whole"
                .into(),
        ));
    }
    plan.check()?;
    let out = output_dir(&plan.out)?;
    let references = references(plan, progress)?;
    let range = seeds(shard, plan.replicas, plan.first_seed);
    let renders = render_replicas(plan, &references.frames(), range.clone(), progress)?;
    let rendered = renders.runs.iter().map(|r| r.replicas.len()).min();
    if progress.stop_requested() || rendered.unwrap_or(0) < (range.end - range.start) as usize {
        return Err(Error::Interrupted(format!(
            "shard {}/{} interrupted before its {} replicas of each method; nothing written",
            shard.index,
            shard.count,
            range.end - range.start
        )));
    }
    let header = CompareShard {
        schema: SHARD_SCHEMA.to_string(),
        index: shard.index,
        plan: shard_plan(plan, references.frames(), shard),
        seeds: [range.start, range.end],
        scene_path: scene_path.to_string(),
        trajectory: trajectory.map(|p| p.display().to_string()),
        cache: match &plan.reference {
            ReferenceSource::Cache { dir, .. } => Some(dir.display().to_string()),
            ReferenceSource::File(_) => None,
        },
        methods: renders.runs.iter().map(method_part).collect(),
        denoise_errors: renders.denoise_errors.clone(),
    };
    let path = out.join(crate::shard::file_name(shard));
    let mut bytes = Vec::new();
    for image in payload_images(&renders.runs) {
        for p in &image.pixels {
            for c in p.to_array() {
                bytes.extend_from_slice(&c.to_le_bytes());
            }
        }
    }
    let io = |p: &Path, e: std::io::Error| Error::Io(format!("{}: {e}", p.display()));
    std::fs::write(payload_path(&path), bytes).map_err(|e| io(&payload_path(&path), e))?;
    let text = serde_json::to_string_pretty(&header).expect("plain data serializes");
    std::fs::write(&path, text).map_err(|e| io(&path, e))?;
    Ok(path)
}

fn method_part(run: &MethodRuns) -> MethodPart {
    MethodPart {
        replicas: run.replicas.iter().map(Measured::of).collect(),
        denoised: run
            .denoised
            .iter()
            .map(|(d, list)| (d.to_string(), list.iter().map(Measured::of).collect()))
            .collect(),
        trajectory: !run.trajectory.is_empty(),
        denoised_trajectory: run
            .denoised_trajectory
            .iter()
            .map(|(d, r)| (d.to_string(), r.as_ref().map(|_| ()).map_err(Clone::clone)))
            .collect(),
    }
}

/// The images of `runs` in payload order: per method, each replica's measured frames, then per
/// denoiser its denoised last frames, then replica 0's trajectory and its denoised ones.
fn payload_images(runs: &[MethodRuns]) -> impl Iterator<Item = &engine::Image> {
    runs.iter().flat_map(|r| {
        let raw = r.replicas.iter().flat_map(|x| &x.frames);
        let denoised = r
            .denoised
            .iter()
            .flat_map(|(_, l)| l.iter().flat_map(|x| &x.frames));
        let trajectories = r
            .denoised_trajectory
            .iter()
            .filter_map(|(_, t)| t.as_ref().ok());
        raw.chain(denoised)
            .chain(&r.trajectory)
            .chain(trajectories.flatten())
    })
}

/// Reads images of `width × height` one after another from a payload, refusing one that ends
/// early or holds more than its header says.
struct Payload<'a> {
    path: &'a Path,
    floats: std::slice::ChunksExact<'a, u8>,
    width: u32,
    height: u32,
}

impl Payload<'_> {
    fn image(&mut self) -> Result<engine::Image, Error> {
        let pixels = self.width as usize * self.height as usize;
        let mut read = Vec::with_capacity(pixels);
        for _ in 0..pixels {
            let mut c = [0f32; 3];
            for x in &mut c {
                let bytes = self.floats.next().ok_or_else(|| self.short())?;
                *x = f32::from_le_bytes(bytes.try_into().expect("chunks of 4"));
            }
            read.push(Vec3::from_array(c));
        }
        Ok(engine::Image {
            width: self.width,
            height: self.height,
            pixels: read,
        })
    }

    fn images(&mut self, n: usize) -> Result<Vec<engine::Image>, Error> {
        (0..n).map(|_| self.image()).collect()
    }

    fn short(&self) -> Error {
        Error::Invalid(format!(
            "{}: ends before the images its header names",
            self.path.display()
        ))
    }
}

/// The [`MethodRuns`] of one method of shard `shard` (header at `path`), its images read from
/// `payload`.
fn method_runs(
    spec: &str,
    part: &MethodPart,
    frames: &ShardPlan,
    payload: &mut Payload,
) -> Result<MethodRuns, Error> {
    let bad = |what: String| Error::Invalid(format!("{}: {spec}: {what}", payload.path.display()));
    let denoiser =
        |name: &str| Denoiser::parse(name).ok_or_else(|| bad(format!("unknown denoiser {name:?}")));
    let measured = frames.measured_frames.len();
    let replicas = (part.replicas.iter())
        .map(|m| Ok(m.replica(payload.images(measured)?)))
        .collect::<Result<Vec<_>, Error>>()?;
    let mut denoised = Vec::new();
    for (name, list) in &part.denoised {
        if list.len() != replicas.len() {
            return Err(bad(format!(
                "{} {name} replicas, {} raw ones",
                list.len(),
                replicas.len()
            )));
        }
        let list = (list.iter())
            .map(|m| Ok(m.replica(payload.images(1)?)))
            .collect::<Result<Vec<_>, Error>>()?;
        denoised.push((denoiser(name)?, list));
    }
    let length = frames.frames as usize;
    let trajectory = match part.trajectory {
        true => payload.images(length)?,
        false => Vec::new(),
    };
    let mut denoised_trajectory = Vec::new();
    for (name, result) in &part.denoised_trajectory {
        let frames = match result {
            Ok(()) => Ok(payload.images(length)?),
            Err(e) => Err(e.clone()),
        };
        denoised_trajectory.push((denoiser(name)?, frames));
    }
    Ok(MethodRuns {
        spec: spec.to_string(),
        method: Method::parse(spec)?,
        replicas,
        denoised,
        trajectory,
        denoised_trajectory,
    })
}

/// The runs of shard `part` (header at `path`), its payload read after checking its length
/// against the header's images.
fn read_runs(path: &Path, part: &CompareShard) -> Result<Vec<MethodRuns>, Error> {
    let p = &part.plan;
    let bad = |what: String| Error::Invalid(format!("{}: {what}", path.display()));
    let (width, height) = resolution(path, p)?;
    if part.methods.len() != p.methods.len() {
        return Err(bad(format!(
            "{} method parts, the plan {} methods",
            part.methods.len(),
            p.methods.len()
        )));
    }
    let expected = seeds(part.shard(), p.replicas, p.first_seed);
    if part.seeds != [expected.start, expected.end] {
        return Err(bad(format!(
            "holds seeds {}..{}, its part is {}..{}",
            part.seeds[0], part.seeds[1], expected.start, expected.end
        )));
    }
    let holds_first_seed = p.video && expected.contains(&p.first_seed);
    let mut images: u64 = 0;
    for m in &part.methods {
        if m.replicas.len() as u64 != expected.end - expected.start {
            return Err(bad(format!(
                "{} replicas of a method, its part is {}..{}",
                m.replicas.len(),
                expected.start,
                expected.end
            )));
        }
        if m.trajectory != holds_first_seed {
            return Err(bad(format!(
                "field 'trajectory' is {}: only the shard of the first seed keeps one, with video",
                m.trajectory
            )));
        }
        let denoised: u64 = m.denoised.iter().map(|(_, l)| l.len() as u64).sum();
        let trajectories = m.trajectory as u64
            + m.denoised_trajectory
                .iter()
                .filter(|(_, r)| r.is_ok())
                .count() as u64;
        images += m.replicas.len() as u64 * p.measured_frames.len() as u64
            + denoised
            + trajectories * p.frames as u64;
    }
    let payload_path = payload_path(path);
    let bytes_per_image = width as u64 * height as u64 * 12;
    let size = images
        .checked_mul(bytes_per_image)
        .filter(|&b| b <= MAX_SHARD_BYTES);
    let Some(size) = size else {
        return Err(bad(format!(
            "its header names {images} images of {width}×{height}, more than a shard may hold"
        )));
    };
    let actual = std::fs::metadata(&payload_path)
        .map_err(|e| Error::Io(format!("{}: {e}", payload_path.display())))?
        .len();
    if actual != size {
        return Err(Error::Invalid(format!(
            "{}: {actual} bytes, its header {} names {size} ({images} images of {width}×{height})",
            payload_path.display(),
            path.display()
        )));
    }
    let bytes = geometry::limits::read_file(&payload_path, size)?;
    let mut payload = Payload {
        path: &payload_path,
        floats: bytes.chunks_exact(4),
        width,
        height,
    };
    let runs = (p.methods.iter().zip(&part.methods))
        .map(|(spec, m)| method_runs(spec, m, p, &mut payload))
        .collect::<Result<Vec<_>, Error>>()?;
    match payload.floats.next() {
        Some(_) => Err(bad("its payload holds more than its header names".into())),
        None => Ok(runs),
    }
}

/// `WxH` of the plan.
fn resolution(path: &Path, p: &ShardPlan) -> Result<(u32, u32), Error> {
    (p.resolution.split_once('x'))
        .and_then(|(w, h)| Some((w.parse().ok()?, h.parse().ok()?)))
        .filter(|&(w, h): &(u32, u32)| w > 0 && h > 0)
        .ok_or_else(|| {
            Error::Invalid(format!(
                "{}: field 'resolution' is {:?}, not WxH",
                path.display(),
                p.resolution
            ))
        })
}

/// The comparison of the whole run from its shards (each with its header file, in any order)
/// and the plan it ran, its report to go to `out`: after [`check_set`], the references obtained
/// as the shards obtained them, the replicas of every shard in seed order, reduced as
/// [`super::run`] reduces them. A denoiser's row is kept where every shard denoised every
/// replica of its method; the failures are those one run would have met first.
pub fn merge(
    parts: Vec<(PathBuf, CompareShard)>,
    out: PathBuf,
    progress: &mut dyn Progress,
) -> Result<(Comparison, Outcome), Error> {
    let parts = check_set(parts)?;
    let (first_path, first) = &parts[0];
    let plan = Comparison {
        out,
        ..rebuilt_plan(first_path, first)?
    };
    plan.check()?;
    let out = output_dir(&plan.out)?;
    let references = references(&plan, progress)?;
    if references.frames() != first.plan.measured_frames {
        return Err(Error::Invalid(format!(
            "{}: field 'measured_frames' is {:?}, the references now give {:?}",
            first_path.display(),
            first.plan.measured_frames,
            references.frames()
        )));
    }
    let mut runs: Option<Vec<MethodRuns>> = None;
    let mut failures: Vec<DenoiseFailure> = Vec::new();
    for (path, part) in &parts {
        let part_runs = read_runs(path, part)?;
        runs = Some(match runs {
            None => part_runs,
            Some(runs) => runs.into_iter().zip(part_runs).map(joined).collect(),
        });
        for f in &part.denoise_errors {
            let met = |g: &DenoiseFailure| {
                g.denoiser == f.denoiser && (g.method.is_none() || g.method == f.method)
            };
            if !failures.iter().any(met) {
                failures.push(f.clone());
            }
        }
    }
    let renders = Renders {
        runs: runs.expect("check_set returns at least one shard"),
        denoise_errors: failures,
    };
    let outcome = reduce(&plan, references, renders, false, out)?;
    Ok((plan, outcome))
}

/// Two shards' runs of one method, `b`'s seeds after `a`'s: a denoiser stays where both kept
/// it, the trajectories come from the shard that has them.
fn joined((mut a, b): (MethodRuns, MethodRuns)) -> MethodRuns {
    a.replicas.extend(b.replicas);
    let mut theirs = b.denoised;
    a.denoised.retain_mut(|(d, list)| {
        let other = theirs.iter_mut().find(|(e, _)| e == d);
        other.map(|(_, l)| list.append(l)).is_some()
    });
    if a.trajectory.is_empty() {
        a.trajectory = b.trajectory;
        a.denoised_trajectory = b.denoised_trajectory;
    }
    a
}

/// The [`Comparison`] a shard ran: its scene (and trajectory) loaded again and checked to be the
/// same by its cache key, at the plan's resolution, its methods and denoisers parsed, its
/// reference from the same source, on the backend it names.
fn rebuilt_plan(path: &Path, shard: &CompareShard) -> Result<Comparison, Error> {
    let p = &shard.plan;
    let bad = |what: String| Error::Invalid(format!("{}: {what}", path.display()));
    let mut loaded = load_scene(&shard.scene_path)?;
    if let Some(t) = &shard.trajectory {
        loaded = loaded.on_trajectory(Path::new(t))?.0;
    }
    if loaded.key != p.scene {
        return Err(bad(format!(
            "field 'scene' is {:?}, but {} is now {:?}: the scene changed since the shards ran",
            p.scene, shard.scene_path, loaded.key
        )));
    }
    let reference = match (&shard.cache, p.reference.strip_prefix("file ")) {
        (None, Some(file)) => ReferenceSource::File(PathBuf::from(file)),
        (Some(dir), None) => {
            let settings = (p.reference.strip_prefix("cache, "))
                .and_then(|r| r.split_once(" spp in batches of "))
                .and_then(|(s, b)| Some((s.parse().ok()?, b.parse().ok()?)));
            let (spp, batch_spp) =
                settings.ok_or_else(|| bad(format!("field 'reference' is {:?}", p.reference)))?;
            ReferenceSource::Cache {
                dir: PathBuf::from(dir),
                spp,
                batch_spp,
            }
        }
        _ => return Err(bad(format!("field 'reference' is {:?}", p.reference))),
    };
    let backend = match p.backend.as_str() {
        "cpu" => Backend::Cpu,
        name => {
            let device = name
                .strip_prefix("vulkan (")
                .and_then(|d| d.strip_suffix(')'));
            let opened = device.and_then(|d| Backend::vulkan(Some(d), false).ok());
            opened
                .filter(|b| b.to_string() == name)
                .ok_or_else(|| bad(format!("field 'backend' is {name:?}: not available here")))?
        }
    };
    let denoise = (p.denoisers.iter())
        .map(|d| Denoiser::parse(d).ok_or_else(|| bad(format!("unknown denoiser {d:?}"))))
        .collect::<Result<_, _>>()?;
    Ok(Comparison {
        scene: with_resolution(loaded.scene, Some(resolution(path, p)?)),
        scene_key: p.scene.clone(),
        methods: super::parse_methods(&p.methods)?,
        baseline: p.baseline.clone(),
        replicas: p.replicas,
        first_seed: p.first_seed,
        frames: p.frames,
        equal_time: None,
        reference,
        frame_reference_spp: p.frame_reference_spp,
        out: PathBuf::new(),
        backend,
        denoise,
        video: p.video,
    })
}

#[cfg(test)]
mod tests;
