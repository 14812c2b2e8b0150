//! docs/adding-a-method.md quotes the code of its worked examples from the files that compile
//! it: each block after `<!-- quoted: <path> -->` must occur verbatim in `<path>` (relative to
//! the workspace), so the page cannot drift from the code it explains.

use std::path::Path;

const DOC: &str = include_str!("../../docs/adding-a-method.md");
const MARK: &str = "<!-- quoted: ";

/// The quoted blocks of `doc`: (path, code).
fn quotes(doc: &str) -> Vec<(&str, &str)> {
    doc.split(MARK)
        .skip(1)
        .map(|rest| {
            let (path, rest) = rest.split_once(" -->").expect("a closed quote marker");
            let rest = rest
                .trim_start()
                .strip_prefix("```rust\n")
                .expect("a rust block");
            let (code, _) = rest.split_once("```").expect("a closed block");
            (path, code)
        })
        .collect()
}

/// The quotes of `doc` that do not occur in their files, by path.
fn drifted<'a>(doc: &'a str) -> Vec<&'a str> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    quotes(doc)
        .into_iter()
        .filter(|(path, code)| {
            let text =
                std::fs::read_to_string(root.join(path)).unwrap_or_else(|e| panic!("{path}: {e}"));
            !text.contains(code)
        })
        .map(|(path, _)| path)
        .collect()
}

#[test]
fn every_quote_is_the_code_it_quotes() {
    let quotes = quotes(DOC);
    let paths: Vec<&str> = quotes.iter().map(|(p, _)| *p).collect();
    assert_eq!(
        paths,
        [
            "methods/src/pt_one_hit.rs",
            "methods/src/image_space/vulkan.rs",
            "methods/src/lib.rs",
        ]
    );
    assert!(quotes.iter().all(|(_, code)| code.lines().count() >= 1));
    assert_eq!(drifted(DOC), Vec::<&str>::new());
}

/// Negative control: a quote edited in the page (one identifier) is caught.
#[test]
fn an_edited_quote_is_caught() {
    let edited = DOC.replacen("seed, IMAGE_SPACE, |context", "seed, PT, |context", 1);
    assert_ne!(edited, DOC);
    assert_eq!(drifted(&edited), ["methods/src/image_space/vulkan.rs"]);
}
