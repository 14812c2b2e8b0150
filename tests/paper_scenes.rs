//! Paper 001's own scenes from the command line: glTF files in scene files (every malformed file
//! of the fuzz corpus is one line naming the file and the element, exit status 1), the asset
//! directory (`--assets`, `RESHIFT_ASSETS`, and the line that says where to get the assets),
//! `ajax` and `ajax-many-lights` rendered, and a portrait scene compared at its own size.
//!
//! The tests that read `../shared/assets/restir-sss` skip where it is missing and say why,
//! unless `RESHIFT_REQUIRE_ASSETS=1` (`.ci/run` sets it where the folder exists).

mod common;

use std::path::{Path, PathBuf};
use std::process::Output;

use common::{command, ok, one_line_error, scratch};
use sss::scene::assets::{ASSETS_ENV, shared_or_skip};

/// Runs `reshift args` with the asset directory `assets` in the environment, if any.
fn reshift(args: &[&str], assets: Option<&Path>) -> Output {
    let mut command = command(args);
    if let Some(dir) = assets {
        command.env(ASSETS_ENV, dir);
    }
    command.output().expect("run reshift")
}

fn repo() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// A scene whose only object is the glTF file `mesh` beside it (its own materials), lit by a
/// point light.
fn gltf_scene(mesh: &str) -> String {
    format!(
        r#"
[camera]
resolution = [8, 6]
vfov = 40.0
eye = [0.0, 0.0, 5.0]
target = [0.0, 0.0, 0.0]

[[objects]]
name = "file"
mesh = {mesh:?}

[[lights]]
type = "point"
position = [0.0, 3.0, 3.0]
intensity = [1.0, 1.0, 1.0]
"#
    )
}

/// Every malformed glTF file of the fuzz corpus (`fuzz/corpus/gltf/regress-*`, at least 20),
/// placed by a scene file, makes `reshift render` fail with one line naming the glTF file and
/// the element (`field \`…\``), exit status 1, no panic; a valid seed of the same corpus renders.
#[test]
fn malformed_gltf_files_are_one_line_errors() {
    let corpus = repo().join("fuzz/corpus/gltf");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&corpus)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    files.sort();
    // Beside its scene file in a folder the command runs in, so that the error's file name is
    // short enough to print whole.
    let dir = scratch("gltf");
    let (mut malformed, mut valid) = (0, 0);
    for file in &files {
        let name = file.file_name().unwrap().to_str().unwrap();
        std::fs::copy(file, dir.join(name)).unwrap();
        let scene = format!("{name}.toml");
        std::fs::write(dir.join(&scene), gltf_scene(name)).unwrap();
        let args = [
            "render", "--scene", &scene, "--method", "pt:1", "--frames", "1", "--out", "out",
        ];
        let o = command(&args)
            .current_dir(&dir)
            .output()
            .expect("run reshift");
        if name.starts_with("regress-") {
            one_line_error(&o, &[name, "field `"]);
            malformed += 1;
        } else if name.starts_with("seed-") && o.status.success() {
            valid += 1;
        }
    }
    assert!(malformed >= 20, "{malformed} malformed files");
    assert!(valid >= 1, "no seed rendered");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Without an asset directory `ajax` is one line naming the field, the setting and where the
/// assets come from; with a directory that lacks them, the directory and the setting.
#[test]
fn missing_assets_say_where_to_get_them() {
    let args = [
        "render", "--scene", "ajax", "--method", "pt:1", "--frames", "1",
    ];
    one_line_error(
        &reshift(&args, None),
        &[
            "objects[0].asset",
            ASSETS_ENV,
            "--assets",
            "ReSTIR-SSS-Assets",
        ],
    );
    let empty = scratch("no-assets");
    one_line_error(
        &reshift(&args, Some(&empty)),
        &["ajax/ajax.gltf", ASSETS_ENV, "ReSTIR-SSS-Assets"],
    );
    let with_flag = [&args[..], &["--assets", empty.to_str().unwrap()]].concat();
    one_line_error(&reshift(&with_flag, None), &["--assets", "ajax/ajax.gltf"]);
    std::fs::remove_dir_all(&empty).unwrap();
}

/// `ajax` and `ajax-many-lights` render from the shared assets (through `RESHIFT_ASSETS` and
/// through `--assets`) at a small portrait size: the images have the size, the bust is lit
/// (its pixels are not black), and the many-lights scene's emitters are seen.
#[test]
fn paper_scenes_render_from_the_assets() {
    let Some(assets) = shared_or_skip(repo(), "paper_scenes_render_from_the_assets") else {
        return;
    };
    let dir = scratch("ajax");
    for (scene, by_flag) in [("ajax", false), ("ajax-many-lights", true)] {
        let out = dir.join(scene);
        let mut args = vec![
            "render",
            "--scene",
            scene,
            "--method",
            "pt:2",
            "--frames",
            "1",
            "--resolution",
            "24x36",
            "--out",
            out.to_str().unwrap(),
            "--json",
        ];
        if by_flag {
            args.extend(["--assets", assets.to_str().unwrap()]);
        }
        let json: serde_json::Value =
            serde_json::from_str(&ok(&reshift(&args, (!by_flag).then_some(&assets)))).unwrap();
        let png = image::open(json["png"].as_str().unwrap())
            .unwrap()
            .to_rgb8();
        assert_eq!(png.dimensions(), (24, 36), "{scene}");
        let lit = png.pixels().filter(|p| p.0.iter().any(|&c| c > 32)).count();
        assert!(lit > 24 * 36 / 10, "{scene}: {lit} lit pixels");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `compare` on a portrait scene file renders at the file's resolution (12 × 18), not at a
/// landscape default: the reference and every method image are 12 wide and 18 tall.
#[test]
fn compare_renders_a_portrait_scene_at_its_own_size() {
    let dir = scratch("portrait");
    let text = std::fs::read_to_string(repo().join("scenes/bumpy.toml"))
        .unwrap()
        .replace("resolution = [256, 192]", "resolution = [12, 18]");
    assert!(text.contains("[12, 18]"));
    let scene = dir.join("portrait.toml");
    std::fs::write(&scene, text).unwrap();
    let out = dir.join("out");
    ok(&reshift(
        &[
            "compare",
            "--scene",
            scene.to_str().unwrap(),
            "--methods",
            "pt,restir:hybrid",
            "--baseline",
            "pt",
            "--replicas",
            "2",
            "--frames",
            "2",
            "--reference-spp",
            "16",
            "--reference-batch-spp",
            "8",
            "--denoise",
            "none",
            "--no-video",
            "--out",
            out.to_str().unwrap(),
            "--cache",
            dir.join("cache").to_str().unwrap(),
        ],
        None,
    ));
    let mut pngs = 0;
    for entry in std::fs::read_dir(&out).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_str().unwrap().to_string();
        let single = ["reference.png", "pt.png", "restir-hybrid.png"];
        if single.contains(&name.as_str()) {
            let png = image::open(&path).unwrap();
            assert_eq!((png.width(), png.height()), (12, 18), "{name}");
            pngs += 1;
        }
    }
    assert_eq!(pngs, 3, "reference and method images in {}", out.display());
    std::fs::remove_dir_all(&dir).unwrap();
}
