//! `ablation` (issue 10): one ReSTIR preset varied one knob at a time — temporal cap, spatial
//! cap, neighbours, Rao-Blackwellised shading, camera motion, jitter, resolution (2× and 3× the
//! run's) — each row's efficiency `1/(MSE·s)` over 1-spp `pt` per region with its 95% interval
//! (the delta method over replicas, paired by seed, [`crate::uncertainty`]), and its efficiency,
//! MSE and time over the unmodified preset where both ran on the same images. Rows sharing a camera and a resolution are one
//! [`compare::run`] (`<out>/<group>/`), so their ratios pair by seed. Every row's reuse
//! telemetry ([`crate::telemetry`], CPU backend) comes from separate runs of the same seeds
//! with diagnostics on (which cost time, so they are not the timed runs): `telemetry.md`.

use engine::RunConfig;
use serde_json::{Value, json};
use sss::scene::{GBuffer, Scene};

use crate::compare::{self, DEFAULT_BASELINE, Plan, parse_methods};
use crate::error::Error;
use crate::method_result::{Measured, MethodResult};
use crate::methods::restir;
use crate::metrics::Area;
use crate::progress::Progress;
use crate::reference_cache::{REFERENCE_SEED, ReferenceSource};
use crate::regions::{Region, Regions};
use crate::report::tables::{verdict_word, with_ci};
use crate::report::{output_dir, write_text};
use crate::scenes::{load_scene, with_resolution};
use crate::telemetry::{self, RegionSummary};
use crate::uncertainty::INTERVAL_METHOD;

use super::setup::{FRAMES, Report, Settings};

/// The ReSTIR method ablated unless `--methods` names others.
pub const DEFAULT_BASE: &str = "restir:hybrid";

/// The built-in scene ablated unless `--scene` names another.
pub const DEFAULT_SCENE: &str = "bumpy";

/// The resolution rows: the run's resolution times these factors (128×96 → 256×192, 384×288).
pub const RESOLUTION_FACTORS: [u32; 2] = [2, 3];

/// Samples per pixel of one reference batch.
const REFERENCE_BATCH_SPP: u32 = 128;

/// Knobs of issue 10's list that the engine does not have: named in the table's notes.
pub const NOT_KNOBS: [(&str, &str); 2] = [
    (
        "spatial radius rule",
        "not a knob yet: `Camera::spatial_radius_px` always clamps the projected 2·max d to [5, 30] px",
    ),
    (
        "target p̂",
        "not a knob yet: p̂ is the luminance of the contribution f (`SssDomain::target`) in both backends",
    ),
];

/// How the camera moves over the trajectory.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Framing {
    /// The scene's trajectory; `false`: at rest at its last pose (`Camera::at_rest`).
    pub moving: bool,
    /// Sub-pixel jitter per frame.
    pub jitter: bool,
}

impl Framing {
    /// The scene's own camera: moving and jittered (seed 001's setup).
    pub const SCENE: Framing = Framing {
        moving: true,
        jitter: true,
    };

    /// `scene` with this framing; the scene's own camera is returned unchanged.
    pub fn apply(self, mut scene: Scene) -> Scene {
        if !self.moving {
            scene.camera = scene.camera.at_rest();
        }
        if !self.jitter {
            scene.camera = scene.camera.with_jitter(false);
        }
        scene
    }

    /// `moving`, `static`, with `-unjittered` when jitter is off.
    pub fn name(self) -> String {
        let motion = if self.moving { "moving" } else { "static" };
        let jitter = if self.jitter { "" } else { "-unjittered" };
        format!("{motion}{jitter}")
    }
}

/// One row of the ablation: a method spec on a camera at a resolution.
#[derive(Clone, Debug, PartialEq)]
pub struct Variation {
    /// What varies, e.g. `temporal cap 1`.
    pub label: String,
    /// The method, e.g. `restir:hybrid/cap=1`.
    pub spec: String,
    pub framing: Framing,
    pub resolution: (u32, u32),
}

