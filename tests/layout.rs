//! The layout rules of docs/architecture.md, checked on the sources: no module of a crate is
//! longer than 700 lines without its tests, no two modules of a crate import each other
//! (directly or round a circle), and `sss` knows nothing of shifts (DESIGN §1).
//!
//! Modules are files (`a.rs`, `a/mod.rs`); an import is a `crate::…` or `super::…` path in
//! code outside `#[cfg(test)]`. A module's own ancestors and descendants do not count (a parent
//! re-exporting its child while the child uses the parent's items is the usual Rust layout).

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The longest a module may be without its tests.
const MAX_LINES: usize = 700;

/// The `src/` of the root crate and of every workspace member (`[workspace] members` of the
/// root Cargo.toml, nested ones such as `methods/registry` included); a member without a `src/`
/// fails the test rather than escaping it.
fn crate_sources() -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let manifest: toml::Table = std::fs::read_to_string(root.join("Cargo.toml"))
        .expect("readable Cargo.toml")
        .parse()
        .expect("valid Cargo.toml");
    let members = manifest["workspace"]["members"]
        .as_array()
        .expect("workspace members");
    let mut out = vec![root.join("src")];
    for member in members {
        let src = root
            .join(member.as_str().expect("a member path"))
            .join("src");
        assert!(src.is_dir(), "{} has no src/", src.display());
        out.push(src);
    }
    out.sort();
    out
}

/// Every `.rs` file under `dir`, except test files (`tests.rs`, a folder `tests/`).
fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("readable folder").flatten() {
        let path = entry.path();
        let name = entry.file_name().to_string_lossy().into_owned();
        if path.is_dir() {
            if name != "tests" {
                rust_files(&path, out);
            }
        } else if name.ends_with(".rs") && name != "tests.rs" {
            out.push(path);
        }
    }
}

/// `file`'s module path inside its crate: `src/a/b.rs` and `src/a/b/mod.rs` → `[a, b]`.
fn module_of(src: &Path, file: &Path) -> Vec<String> {
    let mut parts: Vec<String> = file
        .strip_prefix(src)
        .expect("file under src")
        .with_extension("")
        .iter()
        .map(|p| p.to_string_lossy().into_owned())
        .collect();
    if matches!(
        parts.last().map(String::as_str),
        Some("mod" | "lib" | "main")
    ) {
        parts.pop();
    }
    parts
}

/// `text` without its `#[cfg(test)]` items (a `mod tests { … }` block or one item).
fn without_tests(text: &str) -> String {
    let mut out = String::new();
    let mut rest = text;
    while let Some(at) = rest.find("#[cfg(test)]") {
        out.push_str(&rest[..at]);
        let item = &rest[at..];
        let (brace, semicolon) = (item.find('{'), item.find(';'));
        rest = match (brace, semicolon) {
            (Some(b), Some(s)) if s < b => &item[s + 1..],
            (Some(b), _) => {
                let mut depth = 0usize;
                let mut end = item.len();
                for (i, c) in item[b..].char_indices() {
                    match c {
                        '{' => depth += 1,
                        '}' => {
                            depth -= 1;
                            if depth == 0 {
                                end = b + i + 1;
                                break;
                            }
                        }
                        _ => {}
                    }
                }
                &item[end..]
            }
            (None, Some(s)) => &item[s + 1..],
            (None, None) => "",
        };
    }
    out.push_str(rest);
    out
}

