//! A whole comparison through the library, measured ([`super::run`]) and written
//! ([`crate::report::write`]).

use engine::Backend;
use engine::denoise::Denoiser;
use sss::scene::Scene;

use super::*;
use crate::progress::Silent;
use crate::report;
use crate::scenes::with_resolution;

/// A whole comparison through the library: every file is written, the document agrees with
/// the rows, every frame is measured, a second run reuses the cached references and
/// reproduces the errors, and measuring the last frame alone gives the same last-frame
/// errors (a trajectory's last frame is the frame a single render returns).
#[test]
fn a_comparison_writes_its_outputs_and_reuses_the_reference() {
    let dir = std::env::temp_dir().join(format!("reshift-compare-{}", std::process::id()));
    let plan = Comparison {
        scene: with_resolution(Scene::builtin("bumpy").unwrap(), Some((12, 9))),
        scene_key: "bumpy".into(),
        methods: parse_methods(&["pt:2", "restir:hybrid"]).unwrap(),
        baseline: "pt:2".into(),
        replicas: 3,
        first_seed: 0,
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
        video: true,
        denoise: vec![Denoiser::Svgf],
    };
    let first = run(&plan, &mut Silent).unwrap();
    // `run` measures; `report::write` writes.
    assert!(!first.out.join("table.md").exists());
    let first_written = report::write(&plan, &first).unwrap();
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
    assert_eq!(first_written.results.methods.len(), 4);
    assert_eq!(first_written.results.denoisers, ["svgf"]);
    assert!(
        first_written.markdown.contains("Denoised with svgf"),
        "{}",
        first_written.markdown
    );
    assert!(
        first_written.markdown.contains("| pt:2+svgf |"),
        "{}",
        first_written.markdown
    );
    assert_eq!(first.rows.len(), 2);
    assert!(!first_written.results.reference.cached && !first_written.results.interrupted);
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
    assert_eq!(written, first_written.results.to_json_pretty());
    assert_eq!(first_written.results.frame_references.len(), 3);
    for row in &first.rows {
        let frames: Vec<u32> = row.convergence.iter().map(|f| f.frame).collect();
        assert_eq!(frames, [0, 1, 2], "{}", row.method);
        assert_eq!(row.convergence[2].metrics, row.metrics);
        assert_eq!(row.seconds.replicas(), 3);
    }
    assert_eq!(first_written.results.baseline.as_deref(), Some("pt:2"));
    assert!(
        first_written.markdown.contains("Efficiency over pt:2"),
        "{}",
        first_written.markdown
    );
    let again = run(&plan, &mut Silent).unwrap();
    let again_written = report::write(&plan, &again).unwrap();
    assert!(again_written.results.reference.cached);
    assert!(
        again_written
            .results
            .frame_references
            .iter()
            .all(|f| f.cached)
    );
    assert_eq!(again.rows[1].metrics, first.rows[1].metrics);
    assert_eq!(
        again.denoised[0].1[1].metrics,
        first.denoised[0].1[1].metrics
    );
    // Videos: replica 0's every frame per raw row, each frame against its own reference; the
    // flicker of every raw row (consecutive frames), none of the denoised rows (last frame).
    let video = first.video.as_ref().unwrap();
    assert!(video.own_references && video.references.len() == 3);
    for (trajectory, row) in video.trajectories.iter().zip(&first.rows) {
        let spec = &trajectory.spec;
        assert_eq!((spec, trajectory.frames.len()), (&row.method, 3));
        // Every frame through the comparison's denoiser, as it denoises the last frame.
        let [(d, Ok(denoised))] = &trajectory.denoised[..] else {
            panic!("{spec}: one denoiser's frames");
        };
        assert_eq!((*d, denoised.len()), (first.denoised[0].0, 3));
        assert!(!row.flicker.is_empty(), "{spec}");
        assert!(row.flicker.iter().all(|f| f.flicker.value > 0.0), "{spec}");
    }
    assert!(denoised.iter().all(|r| r.flicker.is_empty()));
    assert!(!first.reference_flicker.is_empty());
    let videos = &first_written.results.videos;
    assert_eq!(videos.len(), 2);
    assert!(videos.iter().all(|v| first.out.join(&v.apng).is_file()));
    assert!(first_written.markdown.contains("| pt:2 | image |"));
    let last_only = Comparison {
        frame_reference_spp: None,
        baseline: "none".into(),
        denoise: Vec::new(),
        ..plan
    };
    let last = run(&last_only, &mut Silent).unwrap();
    let last_written = report::write(&last_only, &last).unwrap();
    assert!(last_written.results.baseline.is_none());
    for (a, b) in last.rows.iter().zip(&first.rows) {
        assert_eq!(a.metrics, b.metrics, "{}", a.method);
        assert_eq!(a.convergence.len(), 1);
        assert!(a.flicker.is_empty(), "one measured frame: no flicker");
    }
    // Without earlier references the video still has every frame, against the last reference.
    let video = last.video.as_ref().unwrap();
    assert!(!video.own_references);
    assert!(video.trajectories.iter().all(|t| t.frames.len() == 3));
    assert!(last_written.results.video_notes[0].contains("the last frame's"));
    assert!(last_written.markdown.contains("Flicker: not measured"));
    // Equal time counts the denoiser: every denoised row's seconds are its rendering's plus
    // one figure shared by the denoiser's rows (the mean of its timings).
    let timed = Comparison {
        equal_time: Some(0.01),
        video: false,
        denoise: vec![Denoiser::Svgf],
        ..last_only
    };
    let counted = run(&timed, &mut Silent).unwrap();
    let counted_written = report::write(&timed, &counted).unwrap();
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
    assert!(counted_written.markdown.contains("counted in ms/frame"));
    let empty = Comparison {
        methods: Vec::new(),
        ..timed
    };
    assert!(matches!(run(&empty, &mut Silent), Err(Error::Invalid(_))));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `replicas` replicas of `methods` (the first the baseline) on `bumpy` at `width`×`height`, 2
/// frames from seed 0, the last frame against a reference of 2 batches of `batch_spp` cached
/// under `dir`; no denoiser, no video. (The shard tests build on it too.)
pub(super) fn small_plan(
    dir: &std::path::Path,
    methods: &[&str],
    replicas: u32,
    (width, height): (u32, u32),
    batch_spp: u32,
) -> Comparison {
    Comparison {
        scene: with_resolution(Scene::builtin("bumpy").unwrap(), Some((width, height))),
        scene_key: "bumpy".into(),
        methods: parse_methods(methods).unwrap(),
        baseline: methods[0].into(),
        replicas,
        first_seed: 0,
        frames: 2,
        equal_time: None,
        reference: ReferenceSource::Cache {
            dir: dir.join("cache"),
            spp: 2 * batch_spp,
            batch_spp,
        },
        frame_reference_spp: None,
        out: dir.join("out"),
        backend: Backend::Cpu,
        video: false,
        denoise: Vec::new(),
    }
}

/// A run from `first_seed` S renders replica k with seed S + k: its replica 0 (the final image,
/// and the video's trajectory) is the method's render of seed S, not of seed 0, and
/// `results.json` records S. A first seed whose range passes the largest seed is refused.
#[test]
fn replicas_start_at_the_first_seed() {
    let dir = std::env::temp_dir().join(format!("reshift-first-seed-{}", std::process::id()));
    let plan = Comparison {
        first_seed: 5,
        video: true,
        ..small_plan(&dir, &["pt:2", "restir:reconnection"], 2, (8, 6), 4)
    };
    assert_eq!(plan.seeds(), 5..7);
    let outcome = run(&plan, &mut Silent).unwrap();
    let video = outcome.video.as_ref().unwrap();
    for ((spec, method), (fin, trajectory)) in plan
        .methods
        .iter()
        .zip(outcome.finals.iter().zip(&video.trajectories))
    {
        let render = |seed| {
            let (t, _) = method
                .render_trajectory_on(&Backend::Cpu, &plan.scene, 2, seed)
                .unwrap();
            t.frames
        };
        let (own, zero) = (render(5), render(0));
        assert_eq!(fin.method, *spec);
        assert_eq!(fin.image, own[1], "{spec}: replica 0 is seed 5's render");
        assert_ne!(fin.image, zero[1], "{spec}: not seed 0's");
        assert_eq!(
            trajectory.frames, own,
            "{spec}: the video is seed 5's trajectory"
        );
    }
    let written = report::write(&plan, &outcome).unwrap();
    assert_eq!(written.results.first_seed, 5);
    assert_eq!(written.results.to_json()["first_seed"], 5);
    let overflowing = Comparison {
        first_seed: u64::MAX - 1,
        ..plan
    };
    match run(&overflowing, &mut Silent) {
        Err(Error::Invalid(line)) => assert!(line.contains("first seed"), "{line}"),
        other => panic!("expected a refusal, got {:?}", other.err()),
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Stops after `after` replicas and records the order they were rendered in.
struct StopAfter {
    after: usize,
    items: Vec<String>,
    steps: usize,
}

impl Progress for StopAfter {
    /// Counts the steps of the `replicas` phase only (a reference's batches are steps too).
    fn begin(&mut self, _what: &str, _total: u64, _done: u64) {
        self.steps = 0;
    }

    fn item(&mut self, name: &str) {
        self.items.push(name.to_string());
    }

    fn step(&mut self) {
        self.steps += 1;
    }

    fn stop_requested(&self) -> bool {
        self.steps >= self.after
    }
}

/// Replicas are rendered in rounds of one seed (seed 0 of every method, then seed 1), and a
/// stop request in the middle of a round keeps only the whole rounds: every row has the same
/// seeds, so its ratios stay paired. Rows keep the plan's order.
#[test]
fn replicas_render_in_rounds_and_a_stop_keeps_whole_rounds() {
    let dir = std::env::temp_dir().join(format!("reshift-rounds-{}", std::process::id()));
    let plan = Comparison {
        baseline: "pt:2".into(),
        ..small_plan(&dir, &["restir:hybrid", "pt:2"], 3, (8, 6), 4)
    };
    let mut progress = StopAfter {
        after: 3,
        items: Vec::new(),
        steps: 0,
    };
    let stopped = run(&plan, &mut progress).unwrap();
    assert_eq!(progress.items, ["restir:hybrid", "pt:2", "restir:hybrid"]);
    assert!(stopped.interrupted);
    let methods: Vec<&str> = stopped.rows.iter().map(|r| r.method.as_str()).collect();
    assert_eq!(methods, ["restir:hybrid", "pt:2"]);
    assert!(
        stopped.rows.iter().all(|r| r.replicas == 1),
        "round 1 dropped"
    );
    let whole = run(&plan, &mut Silent).unwrap();
    assert!(!whole.interrupted);
    for row in &whole.rows {
        assert_eq!(row.replicas, 3);
        // Every frame is timed: a memoryless method renders (and is timed on) the whole
        // trajectory like ReSTIR.
        assert_eq!(row.frames_rendered, 2, "{}", row.method);
        assert!(row.seconds.value > 0.0 && row.wall_seconds.value > 0.0);
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