impl Variation {
    /// The rows' group: one comparison per camera and resolution.
    fn group(&self) -> String {
        let (w, h) = self.resolution;
        format!("{}-{w}x{h}", self.framing.name())
    }
}

/// The rows for `base` at `resolution`: the unmodified preset, then one knob changed per row.
pub fn variations(base: &str, resolution: (u32, u32)) -> Vec<Variation> {
    let row = |label: String, modifier: &str, framing, resolution| Variation {
        label,
        spec: format!("{base}{modifier}"),
        framing,
        resolution,
    };
    let here =
        |label: &str, modifier: &str| row(label.into(), modifier, Framing::SCENE, resolution);
    let mut rows = vec![
        here("default (temporal cap 3)", ""),
        here("temporal cap 1", "/cap=1"),
        here("temporal cap 5", "/cap=5"),
        here("temporal cap 20", "/cap=20"),
        here("spatial cap 1", "/spatial-cap=1"),
        here("spatial cap 3", "/spatial-cap=3"),
        here("neighbours 2", "/neighbours=2"),
        here("neighbours 8", "/neighbours=8"),
        here("shade=all", "/shade=all"),
    ];
    for (label, moving, jitter) in [
        ("static camera", false, true),
        ("no jitter", true, false),
        ("static camera, no jitter", false, false),
    ] {
        rows.push(row(
            label.into(),
            "",
            Framing { moving, jitter },
            resolution,
        ));
    }
    for k in RESOLUTION_FACTORS {
        let (w, h) = (resolution.0 * k, resolution.1 * k);
        rows.push(row(format!("{w}×{h}"), "", Framing::SCENE, (w, h)));
    }
    rows
}