/// `text` without its `//` comments (doc links name modules without importing them).
fn without_comments(text: &str) -> String {
    text.lines()
        .map(|line| match line.find("//") {
            Some(at) if !line[..at].contains('"') => &line[..at],
            _ => line,
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// Expands `a::{b, c::{d, e}}` into `a::b`, `a::c::d`, `a::c::e`.
fn expand(tree: &str) -> Vec<String> {
    let tree = tree.trim();
    let Some(open) = tree.find('{') else {
        return vec![tree.to_owned()];
    };
    let prefix = &tree[..open];
    let inner = &tree[open + 1..tree.rfind('}').unwrap_or(tree.len())];
    let (mut parts, mut depth, mut start) = (Vec::new(), 0, 0);
    for (i, c) in inner.char_indices() {
        match c {
            '{' => depth += 1,
            '}' => depth -= 1,
            ',' if depth == 0 => {
                parts.push(&inner[start..i]);
                start = i + 1;
            }
            _ => {}
        }
    }
    parts.push(&inner[start..]);
    parts
        .into_iter()
        .filter(|p| !p.trim().is_empty())
        .flat_map(|p| expand(p))
        .map(|p| format!("{prefix}{p}"))
        .collect()
}

/// The module paths `code` (of module `module`) names through `crate::` or `super::`.
fn imports(code: &str, module: &[String]) -> Vec<Vec<String>> {
    let mut paths = Vec::new();
    for statement in code.split(';') {
        // Skip the comments and attributes in front of the statement.
        let s: String = statement
            .lines()
            .skip_while(|l| {
                let l = l.trim_start();
                l.is_empty() || l.starts_with("//") || l.starts_with("#[")
            })
            .collect::<Vec<_>>()
            .join("\n");
        let s = s.trim_start();
        let s = s.strip_prefix("pub(crate) ").unwrap_or(s);
        let s = s.strip_prefix("pub(super) ").unwrap_or(s);
        let s = s.strip_prefix("pub ").unwrap_or(s);
        // A `use` declaration holds no string literal: text after `; use` inside a string is not
        // one.
        if let Some(tree) = s.strip_prefix("use ").filter(|t| !t.contains('"')) {
            paths.extend(expand(&tree.replace(char::is_whitespace, "")));
        }
    }
    // Paths written inline, outside `use`.
    for (at, _) in code.match_indices("crate::") {
        let path: String = code[at..]
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_' || *c == ':')
            .collect();
        paths.push(path);
    }
    paths
        .into_iter()
        .filter_map(|p| {
            let segments: Vec<&str> = p.split("::").filter(|s| !s.is_empty()).collect();
            let mut base: Vec<String> = match segments.first() {
                Some(&"crate") => Vec::new(),
                // From `a/b.rs` and `a/b/mod.rs` (module `a::b`) alike, `super` is `a`.
                Some(&"super") => module[..module.len().saturating_sub(1)].to_vec(),
                _ => return None,
            };
            let mut rest = &segments[1..];
            while let Some(&"super") = rest.first() {
                base.pop();
                rest = &rest[1..];
            }
            base.extend(rest.iter().map(|s| (*s).to_owned()));
            Some(base)
        })
        .collect()
}

struct Module {
    file: PathBuf,
    lines: usize,
    imports: Vec<Vec<String>>,
}

fn modules(src: &Path) -> BTreeMap<Vec<String>, Module> {
    let mut files = Vec::new();
    rust_files(src, &mut files);
    files
        .into_iter()
        .map(|file| {
            let text = std::fs::read_to_string(&file).expect("readable source");
            let code = without_comments(&without_tests(&text));
            let module = module_of(src, &file);
            let imports = imports(&code, &module);
            let lines = code.lines().count();
            (
                module,
                Module {
                    file,
                    lines,
                    imports,
                },
            )
        })
        .collect()
}

/// The module a path lands in: its longest prefix that is a module file.
fn target<'a>(
    modules: &'a BTreeMap<Vec<String>, Module>,
    path: &[String],
) -> Option<&'a Vec<String>> {
    (0..=path.len())
        .rev()
        .find_map(|n| modules.get_key_value(&path[..n]).map(|(k, _)| k))
}

/// Import edges between modules of one crate that are not each other's ancestors.
fn edges(
    modules: &BTreeMap<Vec<String>, Module>,
) -> BTreeMap<&Vec<String>, BTreeSet<&Vec<String>>> {
    let mut out: BTreeMap<&Vec<String>, BTreeSet<&Vec<String>>> = BTreeMap::new();
    for (name, module) in modules {
        for path in &module.imports {
            if let Some(to) = target(modules, path) {
                let related = to.starts_with(name) || name.starts_with(to);
                if !related {
                    out.entry(name).or_default().insert(to);
                }
            }
        }
    }
    out
}

/// The circles of `edges`: strongly connected components of more than one module (Tarjan).
fn circles<'a>(
    edges: &BTreeMap<&'a Vec<String>, BTreeSet<&'a Vec<String>>>,
) -> Vec<Vec<&'a Vec<String>>> {
    struct State<'a> {
        index: BTreeMap<&'a Vec<String>, usize>,
        low: BTreeMap<&'a Vec<String>, usize>,
        stack: Vec<&'a Vec<String>>,
        out: Vec<Vec<&'a Vec<String>>>,
    }
    fn visit<'a>(
        v: &'a Vec<String>,
        edges: &BTreeMap<&'a Vec<String>, BTreeSet<&'a Vec<String>>>,
        s: &mut State<'a>,
    ) {
        let i = s.index.len();
        s.index.insert(v, i);
        s.low.insert(v, i);
        s.stack.push(v);
        for &w in edges.get(v).into_iter().flatten() {
            if !s.index.contains_key(w) {
                visit(w, edges, s);
                let low = s.low[v].min(s.low[w]);
                s.low.insert(v, low);
            } else if s.stack.contains(&w) {
                let low = s.low[v].min(s.index[w]);
                s.low.insert(v, low);
            }
        }
        if s.low[v] == s.index[v] {
            let mut component = Vec::new();
            while let Some(w) = s.stack.pop() {
                component.push(w);
                if w == v {
                    break;
                }
            }
            if component.len() > 1 {
                s.out.push(component);
            }
        }
    }
    let mut state = State {
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        out: Vec::new(),
    };
    for &v in edges.keys() {
        if !state.index.contains_key(v) {
            visit(v, edges, &mut state);
        }
    }
    state.out
}

