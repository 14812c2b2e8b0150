//! Compiles the Vulkan backend's compute shaders from GLSL to SPIR-V with `glslc` (DESIGN §6).
//!
//! Every `engine/glsl/*.glsl` is one compute entry point; the GLSL twins it includes live
//! beside their Rust modules (`restir/glsl/`, `sss/glsl/`, `shifts/glsl/`) and are found through
//! `-I`. The SPIR-V goes to `$OUT_DIR/<stem>.spv`, `$OUT_DIR/spirv_table.rs` maps stems to it, and the cfg `reshift_glslc` tells the crate to
//! embed it. Without `glslc` the build still succeeds (with a warning) and the backend reports
//! what to install; a shader that fails to compile fails the build.

use std::env;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Include directories of the GLSL twins and of the kernels' shared headers, relative to this
/// crate.
const INCLUDE_DIRS: [&str; 4] = [
    "../restir/glsl",
    "../sss/glsl",
    "../shifts/glsl",
    "glsl/include",
];

fn main() {
    println!("cargo::rustc-check-cfg=cfg(reshift_glslc)");
    println!("cargo::rerun-if-env-changed=GLSLC");
    println!("cargo::rerun-if-changed=glsl");
    for dir in INCLUDE_DIRS {
        if Path::new(dir).is_dir() {
            println!("cargo::rerun-if-changed={dir}");
        }
    }
    let glslc = env::var_os("GLSLC").unwrap_or_else(|| "glslc".into());
    let found = Command::new(&glslc)
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    if !found {
        println!(
            "cargo::warning=glslc was not found; the Vulkan backend is disabled \
             (install it with `apt-get install glslc` and rebuild)"
        );
        return;
    }
    let out_dir = PathBuf::from(env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    let mut sources: Vec<PathBuf> = std::fs::read_dir("glsl")
        .expect("engine/glsl exists")
        .map(|entry| entry.expect("readable engine/glsl").path())
        .filter(|path| path.extension().is_some_and(|e| e == "glsl"))
        .collect();
    sources.sort();
    let mut table = String::from(
        "/// The SPIR-V compiled from `engine/glsl/<name>.glsl`, by name.\n\
         pub(super) fn embedded_named(name: &str) -> Option<&'static [u8]> {\n    match name {\n",
    );
    for source in &sources {
        let stem = source.file_stem().expect("a file name").to_string_lossy();
        let output = out_dir.join(format!("{stem}.spv"));
        let mut command = Command::new(&glslc);
        command.args([
            "-fshader-stage=compute",
            "--target-env=vulkan1.2",
            "-O",
            "-Werror",
        ]);
        for dir in INCLUDE_DIRS {
            command.arg(format!("-I{dir}"));
        }
        let result = command
            .arg(source)
            .arg("-o")
            .arg(&output)
            .output()
            .expect("glslc ran once already");
        assert!(
            result.status.success(),
            "glslc failed on {}:\n{}",
            source.display(),
            String::from_utf8_lossy(&result.stderr)
        );
        table.push_str(&format!(
            "        {stem:?} => Some(include_bytes!({:?})),\n",
            output.display().to_string()
        ));
    }
    table.push_str("        _ => None,\n    }\n}\n");
    std::fs::write(out_dir.join("spirv_table.rs"), table).expect("OUT_DIR is writable");
    println!("cargo::rustc-cfg=reshift_glslc");
}
