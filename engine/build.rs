//! Renders the Rust ↔ GLSL contract to GLSL headers and compiles the Vulkan backend's compute
//! shaders to SPIR-V with `glslc` (DESIGN §6, docs/gpu-backend.md).
//!
//! Contract: the crates declare what their GLSL twins share with them in `twin::contract!`
//! files (`restir/src/contract.rs`, `geometry/src/contract.rs`, `sss/src/contract.rs`,
//! `shifts/src/contract.rs`, `src/contract.rs`, `src/purpose.rs`) and register shifts in
//! `shifts/src/registry.rs`. This script includes the same files, so the items it renders are the
//! ones the crates compile, and writes `$OUT_DIR/glsl/contract/`: `restir.glsl`,
//! `geometry.glsl`, `sss.glsl`, `shifts.glsl` (with the shift kinds and their dispatch list),
//! `engine.glsl`, one header per push-constant block, and `shift_twins.glsl` (the includes of
//! the registered shifts' GLSL twins).
//!
//! Shaders: every `glsl/*.glsl` is one compute entry point; the GLSL twins it includes live
//! beside their Rust modules (`restir/glsl/`, `geometry/glsl/`, `sss/glsl/`, `shifts/glsl/`) and
//! are found through `-I`, as are the generated headers. The SPIR-V goes to
//! `$OUT_DIR/<stem>.spv`, `$OUT_DIR/spirv_table.rs` maps stems to it, and the cfg
//! `reshift_glslc` tells the crate to embed it. Without `glslc` the build still succeeds (with a warning) and the backend reports
//! what to install; a shader that fails to compile fails the build.
//!
//! Its include path (the twins' directories and the generated headers) is published to crates
//! with kernels of their own through the `links` metadata `DEP_RESHIFT_ENGINE_GLSL_INCLUDE`
//! (`methods/build.rs`). Running `glslc` and checking layouts is `twin::glslc`, shared with them.

use std::env;
use std::path::{Path, PathBuf};

use twin::glslc::Glslc;

#[allow(dead_code)]
mod restir_contract {
    include!("../restir/src/contract.rs");
}

#[allow(dead_code)]
mod geometry_contract {
    include!("../geometry/src/contract.rs");
}

#[allow(dead_code)]
mod sss_contract {
    include!("../sss/src/contract.rs");
}

#[allow(dead_code)]
mod shifts_contract {
    include!("../shifts/src/contract.rs");
}

#[allow(dead_code)]
mod engine_contract {
    include!("src/contract.rs");
}

#[allow(dead_code)]
mod purpose {
    include!("src/purpose.rs");
}

#[allow(dead_code)]
mod kernels {
    include!("src/plan/kernels.rs");
}

/// Whether a registry line's flags include `resolves_deferred_index`, as a GLSL boolean (the
/// other flags, read by `shifts::ShiftKind` only, are checked there).
macro_rules! registry_flag {
    ($($flag:ident),*) => {
        if [$(stringify!($flag)),*].contains(&"resolves_deferred_index") {
            "true"
        } else {
            "false"
        }
    };
}

