//! The GLSL hand-numbers no kind: every integer constant that the twins (`restir/glsl`,
//! `geometry/glsl`, `sss/glsl`, `shifts/glsl`) and the kernels (`engine/glsl`) spell as a number —
//! `const uint|int|uint64_t NAME = <numbers and operators>;` or `#define NAME <numbers>` — must be
//! in [`ALLOWED`], which says why it is no constant of the Rust contract. Every other kind or
//! shared constant comes from a `twin::contract!` file through the headers `engine/build.rs`
//! renders (`contract/*.glsl`), so Rust and GLSL cannot drift (docs/gpu-backend.md, "The
//! contract between Rust and GLSL"). Float constants (`const float`) are not scanned: the twins
//! keep `f32` spellings of `std::f32::consts` such as `BSSRDF_TAU`.

use std::path::{Path, PathBuf};

/// Integer constants the GLSL may spell as numbers, with the reason each is not in a contract.
const ALLOWED: [(&str, &str); 5] = [
    (
        "BVH_STACK_SIZE",
        "geometry/glsl/bvh.glsl: obvhs's TRAVERSAL_STACK_SIZE (a dependency's constant, not ours), \
         the length of the traversal stack array",
    ),
    (
        "RANDOM_WALK_MAX_ENTRY_SKIPS",
        "sss/glsl/random_walk.glsl: a bound of the GPU loop only; the CPU loop has none",
    ),
    (
        "PCG32_MULTIPLIER",
        "restir/glsl/rng.glsl: rand_pcg's Lcg64Xsh32 multiplier (a dependency's constant), \
         the generator's own arithmetic",
    ),
    (
        "SCENE_BINDING",
        "engine/glsl kernels: the scene's bindings start at 0 in every kernel (the plan's \
         bindings follow them, contract/<kernel>_bindings.glsl)",
    ),
    (
        "BVH_BINDING",
        "engine/glsl/parity_bvh.glsl: where the BVH buffers sit in that test kernel's own layout",
    ),
];

/// The GLSL folders scanned, relative to the workspace root.
const FOLDERS: [&str; 6] = [
    "restir/glsl",
    "geometry/glsl",
    "sss/glsl",
    "shifts/glsl",
    "engine/glsl",
    "engine/glsl/include",
];

/// `Some(name)` when `line` declares an integer constant by numbers only: `const <int type> NAME
/// = <expr>;` or `#define NAME <expr>` whose expression has no identifier (only literals such as
/// `0xFFu`, `1`, `65536u` and operators). A value derived from another name is not a number.
fn hand_numbered(line: &str) -> Option<&str> {
    let code = line.split("//").next().unwrap_or("").trim();
    let (name, expr) = if let Some(rest) = code.strip_prefix("#define ") {
        let (name, expr) = rest.trim().split_once(char::is_whitespace)?;
        (name, expr)
    } else {
        let rest = code.strip_prefix("const ")?;
        let (ty, rest) = rest.trim().split_once(char::is_whitespace)?;
        if !["uint", "int", "uint64_t", "int64_t"].contains(&ty) {
            return None;
        }
        let (name, expr) = rest.split_once('=')?;
        (name.trim(), expr.trim().trim_end_matches(';'))
    };
    if name.contains('(') || expr.trim().is_empty() {
        return None;
    }
    let mut words = expr
        .split(|c: char| !(c.is_ascii_alphanumeric() || c == '_' || c == '.'))
        .filter(|w| !w.is_empty());
    words
        .all(|w| w.starts_with(|c: char| c.is_ascii_digit()))
        .then_some(name)
}

fn glsl_files() -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut files = Vec::new();
    for folder in FOLDERS {
        for entry in std::fs::read_dir(root.join(folder)).expect("a GLSL folder") {
            let path = entry.expect("a readable folder").path();
            if path.extension().is_some_and(|e| e == "glsl") {
                files.push(path);
            }
        }
    }
    files.sort();
    files
}

#[test]
fn no_hand_numbered_kind_outside_the_allow_list() {
    let mut found = Vec::new();
    let mut used = Vec::new();
    for path in glsl_files() {
        let text = std::fs::read_to_string(&path).expect("a readable GLSL file");
        for (i, line) in text.lines().enumerate() {
            let Some(name) = hand_numbered(line) else {
                continue;
            };
            if ALLOWED.iter().any(|(allowed, _)| *allowed == name) {
                used.push(name.to_string());
            } else {
                found.push(format!("{}:{}: {}", path.display(), i + 1, line.trim()));
            }
        }
    }
    assert!(
        found.is_empty(),
        "hand-numbered constants in the GLSL; declare them in a twin::contract! file (or, if \
         purely GLSL-internal, add them to ALLOWED with the reason):\n{}",
        found.join("\n")
    );
    for (name, why) in ALLOWED {
        assert!(
            used.iter().any(|u| u == name),
            "ALLOWED names {name} ({why}), which no GLSL file declares any more: remove it"
        );
    }
}

/// The scanner's negative controls: a kind spelled as a number is found, in every form the
/// twins used before the contract; a constant derived from a contract name is not.
#[test]
fn the_scanner_finds_numbered_kinds() {
    for (line, name) in [
        ("const uint BSSRDF_AXIS_NORMAL = 0u;", "BSSRDF_AXIS_NORMAL"),
        (
            "const uint BSSRDF_INDEX_UNKNOWN = 0xFFFFFFFFu; // None",
            "BSSRDF_INDEX_UNKNOWN",
        ),
        ("  const int BVH_ALL_HITS = 2;", "BVH_ALL_HITS"),
        ("#define BVH_MAX_HITS 16", "BVH_MAX_HITS"),
        (
            "const uint DELAYED_CHECKS_ALL = 1u | 2u;",
            "DELAYED_CHECKS_ALL",
        ),
    ] {
        assert_eq!(hand_numbered(line), Some(name), "{line}");
    }
    for line in [
        "#define BVH_MAX_HITS KEPT_HITS",
        "#define BVH_MAX_HITS BVH_DEFAULT_MAX_HITS",
        "#define GEOMETRY_BVH_GLSL",
        "#define MIS_WEIGHT(KIND, stem) \\",
        "const float BSSRDF_TAU = 6.28318548202514648;",
        "const uint MASK = BVH_NO_HIT >> 1u;",
        "// const uint OLD = 3u;",
    ] {
        assert_eq!(hand_numbered(line), None, "{line}");
    }
}
