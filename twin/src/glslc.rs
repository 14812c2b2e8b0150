//! Running `glslc` from a build script (`engine/build.rs`, `methods/build.rs`): finding it and
//! watching it ([`Glslc::find`]), compiling a compute shader ([`Glslc::compile`]) and checking
//! that it lays out every contract struct as Rust does ([`Glslc::check_layouts`]).
//!
//! Freshness: [`Glslc::find`] watches the `glslc` it runs, or, when there is none, every
//! directory it looked in (`$PATH`, or the parent of an absolute `$GLSLC`), so installing `glslc`
//! after a build without it rebuilds with shaders (`tests/newcomer_order.rs`).

use std::collections::HashMap;
use std::env;
use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::process::Command;

use crate::Item;

/// The `glslc` a build script runs: `$GLSLC`, else `glslc` on `$PATH`.
pub struct Glslc {
    program: OsString,
}

impl Glslc {
    /// The `glslc` to run, or `None` when it does not run (`glslc --version` fails); prints the
    /// `cargo::rerun-if-…` lines that rebuild when it changes, appears or disappears.
    pub fn find() -> Option<Glslc> {
        println!("cargo::rerun-if-env-changed=GLSLC");
        let program = env::var_os("GLSLC").unwrap_or_else(|| "glslc".into());
        let found = Command::new(&program)
            .arg("--version")
            .output()
            .is_ok_and(|o| o.status.success());
        watch(Path::new(&program), found);
        found.then_some(Glslc { program })
    }

    /// Compiles the compute shader `source` with `includes` on the include path to `output`;
    /// panics (failing the build) with `glslc`'s message when it does not compile.
    pub fn compile(&self, source: &Path, includes: &[PathBuf], output: &Path) {
        let mut command = Command::new(&self.program);
        command.args([
            "-fshader-stage=compute",
            "--target-env=vulkan1.2",
            "-O",
            "-Werror",
        ]);
        for dir in includes {
            command.arg(format!("-I{}", dir.display()));
        }
        let result = command
            .arg(source)
            .arg("-o")
            .arg(output)
            .output()
            .expect("glslc ran once already");
        assert!(
            result.status.success(),
            "glslc failed on {}:\n{}",
            source.display(),
            String::from_utf8_lossy(&result.stderr)
        );
    }

    /// Fails the build unless `glslc` lays out every contract struct of `items` as Rust does:
    /// compiles probe shaders (without `-O`, so names stay) into `out_dir` that include
    /// `headers` (found under `include`) and declare an array of each struct and each
    /// push-constant block, and compares every member offset and each struct's array stride with
    /// the Rust `offset_of!` and `size_of` the items carry.
    pub fn check_layouts(&self, headers: &[&str], include: &Path, out_dir: &Path, items: &[Item]) {
        let mut main = String::from("#version 460\n");
        for header in headers {
            main += &format!("#include \"{header}\"\n");
        }
        main += "layout(local_size_x = 1) in;\n";
        let mut probes = vec![("layout_probe".to_string(), main)];
        for (binding, item) in items.iter().enumerate() {
            if let Some((file, _)) = crate::push_constant_header("", item) {
                let text = format!(
                    "#version 460\n#include \"contract/{file}\"\nlayout(local_size_x = 1) in;\n\
                     void main() {{}}\n"
                );
                probes.push((
                    format!("layout_probe_{}", file.trim_end_matches(".glsl")),
                    text,
                ));
            } else if let Item::Struct { glsl, .. } = item {
                probes[0].1 += &format!(
                    "layout(std430, binding = {binding}) readonly buffer Probe{binding} \
                     {{ {glsl} probe{binding}[]; }};\n"
                );
            }
        }
        probes[0].1 += "void main() {}\n";
        let mut found = HashMap::new();
        for (name, text) in probes {
            let source = out_dir.join(format!("{name}.comp"));
            let spirv = out_dir.join(format!("{name}.spv"));
            std::fs::write(&source, text).expect("OUT_DIR is writable");
            let result = Command::new(&self.program)
                .args(["--target-env=vulkan1.2", "-Werror"])
                .arg(format!("-I{}", include.display()))
                .arg(&source)
                .arg("-o")
                .arg(&spirv)
                .output()
                .expect("glslc ran once already");
            assert!(
                result.status.success(),
                "glslc failed on the layout probe {}:\n{}",
                source.display(),
                String::from_utf8_lossy(&result.stderr)
            );
            let bytes = std::fs::read(&spirv).expect("glslc wrote the probe");
            found.extend(crate::spirv::layouts(&bytes).expect("glslc writes SPIR-V"));
        }
        for item in items {
            let Item::Struct {
                rust,
                glsl,
                fields,
                size,
                push_constant,
                ..
            } = item
            else {
                continue;
            };
            let layout = found
                .get(*glsl)
                .unwrap_or_else(|| panic!("the layout probe has no struct {glsl} (Rust {rust})"));
            let rust_offsets: Vec<u32> = fields.iter().map(|f| f.offset as u32).collect();
            assert_eq!(
                layout.offsets, rust_offsets,
                "glslc's member offsets of {glsl} differ from Rust's {rust}"
            );
            if push_constant.is_none() {
                assert_eq!(
                    layout.array_stride,
                    Some(*size as u32),
                    "glslc's array stride of {glsl} differs from size_of::<{rust}>()"
                );
            }
        }
    }
}

/// Reruns the build script when the `glslc` it would run changes, appears or disappears: watches
/// the resolved executable when `found`, otherwise every existing directory it would be looked
/// up in.
fn watch(glslc: &Path, found: bool) {
    println!("cargo::rerun-if-env-changed=PATH");
    let candidates: Vec<PathBuf> = if glslc.components().count() > 1 {
        vec![glslc.to_path_buf()]
    } else {
        env::split_paths(&env::var_os("PATH").unwrap_or_default())
            .map(|dir| dir.join(glslc))
            .collect()
    };
    let resolved = candidates.iter().find(|path| path.is_file());
    match resolved {
        Some(path) if found => println!("cargo::rerun-if-changed={}", path.display()),
        _ => {
            for dir in candidates.iter().filter_map(|path| path.parent()) {
                if dir.is_dir() {
                    println!("cargo::rerun-if-changed={}", dir.display());
                }
            }
        }
    }
}