/// The efficiency ratio of every row over `pt` and over its base's default row per region.
struct Measurement {
    variation: Variation,
    over_pt: Vec<Option<Measured>>,
    /// `None` where the default row ran on other images (another camera or resolution).
    over_default: Option<Vec<Option<Measured>>>,
    /// Milliseconds per frame of the row and of its `pt`.
    milliseconds: (Measured, Option<Measured>),
    /// MSE over the default row per region at equal spp, and seconds per frame over the default
    /// row (both paired by seed); `None` like `over_default`.
    mse_over_default: Option<(Vec<Option<Measured>>, Option<Measured>)>,
    /// `None` on a backend without telemetry.
    telemetry: Option<Vec<RegionSummary>>,
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
    // Rao-Blackwellised shading has no Vulkan kernel: its rows run on the CPU backend only.
    let cpu = matches!(settings.backend, engine::Backend::Cpu);
    let rows: Vec<Variation> = bases
        .iter()
        .flat_map(|b| variations(b, settings.resolution))
        .filter(|v| cpu || !v.spec.contains("/shade=all"))
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
        let outcome = compare::run(&plan, progress)?;
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
                milliseconds: (milliseconds(row), pt.map(milliseconds)),
                mse_over_default: default.filter(|_| own_group).map(|d| {
                    let time = row.seconds.ln().zip(d.seconds.ln());
                    let time = time.and_then(|(a, b)| a.minus(&b));
                    (mse_ratios(row, d), time.as_ref().map(Measured::of_log))
                }),
                telemetry: reuse_telemetry(settings, &plan.scene, &v.spec)?
                    .map(|runs| telemetry::summarise(&runs, &regions)),
            });
        }
        runs.push(json!({ "group": group, "results": outcome.results.to_json() }));
    }
    // Table order: the rows' own order.
    measured.sort_by_key(|m| rows.iter().position(|v| *v == m.variation));
    let table = markdown(&measured, scene_name, settings);
    let findings = findings(&measured);
    let json = json!({
        "schema": "reshift-ablation/1",
        "scene": scene_name,
        "replicas": settings.replicas,
        "frames": FRAMES,
        "reference_spp": settings.reference_spp,
        "interval": INTERVAL_METHOD,
        "confidence": crate::uncertainty::CONFIDENCE,
        "rows": measured.iter().map(row_json).collect::<Vec<_>>(),
        "not_knobs": NOT_KNOBS
            .iter()
            .map(|(k, why)| json!({ "knob": k, "note": why }))
            .collect::<Vec<_>>(),
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
) -> Result<Plan, Error> {
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
    Ok(Plan {
        scene,
        scene_key: key,
        methods: parse_methods(&specs)?,
        baseline: DEFAULT_BASELINE.into(),
        replicas: settings.replicas,
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

/// One telemetry table per row ([`telemetry::markdown`]).
fn telemetry_markdown(measured: &[Measurement]) -> String {
    let mut out = String::from(
        "Reuse telemetry of the last frame per region: means over replicas with 95% intervals \
         (delta method). Runs with diagnostics on, same seeds as the timed runs (CPU backend \
         only). \"moved in last by\": the pass that last replaced the pixel's sample; \
         \"m₀\": the MIS weight of the pixel's own sample in that pass; \"pixels sharing x2\": \
         the mean number of pixels whose final sample has the pixel's entry point.\n",
    );
    for m in measured {
        let v = &m.variation;
        out.push_str(&format!(
            "\n### {} (`{}`, {}, {}×{})\n\n",
            v.label,
            v.spec,
            v.framing.name(),
            v.resolution.0,
            v.resolution.1
        ));
        match &m.telemetry {
            Some(t) => out.push_str(&telemetry::markdown(t)),
            None => out.push_str("No telemetry: the backend records none (CPU backend only).\n"),
        }
    }
    out
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

/// Milliseconds per frame over replicas.
fn milliseconds(row: &MethodResult) -> Measured {
    let s = Measured::of(&row.seconds);
    Measured {
        value: 1e3 * s.value,
        ci: s.ci.map(|i| crate::uncertainty::Interval {
            lo: 1e3 * i.lo,
            hi: 1e3 * i.hi,
        }),
    }
}

/// `ratio [lo, hi] lower|higher|inconclusive` for a ratio where below 1 is lower, or `-`.
fn ratio_cell(m: &Option<Measured>) -> String {
    let Some(m) = m else { return "-".into() };
    let word = match m.ci {
        Some(i) if i.below(1.0) => "lower",
        Some(i) if i.above(1.0) => "higher",
        _ => "inconclusive",
    };
    format!("{} {word}", with_ci(Some(*m)))
}

/// `ratio [lo, hi] verdict`, or `-`.
fn cell(m: &Option<Measured>) -> String {
    match m {
        Some(m) => format!("{} {}", with_ci(Some(*m)), verdict_word(m)),
        None => "-".into(),
    }
}

fn markdown(measured: &[Measurement], scene: &str, settings: &Settings) -> String {
    let (w, h) = settings.resolution;
    let header = "| variation | method | camera | size | translucent | lit | penumbra | shadowed |\n\
                  |---|---|---|---|---:|---:|---:|---:|\n";
    let mut over_pt = format!(
        "Efficiency 1/(MSE·s) over 1-spp `pt`, frame {} of `{scene}`, {} replicas, reference {} spp; \
         95% intervals by the delta method over replicas (paired by seed, log scale); verdict \
         *better* / *worse* when the interval excludes 1, else *inconclusive*. Wall times on a \
         shared machine: their intervals hold the spread within the run, not a load change \
         between methods.\n\n| variation | method | camera | size | translucent | lit | penumbra | shadowed | ms/frame (pt) |\n\
         |---|---|---|---|---:|---:|---:|---:|---:|\n",
        FRAMES - 1,
        settings.replicas,
        settings.reference_spp
    );
    let mut over_default = format!(
        "\nEfficiency over the unmodified preset (same camera, {w}×{h}, paired by seed):\n\n{header}"
    );
    let mut mse_over_default = format!(
        "\nMSE over the unmodified preset at equal spp (same camera, {w}×{h}, paired by seed; the \
         MSEs are deterministic, the times are not), and time per frame over it:\n\n\
         | variation | method | camera | size | translucent | lit | penumbra | shadowed | time/frame |\n\
         |---|---|---|---|---:|---:|---:|---:|---:|\n"
    );
    for m in measured {
        let v = &m.variation;
        let lead = format!(
            "| {} | {} | {} | {}×{} |",
            v.label,
            v.spec,
            v.framing.name(),
            v.resolution.0,
            v.resolution.1
        );
        let cells = |ms: &[Option<Measured>]| ms.iter().map(cell).collect::<Vec<_>>().join(" | ");
        let (ms, pt_ms) = &m.milliseconds;
        over_pt.push_str(&format!(
            "{lead} {} | {} ({}) |\n",
            cells(&m.over_pt),
            with_ci(Some(*ms)),
            with_ci(*pt_ms)
        ));
        if let Some(d) = &m.over_default {
            over_default.push_str(&format!("{lead} {} |\n", cells(d)));
        }
        if let Some((mse, time)) = &m.mse_over_default {
            let mse: Vec<String> = mse.iter().map(ratio_cell).collect();
            mse_over_default.push_str(&format!(
                "{lead} {} | {} |\n",
                mse.join(" | "),
                ratio_cell(time)
            ));
        }
    }
    let mut notes = String::from("\nNot varied:\n\n");
    for (knob, why) in NOT_KNOBS {
        notes.push_str(&format!("- {knob}: {why}\n"));
    }
    if !matches!(settings.backend, engine::Backend::Cpu) {
        notes.push_str("- shade=all: left out, it has no Vulkan kernel (CPU backend only)\n");
    }
    format!("{over_pt}{over_default}{mse_over_default}{notes}")
}

/// What the intervals decide: per region, the rows more or less efficient than the unmodified
/// preset, and whether issue 10's bar is met (lower bound ≥ 5 over `pt` in penumbra and
/// shadow, > 1 over all translucent pixels).
fn findings(measured: &[Measurement]) -> String {
    let mut out = String::from(
        "| region | more efficient than the unmodified preset | less efficient | rows whose lower bound over pt clears the bar |\n|---|---|---|---|\n",
    );
    for (i, region) in Region::ALL.iter().enumerate() {
        let bar = match region {
            Region::Penumbra | Region::Shadowed => 5.0,
            _ => 1.0,
        };
        let decided = |word: &str| {
            let labels: Vec<&str> = measured
                .iter()
                .filter(|m| {
                    m.over_default
                        .as_ref()
                        .and_then(|d| d[i].as_ref())
                        .is_some_and(|r| verdict_word(r) == word)
                })
                .map(|m| m.variation.spec.as_str())
                .collect();
            list(&labels)
        };
        let clear: Vec<String> = measured
            .iter()
            .filter(|m| {
                m.over_pt[i]
                    .and_then(|r| r.ci)
                    .is_some_and(|ci| if bar > 1.0 { ci.lo >= bar } else { ci.lo > bar })
            })
            .map(|m| format!("{} ({})", m.variation.spec, m.variation.label))
            .collect();
        let clear: Vec<&str> = clear.iter().map(String::as_str).collect();
        let sign = if bar > 1.0 { "≥" } else { ">" };
        out.push_str(&format!(
            "| {region} | {} | {} | {sign} {bar}: {} |\n",
            decided("better"),
            decided("worse"),
            list(&clear)
        ));
    }
    out
}

fn list(labels: &[&str]) -> String {
    if labels.is_empty() {
        "none".into()
    } else {
        labels.join(", ")
    }
}

/// `{value, lo, hi}` and, for an efficiency ratio, its verdict.
fn measured_json(m: &Option<Measured>, efficiency: bool) -> Value {
    match m {
        Some(m) => {
            let mut v = json!({
                "value": m.value,
                "lo": m.ci.map(|i| i.lo),
                "hi": m.ci.map(|i| i.hi).filter(|h| h.is_finite()),
            });
            if efficiency {
                v["verdict"] = json!(verdict_word(m));
            }
            v
        }
        None => Value::Null,
    }
}

fn row_json(m: &Measurement) -> Value {
    let by_region = |ms: &[Option<Measured>], efficiency: bool| {
        Region::ALL
            .iter()
            .zip(ms)
            .map(|(r, m)| (r.name().to_string(), measured_json(m, efficiency)))
            .collect::<serde_json::Map<_, _>>()
    };
    let v = &m.variation;
    json!({
        "variation": v.label,
        "method": v.spec,
        "camera": v.framing.name(),
        "width": v.resolution.0,
        "height": v.resolution.1,
        "efficiency_over_pt": by_region(&m.over_pt, true),
        "efficiency_over_default": m.over_default.as_deref().map(|d| by_region(d, true)),
        "ms_per_frame": measured_json(&Some(m.milliseconds.0), false),
        "pt_ms_per_frame": measured_json(&m.milliseconds.1, false),
        "mse_over_default": m.mse_over_default.as_ref().map(|(mse, _)| by_region(mse, false)),
        "time_over_default": m.mse_over_default.as_ref().map(|(_, t)| measured_json(t, false)),
        "telemetry": m.telemetry.as_deref().map(telemetry::json),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::methods::Method;

    /// The rows: the default first, every knob of issue 10 that exists once, each method spec
    /// parses, framings and resolutions differ from the default only where the label says so,
    /// and the resolution rows scale the run's resolution.
    #[test]
    fn the_rows_cover_every_knob_once() {
        let rows = variations("restir:hybrid", (128, 96));
        assert_eq!(rows[0].spec, "restir:hybrid");
        assert_eq!(rows[0].group(), "moving-128x96");
        let labels: Vec<&str> = rows.iter().map(|v| v.label.as_str()).collect();
        for wanted in [
            "temporal cap 1",
            "temporal cap 5",
            "temporal cap 20",
            "spatial cap 1",
            "neighbours 2",
            "neighbours 8",
            "shade=all",
            "static camera",
            "no jitter",
            "256×192",
            "384×288",
        ] {
            assert_eq!(
                labels.iter().filter(|l| **l == wanted).count(),
                1,
                "{wanted}"
            );
        }
        for v in &rows {
            Method::parse(&v.spec).unwrap_or_else(|e| panic!("{}: {e}", v.spec));
            let modified = v.spec != "restir:hybrid";
            let elsewhere = v.framing != Framing::SCENE || v.resolution != (128, 96);
            assert!(
                modified != elsewhere || v == &rows[0],
                "{}: changes one thing",
                v.label
            );
        }
        let groups: std::collections::BTreeSet<String> =
            rows.iter().map(Variation::group).collect();
        assert_eq!(groups.len(), 6, "{groups:?}");
        let small = variations("restir:sequential", (8, 6));
        let sizes: Vec<(u32, u32)> = small.iter().map(|v| v.resolution).collect();
        assert!(sizes.contains(&(16, 12)) && sizes.contains(&(24, 18)));
    }

    /// A framing changes the camera as named: at rest every frame has the last pose.
    #[test]
    fn framings_apply_to_the_camera() {
        let camera = Scene::builtin("bumpy").unwrap().camera;
        let still = Framing {
            moving: false,
            jitter: false,
        }
        .apply(Scene::builtin("bumpy").unwrap());
        assert_eq!(still.camera.eye(0), camera.eye(FRAMES - 1));
        assert!(!still.camera.jittered());
        let same = Framing::SCENE.apply(Scene::builtin("bumpy").unwrap());
        assert_eq!(same.camera, camera);
    }
}
