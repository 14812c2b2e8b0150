//! `ablation` (issue 10): one ReSTIR preset varied one knob at a time — temporal cap, spatial
//! cap, neighbours, Rao-Blackwellised shading, camera motion, jitter, resolution (2× and 3× the
//! run's) — each row's efficiency `1/(MSE·s)` over 1-spp `pt` per region with its 95% interval
//! (the delta method over replicas, paired by seed, [`lab::uncertainty`]), and its efficiency,
//! MSE and time over the unmodified preset where both ran on the same images. Rows sharing a
//! camera and a resolution are one [`compare`](super::setup::compare()) (`<out>/<group>/`), so
//! their ratios pair by seed. Every row's reuse telemetry ([`lab::telemetry`], CPU backend)
//! comes from separate runs of the same seeds with diagnostics on (which cost time, so they are
//! not the timed runs): `telemetry.md`.

mod rows;
mod tables;

use rows::{CPU_ONLY, Framing, Variation, variations};

use engine::RunConfig;
use serde_json::json;
use sss::scene::{GBuffer, Scene};

use lab::compare::{Comparison, DEFAULT_BASELINE, parse_methods};
use lab::error::Error;
use lab::method_result::{Measured, MethodResult};
use lab::metrics::Area;
use lab::output::{output_dir, write_text};
use lab::progress::Progress;
use lab::reference_cache::{REFERENCE_SEED, ReferenceSource};
use lab::regions::{Region, Regions};
use lab::report::tables::milliseconds;
use lab::scenes::{load_scene, with_resolution};
use lab::telemetry::{self, RegionSummary};
use lab::uncertainty::INTERVAL_METHOD;
use methods::restir;

use super::setup::{FRAMES, Report, Settings, compare};
use tables::{findings, markdown, row_json, telemetry_markdown};

/// The ReSTIR method ablated unless `--methods` names others.
pub const DEFAULT_BASE: &str = "restir:hybrid";

/// The built-in scene ablated unless `--scene` names another.
pub const DEFAULT_SCENE: &str = "bumpy";

/// Samples per pixel of one reference batch.
const REFERENCE_BATCH_SPP: u32 = 128;

/// The efficiency ratio of every row over `pt` and over its base's default row per region.
pub(super) struct Measurement {
    pub(super) variation: Variation,
    pub(super) over_pt: Vec<Option<Measured>>,
    /// `None` where the default row ran on other images (another camera or resolution).
    pub(super) over_default: Option<Vec<Option<Measured>>>,
    /// Milliseconds per frame of the row and of its `pt`.
    pub(super) milliseconds: (Measured, Option<Measured>),
    /// MSE over the default row per region at equal spp, and seconds per frame over the default
    /// row (both paired by seed); `None` like `over_default`.
    pub(super) mse_over_default: Option<(Vec<Option<Measured>>, Option<Measured>)>,
    /// `None` on a backend without telemetry.
    pub(super) telemetry: Option<Vec<RegionSummary>>,
}

pub fn run(settings: &Settings, progress: &mut dyn Progress) -> Result<Report, Error> {
    let scene_name = match settings.scenes.as_slice() {
        [] => DEFAULT_SCENE,
        [one] => one.as_str(),
        more => {
            return Err(Error::Invalid(format!(
                "ablation runs one scene, not {}",
                more.join(",")
            )));
        }
    };
    let bases: Vec<&str> = if settings.methods.is_empty() {
        vec![DEFAULT_BASE]
    } else {
        settings.methods.iter().map(String::as_str).collect()
    };
    if let Some(bad) = bases.iter().find(|b| !b.starts_with("restir:")) {
        return Err(Error::Invalid(format!(
            "ablation varies ReSTIR methods; {bad} is not one (restir:<preset>[/modifier…])"
        )));
    }
    let root = output_dir(&settings.out_dir("ablation"))?;
    // The unclamped radius and the mean and L2 targets have no Vulkan kernel: CPU rows only.
    let cpu = matches!(settings.backend, engine::Backend::Cpu);
    let rows: Vec<Variation> = bases
        .iter()
        .flat_map(|b| variations(b, settings.resolution))
        .filter(|v| cpu || !CPU_ONLY.iter().any(|m| v.spec.contains(m)))
        .collect();
    let mut groups: Vec<String> = rows.iter().map(Variation::group).collect();
    groups.sort();
    groups.dedup();
    let mut measured = Vec::new();
    let mut runs = Vec::new();
    for group in &groups {
        let members: Vec<&Variation> = rows.iter().filter(|v| &v.group() == group).collect();
        let first = members[0];
        let plan = group_plan(settings, scene_name, first, &members, &root.join(group))?;
        let (outcome, written) = compare(&plan, progress)?;
        let pt = outcome.rows.iter().find(|r| r.method == DEFAULT_BASELINE);
        let last = GBuffer::render(&plan.scene, FRAMES - 1);
        let regions = Regions::classify(&plan.scene, &last, REFERENCE_SEED);
        for v in members {
            let Some(row) = outcome.rows.iter().find(|r| r.method == v.spec) else {
                continue;
            };
            let base = bases
                .iter()
                .filter(|b| v.spec.starts_with(**b))
                .max_by_key(|b| b.len());
            let default = base.and_then(|b| outcome.rows.iter().find(|r| r.method == *b));
            // The default row against itself says nothing: it is left out.
            let own_group = v.framing == Framing::SCENE
                && v.resolution == settings.resolution
                && Some(&row.method) != default.map(|d| &d.method);
            measured.push(Measurement {
                variation: v.clone(),
                over_pt: ratios(row, pt),
                over_default: own_group.then(|| ratios(row, default)),
                milliseconds: (
                    milliseconds(&row.seconds),
                    pt.map(|p| milliseconds(&p.seconds)),
                ),
                mse_over_default: default.filter(|_| own_group).map(|d| {
                    let time = row.seconds.ln().zip(d.seconds.ln());
                    let time = time.and_then(|(a, b)| a.minus(&b));
                    (mse_ratios(row, d), time.as_ref().map(Measured::of_log))
                }),
                telemetry: reuse_telemetry(settings, &plan.scene, &v.spec)?
                    .map(|runs| telemetry::summarise(&runs, &regions)),
            });
        }
        runs.push(json!({ "group": group, "results": written.results.to_json() }));
    }
    // Table order: the rows' own order.
    measured.sort_by_key(|m| rows.iter().position(|v| *v == m.variation));
    let table = markdown(&measured, scene_name, settings);
    let findings = findings(&measured);
    let json = json!({
        "schema": "reshift-ablation/2",
        "scene": scene_name,
        "replicas": settings.replicas,
        "frames": FRAMES,
        "reference_spp": settings.reference_spp,
        "interval": INTERVAL_METHOD,
        "confidence": lab::uncertainty::CONFIDENCE,
        "rows": measured.iter().map(row_json).collect::<Vec<_>>(),
        "runs": runs,
    });
    write_text(&root.join("telemetry.md"), &telemetry_markdown(&measured))?;
    let report = Report {
        table,
        findings,
        out: root,
        json,
    }
    .write()?;
    write_text(
        &report.out.join("results.json"),
        &serde_json::to_string_pretty(&report.json).expect("JSON values"),
    )?;
    Ok(report)
}

