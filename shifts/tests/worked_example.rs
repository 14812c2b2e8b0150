//! `docs/adding-a-shift.md` to the letter: the files and lines its "What you touch" states are
//! exactly those of the workspace's sources that name the worked example `distant-reconnection`
//! (tests excluded: a file's `#[cfg(test)]` module, `tests/`, `benches/`, `examples/`), its
//! registry entry is quoted verbatim, and the registry alone gives the shift its name and
//! declaration. Its conformance is `conformance.rs`'s `distant_reconnection_conforms`; that the
//! CLI lists it is `tests/cli.rs`'s `presets_shifts_and_mis_schemes_are_listed_from_their_registries`.

use std::fs;
use std::path::{Path, PathBuf};

use shifts::numbers::DeclaresNumbers;
use shifts::{DistantReconnection, ShiftKind};

/// What names the worked example in a line of source.
const MARKS: [&str; 5] = [
    "DistantReconnection",
    "distant-reconnection",
    "distant::",
    "distant_",
    "mod distant;",
];

/// The new files, as the guide names them.
const NEW_FILES: [&str; 2] = ["shifts/src/distant.rs", "shifts/glsl/distant.glsl"];

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn guide() -> String {
    fs::read_to_string(root().join("docs/adding-a-shift.md")).expect("docs/adding-a-shift.md")
}

/// Every `.rs` and `.glsl` file under `dir`, outside build output and test-only folders.
fn sources(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in fs::read_dir(dir).expect("readable folder") {
        let path = entry.expect("folder entry").path();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        if path.is_dir() {
            let skipped = ["target", "tests", "benches", "examples", "fuzz", "docs"];
            if !name.starts_with('.') && !skipped.contains(&name.as_str()) {
                sources(&path, out);
            }
        } else if name.ends_with(".rs") || name.ends_with(".glsl") {
            out.push(path);
        }
    }
}

/// The figure written just before `unit` after `after` in the guide's "What you touch".
fn figure(text: &str, after: &str, unit: &str) -> usize {
    let start = text
        .find(after)
        .unwrap_or_else(|| panic!("{after:?} in the guide"))
        + after.len();
    let rest = &text[start..];
    let end = rest
        .find(unit)
        .unwrap_or_else(|| panic!("{unit:?} after {after:?}"));
    rest[..end]
        .trim()
        .parse()
        .unwrap_or_else(|_| panic!("a number before {unit:?}"))
}

#[test]
fn the_guide_states_exactly_what_the_worked_example_touches() {
    let guide = guide();
    let touch = &guide[guide.find("**What you touch**").expect("What you touch")..];
    let root = root();
    let mut files = Vec::new();
    sources(&root, &mut files);
    let mut edited: Vec<(String, String)> = Vec::new();
    for path in &files {
        let rel = path
            .strip_prefix(&root)
            .unwrap()
            .to_string_lossy()
            .replace('\\', "/");
        let text = fs::read_to_string(path).unwrap();
        if NEW_FILES.contains(&rel.as_str()) {
            let stated = figure(touch, &format!("`{rel}`,"), " lines");
            assert_eq!(text.lines().count(), stated, "{rel}");
            continue;
        }
        // A marked line and the doc lines right above it (a registry entry's).
        let code: Vec<&str> = text.split("#[cfg(test)]").next().unwrap().lines().collect();
        for (i, line) in code.iter().enumerate() {
            if MARKS.iter().any(|m| line.contains(m)) {
                let docs = code[..i]
                    .iter()
                    .rev()
                    .take_while(|l| l.trim_start().starts_with("///"));
                for l in docs.chain([line]) {
                    edited.push((rel.clone(), l.trim().to_string()));
                }
            }
        }
    }
    let new_files = figure(touch, "**What you touch**:", " new files");
    assert_eq!(new_files, NEW_FILES.len());
    let lines = figure(touch, ") and", " lines in");
    let in_files = figure(touch, "lines in", " files");
    let mut edited_files: Vec<&str> = edited.iter().map(|(f, _)| f.as_str()).collect();
    edited_files.dedup();
    assert_eq!(lines, edited.len(), "{edited:#?}");
    assert_eq!(in_files, edited_files.len(), "{edited:#?}");
    for file in edited_files {
        assert!(
            touch.contains(&format!("`{file}`")),
            "the guide does not name {file}"
        );
    }
    for (_, line) in &edited {
        assert!(
            guide.contains(line.as_str()) || line.starts_with("//! |"),
            "the guide does not show {line:?}"
        );
    }
}

#[test]
fn the_registry_entry_gives_the_shift_its_name_and_declaration() {
    let guide = guide();
    let registry = fs::read_to_string(root().join("shifts/src/registry.rs")).unwrap();
    let block = guide
        .split("**The registry entry**")
        .nth(1)
        .and_then(|rest| rest.split("```rust\n").nth(1))
        .and_then(|code| code.split("```").next())
        .expect("the registry entry's code block");
    assert!(registry.contains(block), "{block}");
    let kind = ShiftKind::named("distant-reconnection").expect("registered");
    assert_eq!(kind.numbers(), DistantReconnection::NUMBERS);
    assert!(!kind.resolves_deferred_index());
    assert_eq!(
        kind.about(),
        "Reconnection where x2 lies at least 2·max d from both exit points (the worked example)."
    );
}
