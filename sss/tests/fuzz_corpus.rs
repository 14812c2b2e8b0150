//! Replays every committed fuzzing corpus file (`fuzz/corpus/<target>/*`: the project's own
//! scenes and meshes, small checkpoints and the minimised inputs that once crashed) through the
//! fuzz targets' bodies: each must load or fail with a one-line error of at most 200 characters,
//! never panic. Deterministic and quick; the fuzzing campaigns themselves are `fuzz/run-all.sh`.

#[path = "../../fuzz/src/lib.rs"]
mod reshift_fuzz;

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;

#[test]
fn every_corpus_file_loads_or_fails_in_one_line() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../fuzz/corpus");
    let mut failures = Vec::new();
    for (name, target) in reshift_fuzz::TARGETS {
        let mut files: Vec<_> = std::fs::read_dir(root.join(name))
            .unwrap_or_else(|e| panic!("fuzz/corpus/{name}: {e}"))
            .map(|entry| entry.expect("readable corpus folder").path())
            .collect();
        files.sort();
        assert!(!files.is_empty(), "fuzz/corpus/{name} is empty");
        for file in files {
            let data = std::fs::read(&file).expect("readable corpus file");
            if catch_unwind(AssertUnwindSafe(|| target(&data))).is_err() {
                failures.push(file.display().to_string());
            }
        }
    }
    assert!(failures.is_empty(), "panicked on {failures:?}");
}
