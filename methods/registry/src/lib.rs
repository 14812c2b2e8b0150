//! The `methods` crate's registry as its build script reads it (`methods/build.rs`): the
//! methods that `methods/src/lib.rs` registers by their `pub mod` lines ([`METHODS`]), and the
//! contracts of their folders, compiled ([`contracts`]). This crate's own build script reads
//! `lib.rs` and includes each `src/<name>/contract.rs` there is; a build script can compile only
//! the files it names before it runs, so the `methods` build script takes them from here.

/// A registered method: its module name and whether its folder has a `contract.rs`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Method {
    pub name: &'static str,
    pub contract: bool,
}

include!(concat!(env!("OUT_DIR"), "/methods.rs"));

mod registered {
    include!("registered.rs");
}

pub use registered::{END, START, registered};

#[cfg(test)]
mod tests {
    use super::*;

    /// The generated list is the registry of `methods/src/lib.rs`; a folder has a contract
    /// exactly where its `contract.rs` exists.
    #[test]
    fn methods_are_the_registry_of_lib_rs() {
        let src = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../src");
        let lib = std::fs::read_to_string(src.join("lib.rs")).unwrap();
        let names: Vec<&str> = METHODS.iter().map(|m| m.name).collect();
        assert_eq!(registered(&lib).unwrap(), names);
        assert!(names.contains(&"pt") && !names.contains(&"estimator"));
        for method in METHODS {
            let has = src.join(method.name).join("contract.rs").is_file();
            assert_eq!(method.contract, has, "{}", method.name);
        }
        let with_contracts: Vec<&str> = contracts().iter().map(|(name, _)| *name).collect();
        let expected: Vec<&str> = METHODS
            .iter()
            .filter(|m| m.contract)
            .map(|m| m.name)
            .collect();
        assert_eq!(with_contracts, expected);
        assert!(contracts().iter().all(|(_, items)| !items.is_empty()));
    }

    /// Comments and blank lines in the block are skipped; anything else, or a block that is not
    /// opened or closed, is an error that names it.
    #[test]
    fn the_block_holds_only_pub_mod_lines() {
        let block =
            |body: &str| format!("mod estimator;\n{START}: ...\n{body}\n{END}.\npub mod after;\n");
        assert_eq!(
            registered(&block("pub mod a;\n\n// note\npub mod b_2;")).unwrap(),
            ["a", "b_2"]
        );
        for (bad, named) in [
            ("mod a;", "line 3: `mod a;`"),
            ("pub mod a", "line 3: `pub mod a`"),
            ("pub mod a::b;", "line 3"),
            ("pub use a::ENTRY;", "line 3"),
        ] {
            let e = registered(&block(bad)).unwrap_err();
            assert!(e.contains(named), "{bad}: {e}");
        }
        assert!(registered("pub mod a;\n").unwrap_err().contains("opens"));
        assert!(
            registered(&format!("{START}\npub mod a;\n"))
                .unwrap_err()
                .contains("closes")
        );
    }
}
