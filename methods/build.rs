//! Writes the crate's method registry, renders the methods' contracts to GLSL headers and
//! compiles their kernels to SPIR-V with `glslc` (docs/adding-a-method.md, docs/gpu-backend.md).
//!
//! Registry: a method is registered by its `pub mod <name>;` line between `// Method registry`
//! and `// End of the method registry` in `src/lib.rs`; `methods-registry` (methods/registry,
//! a build dependency) reads those lines. Its `METHODS` become `$OUT_DIR/registry.rs`,
//! `pub const REGISTRY: &[Entry] = &[<name>::ENTRY, ...];`, which `src/lib.rs` includes.
//!
//! Contracts: a method folder's `contract.rs` (one `twin::contract!`) exists or not; the ones that
//! exist `methods-registry` compiled, so the items rendered are the ones the crate compiles; each
//! is written to `$OUT_DIR/glsl/contract/<folder>.glsl`, with one header per push-constant block.
//!
//! Kernels: every `src/<folder>/method_*.glsl` is one compute entry point. It finds the GLSL of
//! its folder beside it, the generated headers through `$OUT_DIR/glsl`, and the engine's GLSL
//! (the twins of `restir`, `sss`, `shifts` and the engine's contract headers) through the include
//! path the engine's build script publishes as `links` metadata (`DEP_RESHIFT_ENGINE_GLSL_INCLUDE`,
//! engine/build.rs). The SPIR-V goes to `$OUT_DIR/<stem>.spv` and the cfg `reshift_glslc` tells
//! the crate to embed it (`spirv!` in src/lib.rs). Without `glslc` the build still succeeds and
//! the kernels report what to install; a kernel that fails to compile fails the build.

use std::env;
use std::path::PathBuf;

use methods_registry::{METHODS, contracts};
use twin::glslc::Glslc;

/// `src/lib.rs`'s `REGISTRY`: one line per registered method, the line that names it in a
/// compile error (a module without `ENTRY`).
fn registry() -> String {
    let mut out = String::from(
        "/// Every method family the CLI knows, one per `pub mod` line of the method registry in\n\
         /// `src/lib.rs`, in its order (the modules' alphabetical order, which `cargo fmt` keeps).\n\
         pub const REGISTRY: &[Entry] = &[\n",
    );
    for method in METHODS {
        let name = method.name;
        out.push_str(&format!(
            "    {name}::ENTRY, // `pub mod {name};` in the method registry of src/lib.rs: \
             a method defines `pub const ENTRY: Entry`\n"
        ));
    }
    out.push_str("];\n");
    out
}

fn main() {
    println!("cargo::rustc-check-cfg=cfg(reshift_glslc)");
    // A new method comes with its line in src/lib.rs; a folder is watched whole (its kernels,
    // twins and contract).
    println!("cargo::rerun-if-changed=src/lib.rs");
    let mut folders: Vec<PathBuf> = std::fs::read_dir("src")
        .expect("methods/src exists")
        .map(|entry| entry.expect("readable methods/src").path())
        .filter(|path| path.is_dir())
        .collect();
    folders.sort();
    let mut kernels = Vec::new();
    for folder in &folders {
        println!("cargo::rerun-if-changed={}", folder.display());
        for entry in std::fs::read_dir(folder).expect("a readable method folder") {
            let path = entry.expect("a readable method folder").path();
            let name = path.file_name().expect("a file name").to_string_lossy();
            if name.starts_with("method_") && name.ends_with(".glsl") {
                kernels.push(path);
            }
        }
    }
    kernels.sort();

    let out_dir = PathBuf::from(env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    std::fs::write(out_dir.join("registry.rs"), registry()).expect("OUT_DIR is writable");
    let generated = out_dir.join("glsl");
    let contract_dir = generated.join("contract");
    std::fs::create_dir_all(&contract_dir).expect("OUT_DIR is writable");
    let write = |name: &str, text: String| {
        std::fs::write(contract_dir.join(name), text).expect("OUT_DIR is writable");
    };
    let mut items = Vec::new();
    let mut headers = Vec::new();
    for (folder, folder_items) in contracts() {
        let source = format!("methods/src/{folder}/contract.rs");
        for item in &folder_items {
            if let Some((name, text)) = twin::push_constant_header(&source, item) {
                write(&name, text);
            }
        }
        let guard = format!("CONTRACT_{}_GLSL", folder.to_uppercase());
        write(
            &format!("{folder}.glsl"),
            twin::header(&guard, &source, &folder_items),
        );
        headers.push(format!("contract/{folder}.glsl"));
        items.extend(folder_items);
    }

    let Some(glslc) = Glslc::find() else {
        println!(
            "cargo::warning=glslc was not found; the methods' Vulkan kernels are disabled \
             (install it with `apt-get install glslc`; the next build picks it up)"
        );
        return;
    };
    let headers: Vec<&str> = headers.iter().map(String::as_str).collect();
    glslc.check_layouts(&headers, &generated, &out_dir, &items);
    let engine = env::var_os("DEP_RESHIFT_ENGINE_GLSL_INCLUDE")
        .expect("the engine's build script publishes its GLSL include path");
    let mut includes: Vec<PathBuf> = env::split_paths(&engine).collect();
    includes.push(generated);
    for kernel in &kernels {
        let stem = kernel.file_stem().expect("a file name").to_string_lossy();
        glslc.compile(kernel, &includes, &out_dir.join(format!("{stem}.spv")));
    }
    println!("cargo::rustc-cfg=reshift_glslc");
}
