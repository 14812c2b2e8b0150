//! Reads the method registry of the `methods` crate, the `pub mod <name>;` lines between
//! `// Method registry` and `// End of the method registry` in `methods/src/lib.rs`, and writes
//! `$OUT_DIR/methods.rs` for this crate: `METHODS` in the registry's order, and
//! one module per method folder with a `contract.rs`, that file included, for `contracts()`.
//!
//! Why a crate of its own: `methods/build.rs` renders the folders' contracts, so it must compile
//! them, and a build script can only compile files it names before it runs. This script runs
//! first and names them; the `methods` build script then depends on what it generated.
//!
//! A line of the block that is not a `pub mod` line (comments and blank lines aside) fails the
//! build with its line number.

use std::env;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

include!("src/registered.rs");

fn main() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("../src");
    let lib = src.join("lib.rs");
    println!("cargo::rerun-if-changed={}", lib.display());
    let text = std::fs::read_to_string(&lib).expect("methods/src/lib.rs is readable");
    let names = registered(&text).unwrap_or_else(|e| panic!("methods/src/lib.rs: {e}"));

    let mut out =
        String::from("/// The registered methods of `methods/src/lib.rs`, in its order.\n");
    out.push_str("pub const METHODS: &[Method] = &[\n");
    let mut contracts = Vec::new();
    for name in &names {
        // A folder is watched whole (a contract.rs appears in it); a one-file method by its file.
        let folder = src.join(name);
        let watched = if folder.is_dir() {
            folder.clone()
        } else {
            src.join(format!("{name}.rs"))
        };
        println!("cargo::rerun-if-changed={}", watched.display());
        let contract = folder.join("contract.rs");
        let has_contract = contract.is_file();
        writeln!(
            out,
            "    Method {{ name: {name:?}, contract: {has_contract} }},"
        )
        .unwrap();
        if has_contract {
            contracts.push((name, contract));
        }
    }
    out.push_str("];\n\n");
    for (name, path) in &contracts {
        let path: PathBuf = path.canonicalize().expect("a readable contract.rs");
        writeln!(
            out,
            "#[allow(dead_code, rustdoc::broken_intra_doc_links)]\nmod {name} {{\n    include!({:?});\n}}\n",
            path.display().to_string()
        )
        .unwrap();
    }
    out.push_str(
        "/// Each method folder with a `contract.rs`, and the items of its contract.\n\
         pub fn contracts() -> Vec<(&'static str, Vec<twin::Item>)> {\n    vec![\n",
    );
    for (name, _) in &contracts {
        writeln!(out, "        ({name:?}, {name}::glsl_items()),").unwrap();
    }
    out.push_str("    ]\n}\n");
    let out_dir = PathBuf::from(env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    std::fs::write(out_dir.join("methods.rs"), out).expect("OUT_DIR is writable");
}
