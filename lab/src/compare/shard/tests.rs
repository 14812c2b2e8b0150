//! A comparison in shards against one run: every measured figure and image bit for bit, and
//! the refusals of shards that are not one run.

use engine::denoise::Denoiser;

use super::*;
use crate::method_result::MethodResult;
use crate::progress::Silent;

/// A tiny comparison: 16×12, 2 frames, `replicas` replicas of `methods`, a 2×8 spp reference
/// cached under `dir` (shared by the run, the shards and the merge), SVGF, video on.
fn plan(dir: &Path, methods: &[&str], replicas: u32) -> Comparison {
    Comparison {
        frame_reference_spp: Some(16),
        out: dir.join("whole"),
        denoise: vec![Denoiser::Svgf],
        video: true,
        ..crate::compare::tests::small_plan(dir, methods, replicas, (16, 12), 8)
    }
}

/// Every shard of `plan` in `count` parts, written under `dir/<count>` and read back.
fn shards(plan: &dyn Fn() -> Comparison, dir: &Path, count: u32) -> Vec<(PathBuf, CompareShard)> {
    let plan = Comparison {
        out: dir.join(count.to_string()),
        ..plan()
    };
    (0..count)
        .map(|index| {
            let shard = Shard { index, count };
            let path = run_shard(&plan, "bumpy", None, shard, &mut Silent).unwrap();
            let (schema, value) = crate::shard::read(&path).unwrap();
            assert_eq!(schema, SHARD_SCHEMA);
            (path.clone(), crate::shard::parse(&path, value).unwrap())
        })
        .collect()
}

/// `row` with the timings of `like`: the fields that are measurements of a clock (seconds,
/// wall seconds, the denoiser's seconds), which no two runs share.
fn timed_as(row: &MethodResult, like: &MethodResult) -> MethodResult {
    assert_eq!(
        row.denoiser_seconds.is_some(),
        like.denoiser_seconds.is_some()
    );
    MethodResult {
        seconds: like.seconds.clone(),
        wall_seconds: like.wall_seconds.clone(),
        denoiser_seconds: like.denoiser_seconds.clone(),
        ..row.clone()
    }
}

/// Everything of `merged` that is not a timing equals `whole`'s: every row group's metrics,
/// convergence and flicker, the denoiser notes, the final frames, the videos' frames and the
/// references' frames, regions and flicker.
fn assert_same_measurements(merged: &Outcome, whole: &Outcome) {
    let (groups, whole_groups) = (merged.groups(), whole.groups());
    assert_eq!(groups.len(), whole_groups.len());
    for ((d, rows), (e, whole_rows)) in groups.iter().zip(&whole_groups) {
        assert_eq!(d, e);
        assert_eq!(rows.len(), whole_rows.len());
        for (row, w) in rows.iter().zip(*whole_rows) {
            assert_eq!(&timed_as(row, w), w, "{}", w.label());
        }
    }
    assert_eq!(merged.denoise_errors, whole.denoise_errors);
    let finals = |o: &Outcome| -> Vec<_> {
        (o.finals.iter())
            .map(|f| (f.method.clone(), f.denoiser, f.image.clone()))
            .collect()
    };
    assert_eq!(finals(merged), finals(whole));
    let (video, whole_video) = (
        merged.video.as_ref().unwrap(),
        whole.video.as_ref().unwrap(),
    );
    assert_eq!(video.references, whole_video.references);
    assert_eq!(video.own_references, whole_video.own_references);
    assert_eq!(video.trajectories.len(), whole_video.trajectories.len());
    for (t, w) in video.trajectories.iter().zip(&whole_video.trajectories) {
        assert_eq!(
            (&t.spec, &t.frames, &t.denoised),
            (&w.spec, &w.frames, &w.denoised)
        );
    }
    assert_eq!(merged.regions, whole.regions);
    assert_eq!(
        merged.reference.reference.mean(),
        whole.reference.reference.mean()
    );
    assert_eq!(merged.reference_flicker, whole.reference_flicker);
    let frames = |o: &Outcome| {
        o.frame_references
            .iter()
            .map(|p| p.frame)
            .collect::<Vec<_>>()
    };
    assert_eq!(frames(merged), frames(whole));
    assert!(!merged.interrupted);
}