/// The comparison of `members` (one camera and resolution) and `pt` at equal spp, measuring
/// the last frame against a cached reference of the camera's own images.
fn group_plan(
    settings: &Settings,
    scene_name: &str,
    first: &Variation,
    members: &[&Variation],
    out: &std::path::Path,
) -> Result<Comparison, Error> {
    let loaded = load_scene(scene_name)?;
    let scene = first
        .framing
        .apply(with_resolution(loaded.scene, Some(first.resolution)));
    let key = match first.framing {
        Framing::SCENE => loaded.key,
        other => format!("{}-{}", loaded.key, other.name()),
    };
    let mut specs = vec![DEFAULT_BASELINE.to_string()];
    specs.extend(members.iter().map(|v| v.spec.clone()));
    Ok(Comparison {
        scene,
        scene_key: key,
        methods: parse_methods(&specs)?,
        baseline: DEFAULT_BASELINE.into(),
        replicas: settings.replicas,
        first_seed: 0,
        frames: FRAMES,
        equal_time: None,
        reference: ReferenceSource::Cache {
            dir: settings.cache.clone(),
            spp: settings.reference_spp,
            batch_spp: REFERENCE_BATCH_SPP,
        },
        frame_reference_spp: None,
        out: out.to_path_buf(),
        backend: settings.backend.clone(),
        video: false,
        denoise: Vec::new(),
    })
}

/// The reuse telemetry of the last frame of replicas `0..K` of ReSTIR method `spec` (runs with
/// diagnostics on); `None` on a backend that records none.
fn reuse_telemetry(
    settings: &Settings,
    scene: &Scene,
    spec: &str,
) -> Result<Option<Vec<engine::diagnostics::Telemetry>>, Error> {
    let preset = restir::preset(spec.strip_prefix("restir:"))
        .map_err(|reason| Error::Invalid(format!("{spec}: {reason}")))?;
    let mut runs = Vec::new();
    for seed in 0..settings.replicas as u64 {
        let config = RunConfig {
            seed,
            frames: FRAMES,
            collect_diagnostics: true,
        };
        let run = settings.backend.run(scene, &preset, &config)?;
        match run.diagnostics.and_then(|d| d.telemetry) {
            Some(t) => runs.push(t),
            None => return Ok(None),
        }
    }
    Ok(Some(runs))
}

/// `row`'s efficiency ratio over `baseline` per region of [`Region::ALL`].
fn ratios(row: &MethodResult, baseline: Option<&MethodResult>) -> Vec<Option<Measured>> {
    Region::ALL
        .iter()
        .map(|&r| baseline.and_then(|b| row.efficiency_ratio(b, Area::Region(r))))
        .collect()
}

/// `row`'s MSE over `other`'s per region of [`Region::ALL`] (equal spp, paired by seed).
fn mse_ratios(row: &MethodResult, other: &MethodResult) -> Vec<Option<Measured>> {
    Region::ALL
        .iter()
        .map(|&r| row.mse_ratio(other, Area::Region(r)))
        .collect()
}
