//! What the command-line tests share: running the `reshift` binary, reading its output, fresh
//! folders, and the check of a one-line error.

// Each test file uses a part of this module.
#![allow(dead_code)]

use std::path::PathBuf;
use std::process::{Command, Output};

/// The `reshift` binary with `args`, without an asset directory from the environment (tests
/// that need one set it).
pub fn command(args: &[&str]) -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_reshift"));
    command.args(args).env_remove("RESHIFT_ASSETS");
    command
}

/// Runs `reshift args`.
pub fn reshift(args: &[&str]) -> Output {
    command(args).output().expect("run reshift")
}

pub fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A fresh folder for one test.
pub fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("reshift-cli-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

/// The standard output of a run that succeeded.
pub fn ok(o: &Output) -> String {
    assert!(o.status.success(), "exit {:?}\n{}", o.status, stderr(o));
    stdout(o)
}

/// Exit status 1 and exactly one stderr line `reshift: …` of at most 200 characters after the
/// prefix, containing every needle, no panic.
pub fn one_line_error(o: &Output, needles: &[&str]) {
    let err = stderr(o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    let message = err.trim_end().trim_start_matches("reshift: ");
    assert!(message.chars().count() <= 200, "{err}");
    assert!(err.starts_with("reshift: "), "{err}");
    for needle in needles {
        assert!(err.contains(needle), "expected {needle:?} in {err}");
    }
}