/// 2 shards merged in both orders and 3 shards (one replica each) give one run's measured
/// figures and images bit for bit, and the merged report is written.
#[test]
fn merged_shards_measure_what_one_run_measures() {
    let dir = std::env::temp_dir().join(format!("reshift-compare-shards-{}", std::process::id()));
    let plan = || plan(&dir, &["pt:2", "restir:hybrid"], 3);
    let whole = super::super::run(&plan(), &mut Silent).unwrap();
    let two = shards(&plan, &dir, 2);
    let mut reversed = two.clone();
    reversed.reverse();
    for (k, parts) in [two, reversed, shards(&plan, &dir, 3)]
        .into_iter()
        .enumerate()
    {
        let out = dir.join(format!("merged-{k}"));
        let (merged_plan, merged) = merge(parts, out.clone(), &mut Silent).unwrap();
        assert_same_measurements(&merged, &whole);
        assert_eq!(merged.out, out);
        crate::report::write(&merged_plan, &merged).unwrap();
        assert!(out.join("results.json").is_file());
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Shards of a run from a first seed S hold seeds S + ⌊i·N/n⌋.. and merge into that run.
#[test]
fn shards_of_a_run_from_a_first_seed_merge_into_it() {
    let dir = std::env::temp_dir().join(format!("reshift-shards-seed-{}", std::process::id()));
    let plan = || Comparison {
        first_seed: 4,
        ..plan(&dir, &["pt:2", "restir:reconnection"], 3)
    };
    let whole = super::super::run(&plan(), &mut Silent).unwrap();
    let parts = shards(&plan, &dir, 2);
    let held: Vec<[u64; 2]> = parts.iter().map(|(_, p)| p.seeds).collect();
    assert_eq!(held, [[4, 5], [5, 7]]);
    let (merged_plan, merged) = merge(parts, dir.join("merged"), &mut Silent).unwrap();
    assert_eq!(merged_plan.first_seed, 4);
    assert_same_measurements(&merged, &whole);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Shards of another method list or seed count, a missing shard, a truncated payload and equal
/// time are refused with one line naming what is wrong.
#[test]
fn shards_that_are_not_one_run_refuse_to_merge() {
    let dir = std::env::temp_dir().join(format!("reshift-compare-refuse-{}", std::process::id()));
    let plan = || Comparison {
        denoise: Vec::new(),
        video: false,
        ..plan(&dir, &["pt:1"], 2)
    };
    let parts = shards(&plan, &dir, 2);
    let error = |parts: Vec<(PathBuf, CompareShard)>| {
        let e = merge(parts, dir.join("merged"), &mut Silent).err().unwrap();
        e.to_string()
    };
    let mut other = parts.clone();
    other[1].1.plan.methods = vec!["pt:2".into()];
    let (p0, p1) = (
        parts[0].0.display().to_string(),
        parts[1].0.display().to_string(),
    );
    assert_eq!(
        error(other),
        format!("{p1}: field 'methods' is [\"pt:2\"], {p0} has [\"pt:1\"]")
    );
    let mut other = parts.clone();
    other[1].1.plan.replicas = 3;
    assert_eq!(
        error(other),
        format!("{p1}: field 'replicas' is 3, {p0} has 2")
    );
    assert_eq!(
        error(parts[..1].to_vec()),
        "merge: shard 1 of 2 (shard-1-of-2.json) is missing; 1 of 2 given"
    );
    let payload = payload_path(&parts[1].0);
    let bytes = std::fs::read(&payload).unwrap();
    std::fs::write(&payload, &bytes[..bytes.len() - 4]).unwrap();
    let size = bytes.len();
    assert_eq!(
        error(parts),
        format!(
            "{}: {} bytes, its header {p1} names {size} (2 images of 16×12)",
            payload.display(),
            size - 4
        )
    );
    let equal_time = Comparison {
        equal_time: Some(0.1),
        ..plan()
    };
    let e = run_shard(
        &equal_time,
        "bumpy",
        None,
        Shard { index: 0, count: 2 },
        &mut Silent,
    );
    assert!(
        e.err()
            .unwrap()
            .to_string()
            .starts_with("--equal-time with --shard")
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
