//! `reshift gpu-report` end to end on whatever Vulkan device there is (lavapipe in CI) at tiny
//! sizes, on `bumpy` and on paper 001's `ajax` (portrait): it exits 0, writes the markdown file it prints, and the file has the device table, a
//! passing parity row per preset, a timed row for every pass of every preset and for every
//! memoryless method, and the equal-time comparison's table. Skips without Vulkan unless
//! `RESHIFT_REQUIRE_VULKAN=1`.

use std::process::Command;

use engine::Preset;
use engine::plan::Plan;
use sss::scene::assets::shared_or_skip;

#[test]
fn gpu_report_writes_the_markdown_tables() {
    report("bumpy", None, ["24x16", "32x24"]);
}

/// The report on paper 001's own scene (`ajax`, from the shared assets) at portrait sizes, as
/// `reshift gpu-report --scene ajax --sizes 720x1080` measures it on a GPU; skips without the
/// assets unless `RESHIFT_REQUIRE_ASSETS=1`.
#[test]
fn gpu_report_runs_on_the_paper_scene() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    if let Some(assets) = shared_or_skip(root, "gpu_report_runs_on_the_paper_scene") {
        report("ajax", Some(&assets), ["16x24", "24x36"]);
    }
}

/// Runs the report on `scene` at `sizes` (the parity and comparison runs at the first) and
/// checks its tables.
fn report(scene: &str, assets: Option<&std::path::Path>, sizes: [&str; 2]) {
    let dir =
        std::env::temp_dir().join(format!("reshift-gpu-report-{scene}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let out = dir.join("report.md");
    let cache = dir.join("cache");
    let mut command = Command::new(env!("CARGO_BIN_EXE_reshift"));
    if let Some(dir) = assets {
        command.arg("--assets").arg(dir);
    }
    let output = command
        .args(["gpu-report", "--scene", scene, "--frames", "3"])
        .args(["--sizes", &sizes.join(",")])
        .args(["--parity-size", sizes[0], "--parity-frames", "2"])
        .args(["--compare-size", sizes[0], "--compare-frames", "2"])
        .args(["--reference-spp", "8", "--reference-batch-spp", "4"])
        .arg("--cache")
        .arg(&cache)
        .arg("--out")
        .arg(&out)
        .output()
        .expect("run reshift");
    let stderr = String::from_utf8_lossy(&output.stderr);
    // The one-line errors of a machine without Vulkan (engine::vulkan::VulkanError).
    let unavailable = ["libvulkan", "no Vulkan driver", "no Vulkan device", "glslc"];
    if !output.status.success() && unavailable.iter().any(|u| stderr.contains(u)) {
        if std::env::var("RESHIFT_REQUIRE_VULKAN").as_deref() == Ok("1") {
            panic!("RESHIFT_REQUIRE_VULKAN=1 but gpu-report failed: {stderr}");
        }
        return eprintln!("gpu_report: skipped, Vulkan unavailable: {stderr}");
    }
    assert!(
        output.status.success(),
        "exit {:?}: {stderr}",
        output.status
    );
    let md = std::fs::read_to_string(&out).expect("the report file");
    assert!(String::from_utf8_lossy(&output.stdout).contains(&md));
    for heading in [
        "## Device",
        "| maxStorageBufferRange |",
        "## Parity with the CPU backend",
        "## Time per frame",
        "## Equal-time comparison",
        "| method | spp |",
    ] {
        assert!(md.contains(heading), "no {heading:?} in\n{md}");
    }
    let rows: Vec<Vec<&str>> = md
        .lines()
        .filter(|l| l.starts_with("| "))
        .map(|l| l.split('|').map(str::trim).collect())
        .collect();
    for preset in Preset::all() {
        assert!(
            rows.iter().any(|r| r[1] == preset.name && r[6] == "pass"),
            "parity of {} missing or failed:\n{md}",
            preset.name
        );
        let method = format!("restir:{}", preset.name);
        for size in sizes.map(|s| s.replace('x', "×")) {
            let labels = Plan::lower(&preset).steps.into_iter().map(|s| s.label);
            for pass in labels.chain(["**frame**".to_string()]) {
                let row = rows
                    .iter()
                    .find(|r| r[1] == size && r[2] == method && r[3] == pass)
                    .unwrap_or_else(|| panic!("no {size} {method} {pass} row:\n{md}"));
                let median: f64 = row[4].parse().expect("a median in ms");
                assert!(median > 0.0 && median.is_finite(), "{row:?}");
            }
        }
    }
    for method in [
        "pt:1",
        "random-walk:1",
        "single-scatter:1",
        "image-space:1",
        "adaptive",
    ] {
        let size = sizes[1].replace('x', "×");
        assert!(
            rows.iter()
                .any(|r| r[1] == size && r[2] == method && r[4].parse::<f64>().is_ok()),
            "no timed row of {method}:\n{md}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
