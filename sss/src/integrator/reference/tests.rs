use super::*;

fn small_bumpy() -> (Scene, GBuffer) {
    let mut scene = Scene::builtin("bumpy").expect("built-in scene");
    scene.camera = scene.camera.with_resolution(40, 30);
    let gbuffer = GBuffer::render(&scene, 3);
    (scene, gbuffer)
}

fn config(batches: u32) -> ReferenceConfig {
    ReferenceConfig {
        scene: "bumpy".into(),
        frame: 3,
        seed: 11,
        spp_per_batch: 2,
        batches,
        settings: PtSettings::default(),
    }
}

/// Three shards (rendered in any order, merged in shuffled order) equal one unsharded run bit for
/// bit; a run stopped after a checkpoint and resumed from the file equals an uninterrupted one.
#[test]
fn shards_merge_and_resume_bit_identically() {
    let (scene, gbuffer) = small_bumpy();
    let (w, h) = (gbuffer.width, gbuffer.height);
    let mut whole = Reference::new(config(7), w, h, Shard::WHOLE).unwrap();
    assert_eq!(whole.run(&scene, &gbuffer, u32::MAX), 7);
    assert!(
        whole.mean().iter().any(|m| m.max_element() > 0.0),
        "reference is black"
    );
    assert_eq!(whole.nonfinite, 0);

    let shards: Vec<(PathBuf, Reference)> = [2, 0, 1]
        .into_iter()
        .map(|i| {
            let mut r = Reference::new(config(7), w, h, Shard { index: i, count: 3 }).unwrap();
            r.run(&scene, &gbuffer, u32::MAX);
            (PathBuf::from(format!("shard{i}")), r)
        })
        .collect();
    let ranges: Vec<_> = shards.iter().map(|(_, s)| s.start..s.end).collect();
    assert_eq!(ranges, [4..7, 0..2, 2..4]);
    assert_eq!(Reference::merge(shards.clone()).unwrap(), whole);

    // Shards of different references name both files, the field and both values.
    let mut other = shards.clone();
    other[0].1.config.seed = 12;
    let e = Reference::merge(other).unwrap_err();
    assert_eq!(
        (e.file.to_str(), e.field.as_str(), e.value.as_str()),
        (Some("shard2"), "seed", "12")
    );
    assert!(e.reason.contains("shard0 (11)"), "{e}");
    let mut other = shards.clone();
    other[2].1.width = w + 1;
    let e = Reference::merge(other).unwrap_err();
    assert_eq!(
        (e.file.to_str(), e.field.as_str()),
        (Some("shard1"), "width×height")
    );
    assert!(e.reason.contains(&format!("shard0 ({w}×{h})")), "{e}");
    let e = Reference::merge(vec![shards[0].clone(), shards[0].clone()]).unwrap_err();
    assert!(e.reason.contains("overlap"), "{e}");

    let dir = std::env::temp_dir().join(format!("reshift-reference-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("checkpoint.bin");
    let mut interrupted = Reference::new(config(7), w, h, Shard::WHOLE).unwrap();
    assert_eq!(interrupted.run(&scene, &gbuffer, 3), 3);
    interrupted.save(&path).unwrap();
    let mut resumed = Reference::load(&path).unwrap();
    assert_eq!(resumed, interrupted);
    resumed.run(&scene, &gbuffer, u32::MAX);
    assert_eq!(resumed, whole);

    // Negative control: an f64 accumulation of the same batch means depends on grouping.
    let batch = |b: u32| pt::render(&scene, &gbuffer, &PtSettings::default(), 11, 2 * b, 2).pixels;
    let means: Vec<Vec<DVec3>> = (0..7).map(batch).collect();
    let sequential = means
        .iter()
        .fold(vec![DVec3::ZERO; means[0].len()], |acc, m| {
            acc.iter().zip(m).map(|(a, b)| *a + *b).collect()
        });
    let grouped: Vec<DVec3> = (0..means[0].len())
        .map(|p| {
            (means[0][p] + means[1][p])
                + (means[2][p] + means[3][p])
                + (means[4][p] + means[5][p] + means[6][p])
        })
        .collect();
    assert_ne!(
        sequential, grouped,
        "control: plain f64 sums happen to be associative here"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Every combination of hit policy, radius sampling and profile survives a checkpoint; an
/// estimator byte with an unknown bit is a typed error naming the field.
#[test]
fn estimator_options_round_trip_through_checkpoints() {
    let dir = std::env::temp_dir().join(format!("reshift-reference-flags-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("checkpoint.bin");
    for hits in [HitPolicy::UniformOne, HitPolicy::All] {
        for radius in [RadiusSampling::Exact, RadiusSampling::Xie] {
            for profile in [ProfileKind::Burley, ProfileKind::Dipole] {
                let settings = PtSettings {
                    hits,
                    radius,
                    profile,
                    ..PtSettings::default()
                };
                let config = ReferenceConfig {
                    settings,
                    ..config(2)
                };
                let r = Reference::new(config, 3, 2, Shard::WHOLE).unwrap();
                r.save(&path).unwrap();
                assert_eq!(Reference::load(&path).unwrap(), r, "{settings:?}");
            }
        }
    }
    let mut bytes = std::fs::read(&path).unwrap();
    let flags_at = 8 + 3 * 4 + 8 + 5 * 4;
    assert_eq!(bytes[flags_at], 7, "the all-options file sets bits 0–2");
    bytes[flags_at] = 8;
    std::fs::write(&path, &bytes).unwrap();
    let err = Reference::load(&path).unwrap_err();
    assert_eq!((err.field.as_str(), err.value.as_str()), ("estimator", "8"));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bad_input_is_a_typed_error() {
    assert!(Shard::parse("3/3", "--shard").is_err());
    assert!(Shard::parse("1-2", "--shard").is_err());
    assert_eq!(
        Shard::parse(" 1/4", "--shard").unwrap(),
        Shard { index: 1, count: 4 }
    );
    let zero = ReferenceConfig {
        spp_per_batch: 0,
        ..config(2)
    };
    let err = Reference::new(zero, 4, 4, Shard::WHOLE).unwrap_err();
    assert_eq!(
        (err.field.as_str(), err.value.as_str()),
        ("spp_per_batch", "0")
    );

    let (scene, gbuffer) = small_bumpy();
    let dir = std::env::temp_dir().join(format!("reshift-reference-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("checkpoint.bin");
    let mut r = Reference::new(config(2), gbuffer.width, gbuffer.height, Shard::WHOLE).unwrap();
    r.run(&scene, &gbuffer, 1);
    r.save(&path).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    std::fs::write(&path, &bytes[..bytes.len() - 5]).unwrap();
    let err = Reference::load(&path).unwrap_err();
    assert_eq!(
        (err.file.as_path(), err.field.as_str()),
        (path.as_path(), "pixels")
    );
    std::fs::write(&path, b"not a checkpoint").unwrap();
    assert_eq!(Reference::load(&path).unwrap_err().field, "magic");
    // A header that claims 60000×60000 pixels is refused before anything is allocated, both
    // for the limit and for the bytes present.
    let mut huge = bytes.clone();
    huge[8..16]
        .copy_from_slice(&[&60_000u32.to_le_bytes()[..], &60_000u32.to_le_bytes()[..]].concat());
    let err = Reference::from_bytes(&huge, &path).unwrap_err();
    assert_eq!(
        (err.field.as_str(), err.value.as_str()),
        ("width×height", "60000×60000")
    );
    let mut wide = bytes.clone();
    wide[8..12].copy_from_slice(&(2 * gbuffer.width).to_le_bytes());
    let err = Reference::from_bytes(&wide, &path).unwrap_err();
    assert_eq!(err.field, "pixels", "{err}");
    let incomplete = Reference::merge(vec![(path.clone(), r)]).unwrap_err();
    assert!(incomplete.reason.contains("incomplete"), "{incomplete}");
    assert_eq!(incomplete.file, path);
    std::fs::remove_dir_all(&dir).unwrap();
}