#[test]
fn no_module_is_longer_than_700_lines_without_its_tests() {
    let long: Vec<String> = crate_sources()
        .iter()
        .flat_map(|src| modules(src).into_values())
        .filter(|m| m.lines > MAX_LINES)
        .map(|m| format!("{} ({} lines)", m.file.display(), m.lines))
        .collect();
    assert!(long.is_empty(), "over {MAX_LINES} lines: {long:#?}");
}

#[test]
fn no_two_modules_of_a_crate_import_each_other() {
    let mut found = Vec::new();
    for src in crate_sources() {
        let modules = modules(&src);
        for circle in circles(&edges(&modules)) {
            let names: Vec<String> = circle.iter().map(|m| m.join("::")).collect();
            let mut ties = Vec::new();
            for from in &circle {
                for path in &modules[*from].imports {
                    if target(&modules, path).is_some_and(|to| circle.contains(&to)) {
                        ties.push(format!("{} → {}", from.join("::"), path.join("::")));
                    }
                }
            }
            found.push(format!(
                "{}: {} ({})",
                src.display(),
                names.join(" ↔ "),
                ties.join("; ")
            ));
        }
    }
    assert!(found.is_empty(), "import circles: {found:#?}");
}

/// The negative control of the circle check: two modules that import each other are found.
#[test]
fn the_circle_check_finds_a_circle() {
    let module = |name: &str, imports: &[&str]| {
        (
            vec![name.to_owned()],
            Module {
                file: PathBuf::from(name),
                lines: 1,
                imports: imports.iter().map(|i| vec![(*i).to_owned()]).collect(),
            },
        )
    };
    let modules: BTreeMap<_, _> = [
        module("images", &["plots"]),
        module("plots", &["figure"]),
        module("figure", &["images"]),
        module("metrics", &["images"]),
    ]
    .into_iter()
    .collect();
    let found = circles(&edges(&modules));
    assert_eq!(found.len(), 1);
    assert_eq!(found[0].len(), 3);
    let code = "use crate::{a::X, b::{c::Y, Z}};\nfn f() { super::d::g(); crate::e::h(); }";
    let here = vec!["m".to_owned(), "n".to_owned()];
    let paths = imports(code, &here);
    for expected in [&["a", "X"][..], &["b", "c", "Y"], &["b", "Z"], &["e", "h"]] {
        assert!(paths.contains(&expected.iter().map(|s| s.to_string()).collect()));
    }
    assert!(without_tests("a\n#[cfg(test)]\nmod tests {\n use crate::x; { }\n}\nb").contains('b'));
    assert!(!without_tests("#[cfg(test)]\nmod tests {\n use crate::x;\n}\n").contains("crate::x"));
}

#[test]
fn sss_knows_nothing_of_shifts() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let manifest = std::fs::read_to_string(root.join("sss/Cargo.toml")).expect("sss manifest");
    assert!(!manifest.contains("shifts"), "sss depends on shifts");
    let mut files = Vec::new();
    rust_files(&root.join("sss/src"), &mut files);
    let offending: Vec<String> = files
        .iter()
        .filter(|f| {
            let text = std::fs::read_to_string(f).expect("readable source");
            let code = without_comments(&without_tests(&text));
            code.contains("restir::Shift") || code.contains("Shift for ")
        })
        .map(|f| f.display().to_string())
        .collect();
    assert!(
        offending.is_empty(),
        "sss implements restir::Shift in {offending:#?}"
    );
}
