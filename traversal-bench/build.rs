//! Detects Embree 3 (Debian/Ubuntu `libembree-dev`, or a prefix in `EMBREE_DIR`). When found and
//! its configuration matches the hand-written bindings in `src/embree.rs`, sets `cfg(embree)` and
//! links `libembree3`; otherwise the crate builds without it and `EMBREE_STATUS` says why.
//! `TRAVERSAL_BENCH_NO_EMBREE=1` skips the detection (builds as on a machine without Embree).

use std::path::{Path, PathBuf};

/// `(include dir, lib dir)` candidates: `EMBREE_DIR` first, then the system prefixes.
fn candidates() -> Vec<(PathBuf, PathBuf)> {
    let mut out = Vec::new();
    if let Some(dir) = std::env::var_os("EMBREE_DIR") {
        let dir = PathBuf::from(dir);
        out.push((dir.join("include"), dir.join("lib")));
        out.push((dir.join("include"), dir.join("lib64")));
    }
    for lib in [
        "/usr/lib/x86_64-linux-gnu",
        "/usr/lib/aarch64-linux-gnu",
        "/usr/lib64",
        "/usr/lib",
    ] {
        out.push((PathBuf::from("/usr/include"), PathBuf::from(lib)));
    }
    out.push((
        PathBuf::from("/usr/local/include"),
        PathBuf::from("/usr/local/lib"),
    ));
    out
}

/// `#define NAME VALUE` from a header, as text.
fn define(header: &str, name: &str) -> Option<String> {
    header.lines().find_map(|line| {
        let mut words = line.split_whitespace();
        (words.next() == Some("#define") && words.next() == Some(name))
            .then(|| words.next().unwrap_or("").to_string())
    })
}

/// `Ok(lib dir)` when a usable Embree 3 is installed, else why not.
fn detect() -> Result<PathBuf, String> {
    let mut reason = "no embree3/rtcore.h with libembree3.so found (apt-get install libembree-dev, or set EMBREE_DIR)".to_string();
    for (include, lib) in candidates() {
        let config = include.join("embree3/rtcore_config.h");
        println!("cargo::rerun-if-changed={}", config.display());
        let Ok(header) = std::fs::read_to_string(&config) else {
            continue;
        };
        if !Path::new(&lib).join("libembree3.so").exists() {
            continue;
        }
        // The bindings mirror RTCIntersectContext and RTCHit for this configuration only.
        let expected = [
            ("RTC_VERSION_MAJOR", "3"),
            ("RTC_MAX_INSTANCE_LEVEL_COUNT", "1"),
            ("EMBREE_MIN_WIDTH", "0"),
        ];
        match expected
            .iter()
            .find(|(name, value)| define(&header, name).as_deref() != Some(*value))
        {
            None => return Ok(lib),
            Some((name, value)) => {
                reason = format!(
                    "{} has {name} = {:?}, the bindings need {value}",
                    config.display(),
                    define(&header, name)
                );
            }
        }
    }
    Err(reason)
}

fn main() {
    println!("cargo::rerun-if-env-changed=EMBREE_DIR");
    println!("cargo::rerun-if-env-changed=TRAVERSAL_BENCH_NO_EMBREE");
    println!("cargo::rustc-check-cfg=cfg(embree)");
    let found = match std::env::var_os("TRAVERSAL_BENCH_NO_EMBREE") {
        Some(v) if !v.is_empty() && v != "0" => {
            Err("detection skipped (TRAVERSAL_BENCH_NO_EMBREE is set)".to_string())
        }
        _ => detect(),
    };
    match found {
        Ok(lib) => {
            println!("cargo::rustc-cfg=embree");
            println!("cargo::rustc-link-search=native={}", lib.display());
            println!("cargo::rustc-link-lib=dylib=embree3");
            println!("cargo::rustc-env=EMBREE_STATUS=linked ({})", lib.display());
        }
        Err(reason) => println!("cargo::rustc-env=EMBREE_STATUS=absent: {reason}"),
    }
}
