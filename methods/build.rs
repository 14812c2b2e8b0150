//! Renders the methods' contracts to GLSL headers and compiles their kernels to SPIR-V with
//! `glslc` (docs/adding-a-method.md, docs/gpu-backend.md).
//!
//! Contracts: a method folder's `contract.rs` (one `twin::contract!`) is included here through
//! its line `<folder> with contract` in `src/registry.rs` (the list the crate reads too), so the
//! items rendered are the ones the crate compiles; each is written to
//! `$OUT_DIR/glsl/contract/<folder>.glsl`, with one header per push-constant block.
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

use twin::glslc::Glslc;

/// The build script's reading of `src/registry.rs`: each folder marked `with contract` has its
/// `src/<folder>/contract.rs` included as a module, and [`contracts`] lists their items.
macro_rules! registry {
    ($($name:ident $(with $contract:ident)?),* $(,)?) => {
        $($(
            #[allow(dead_code)]
            mod $name {
                // From the manifest: a relative path would be read from src/registry.rs, where
                // the macro is called.
                include!(concat!(
                    env!("CARGO_MANIFEST_DIR"),
                    "/src/",
                    stringify!($name),
                    "/",
                    stringify!($contract),
                    ".rs"
                ));
            }
        )?)*
        /// Each method folder with a contract, and its items.
        fn contracts() -> Vec<(&'static str, Vec<twin::Item>)> {
            vec![$($((stringify!($name), { let _ = stringify!($contract); $name::glsl_items() }),)?)*]
        }
    };
}

include!("src/registry.rs");

fn main() {
    println!("cargo::rustc-check-cfg=cfg(reshift_glslc)");
    // A new method folder comes with its line in src/registry.rs; a folder is watched whole
    // (its kernels, twins and contract).
    println!("cargo::rerun-if-changed=src/registry.rs");
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