/// The build-side reading of `shifts/src/registry.rs` (the crate's reading is
/// `shifts/src/kind.rs`): per line, the kind constant `SHIFT_<KIND>` (its position), the entry
/// `X(SHIFT_<KIND>, glsl_twin, resolves_deferred_index)` of `SHIFT_KINDS(X)`, and the twin's
/// file; the CPU expression is not compiled here.
macro_rules! shift_registry {
    ($(
        $(#[doc = $doc:literal])*
        $kind:ident = $name:literal, $file:ident :: $twin:ident, $cpu:expr $(, $flag:ident)* ;
    )*) => {
        /// The shift kinds and the GLSL files of their twins, in registry order.
        fn shift_registry() -> (twin::Item, Vec<&'static str>) {
            let variants = vec![$(twin::Variant {
                name: stringify!($kind),
                code: 0,
                args: vec![stringify!($twin).to_string(), registry_flag!($($flag),*).to_string()],
                docs: vec![$(twin::doc_text(&format!("doc = {}", stringify!($doc))).unwrap_or_default()),*],
            }),*];
            let variants = variants
                .into_iter()
                .enumerate()
                .map(|(code, v)| twin::Variant { code: code as u32, ..v })
                .collect();
            let kinds = twin::Item::Kinds {
                rust: "shifts::ShiftKind",
                prefix: "SHIFT",
                zero: None,
                variants,
                docs: vec![
                    "The registered shifts (shifts/src/registry.rs): X(SHIFT_<KIND>, twin, \
                     resolves_deferred_index)."
                        .into(),
                ],
            };
            (kinds, vec![$(stringify!($file)),*])
        }
    };
}

include!("../shifts/src/registry.rs");

/// The contract files this script includes, relative to this crate.
const CONTRACTS: [&str; 8] = [
    "../restir/src/contract.rs",
    "../geometry/src/contract.rs",
    "../sss/src/contract.rs",
    "../shifts/src/contract.rs",
    "../shifts/src/registry.rs",
    "src/contract.rs",
    "src/purpose.rs",
    "src/plan/kernels.rs",
];

/// Include directories of the GLSL twins, relative to this crate (the generated headers are
/// found through `$OUT_DIR/glsl`).
const INCLUDE_DIRS: [&str; 4] = [
    "../restir/glsl",
    "../geometry/glsl",
    "../sss/glsl",
    "../shifts/glsl",
];

/// Writes the contract headers into `dir/contract/`; returns every item rendered.
fn write_contract(dir: &Path) -> Vec<twin::Item> {
    let contract = dir.join("contract");
    std::fs::create_dir_all(&contract).expect("OUT_DIR is writable");
    let write = |name: &str, text: String| {
        std::fs::write(contract.join(name), text).expect("OUT_DIR is writable");
    };
    write(
        "restir.glsl",
        twin::header(
            "CONTRACT_RESTIR_GLSL",
            "restir/src/contract.rs",
            &restir_contract::glsl_items(),
        ),
    );
    let geometry = geometry_contract::glsl_items();
    write(
        "geometry.glsl",
        twin::header(
            "CONTRACT_GEOMETRY_GLSL",
            "geometry/src/contract.rs",
            &geometry,
        ),
    );
    let sss = sss_contract::glsl_items();
    write(
        "sss.glsl",
        twin::header("CONTRACT_SSS_GLSL", "sss/src/contract.rs", &sss),
    );
    let (kinds, files) = shift_registry();
    let mut shifts = shifts_contract::glsl_items();
    shifts.push(kinds);
    write(
        "shifts.glsl",
        twin::header(
            "CONTRACT_SHIFTS_GLSL",
            "shifts/src/contract.rs and shifts/src/registry.rs",
            &shifts,
        ),
    );
    let mut twins = String::from(
        "// Generated by engine/build.rs from shifts/src/registry.rs: the GLSL twins of the\n\
         // registered shifts, included by shifts/glsl/shift.glsl.\n",
    );
    let mut seen = Vec::new();
    for file in files {
        if !seen.contains(&file) {
            twins.push_str(&format!("#include \"{file}.glsl\"\n"));
            seen.push(file);
        }
    }
    write("shift_twins.glsl", twins);
    let mut engine = engine_contract::glsl_items();
    engine.extend(purpose::glsl_items());
    let source = "engine/src/contract.rs and engine/src/purpose.rs";
    for item in &engine {
        if let Some((name, text)) = twin::push_constant_header(source, item) {
            write(&name, text);
        }
    }
    write(
        "engine.glsl",
        twin::header("CONTRACT_ENGINE_GLSL", source, &engine),
    );
    for kernel in kernels::PassKernel::ALL {
        write(
            &format!("{}_bindings.glsl", kernel.name()),
            bindings(kernel),
        );
    }
    let mut items = restir_contract::glsl_items();
    items.extend(geometry);
    items.extend(sss);
    items.extend(shifts);
    items.extend(engine);
    items
}

/// The storage-buffer declarations of a pass kernel after the scene's, from
/// `src/plan/kernels.rs`.
fn bindings(kernel: kernels::PassKernel) -> String {
    let mut text = format!(
        "// Generated by engine/build.rs from engine/src/plan/kernels.rs: the storage buffers of\n\
         // {} after the scene's, in binding order.\n",
        kernel.name()
    );
    for (i, buffer) in kernel.buffers().iter().enumerate() {
        let binding = kernels::SCENE_BINDINGS as usize + i;
        let access = match buffer.access {
            kernels::Access::Read => "readonly",
            kernels::Access::Write => "writeonly",
        };
        text += &format!(
            "layout(std430, binding = {binding}) {access} buffer Binding{binding} {{ {} {}[]; }};\n",
            buffer.element, buffer.name
        );
    }
    text
}

fn main() {
    println!("cargo::rustc-check-cfg=cfg(reshift_glslc)");
    println!("cargo::rerun-if-changed=glsl");
    for path in CONTRACTS.iter().chain(&INCLUDE_DIRS) {
        println!("cargo::rerun-if-changed={path}");
    }
    let out_dir = PathBuf::from(env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    let generated = out_dir.join("glsl");
    let items = write_contract(&generated);
    let manifest = PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").expect("cargo sets it"));
    let mut includes: Vec<PathBuf> = INCLUDE_DIRS.iter().map(|dir| manifest.join(dir)).collect();
    includes.push(generated.clone());
    // The include path of the engine's GLSL, for crates whose kernels include it (`links =
    // "reshift_engine"`: they read `DEP_RESHIFT_ENGINE_GLSL_INCLUDE`, e.g. methods/build.rs):
    // the twins, the generated headers and the engine's shared building blocks (`glsl/include/`,
    // which the engine's own kernels include relative to themselves).
    let published = includes
        .iter()
        .cloned()
        .chain([manifest.join("glsl/include")]);
    let path = env::join_paths(published).expect("include paths without the separator");
    println!("cargo::metadata=glsl_include={}", path.to_string_lossy());
    let Some(glslc) = Glslc::find() else {
        println!(
            "cargo::warning=glslc was not found; the Vulkan backend is disabled \
             (install it with `apt-get install glslc`; the next build picks it up)"
        );
        return;
    };
    glslc.check_layouts(
        &[
            "contract/restir.glsl",
            "contract/geometry.glsl",
            "contract/sss.glsl",
            "contract/shifts.glsl",
            "contract/engine.glsl",
        ],
        &generated,
        &out_dir,
        &items,
    );
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
        glslc.compile(source, &includes, &output);
        table.push_str(&format!(
            "        {stem:?} => Some(include_bytes!({:?})),\n",
            output.display().to_string()
        ));
    }
    table.push_str("        _ => None,\n    }\n}\n");
    std::fs::write(out_dir.join("spirv_table.rs"), table).expect("OUT_DIR is writable");
    println!("cargo::rustc-cfg=reshift_glslc");
}
