//! Citations resolve inside the repository: every `DESIGN §N` (optionally `§N "Paragraph"`) in
//! the sources and docs names a section of docs/design.md (and a bold paragraph of it), and
//! every paper citation `[NNN …]` names a paper of docs/references.md.

use std::path::{Path, PathBuf};

/// Source and documentation files of the workspace (Rust, GLSL, Markdown, TOML), without
/// build outputs.
fn files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("readable folder").flatten() {
        let path = entry.path();
        let name = entry.file_name();
        let name = name.to_string_lossy();
        if path.is_dir() {
            if !(name.starts_with('.') || name == "target" || name == "out") {
                files(&path, out);
            }
        } else if ["rs", "glsl", "md", "toml"]
            .iter()
            .any(|ext| path.extension().is_some_and(|e| e == *ext))
        {
            out.push(path);
        }
    }
}

/// `(section, paragraph)` of every `DESIGN §N` and `DESIGN §N "Paragraph"` in `text`, and of
/// the further `§M` of a list (`DESIGN §4, §9`).
fn design_citations(text: &str) -> Vec<(u32, Option<String>)> {
    let mut out = Vec::new();
    for (at, _) in text.match_indices("DESIGN §") {
        let mut rest = &text[at + "DESIGN ".len()..];
        while let Some(after) = rest.strip_prefix('§') {
            let digits: String = after.chars().take_while(char::is_ascii_digit).collect();
            let Ok(section) = digits.parse() else { break };
            let after = &after[digits.len()..];
            let paragraph = after
                .strip_prefix(" \"")
                .and_then(|p| p.split_once('"'))
                .map(|(name, _)| name.to_string());
            out.push((section, paragraph));
            match after.strip_prefix(", ") {
                Some(next) if next.starts_with('§') => rest = next,
                _ => break,
            }
        }
    }
    out
}

/// Whether docs/design.md (`design`) has section `section` and, if named, a paragraph starting
/// with `**<paragraph>` in it.
fn resolves(design: &str, section: u32, paragraph: Option<&str>) -> bool {
    let heading = format!("\n## {section}. ");
    let Some(start) = design.find(&heading) else {
        return false;
    };
    let body = &design[start + heading.len()..];
    let body = &body[..body.find("\n## ").unwrap_or(body.len())];
    paragraph.is_none_or(|p| body.contains(&format!("**{p}")))
}

/// Paper ids of every `[NNN` citation in `text`.
fn paper_citations(text: &str) -> Vec<String> {
    text.match_indices('[')
        .filter_map(|(at, _)| {
            let id = text.get(at + 1..at + 4)?;
            let next = text[at + 4..].chars().next()?;
            (id.starts_with("00") && id.chars().all(|c| c.is_ascii_digit()) && " ,]".contains(next))
                .then(|| id.to_string())
        })
        .collect()
}

#[test]
fn every_citation_resolves_inside_the_repository() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let design = std::fs::read_to_string(root.join("docs/design.md")).expect("docs/design.md");
    let references =
        std::fs::read_to_string(root.join("docs/references.md")).expect("docs/references.md");
    let mut paths = Vec::new();
    files(root, &mut paths);
    let (mut checked, mut broken) = (0, Vec::new());
    // This file's negative controls cite sections and papers that do not exist.
    let this_file = root.join(file!());
    for path in paths.iter().filter(|p| **p != this_file) {
        let Ok(text) = std::fs::read_to_string(path) else {
            continue;
        };
        let shown = path.strip_prefix(root).unwrap_or(path).display();
        for (section, paragraph) in design_citations(&text) {
            checked += 1;
            if !resolves(&design, section, paragraph.as_deref()) {
                broken.push(format!("{shown}: DESIGN §{section} {paragraph:?}"));
            }
        }
        for id in paper_citations(&text) {
            checked += 1;
            if !references.contains(&format!("| {id} |")) {
                broken.push(format!("{shown}: [{id} …]"));
            }
        }
    }
    println!("{checked} citations in {} files", paths.len());
    assert!(
        checked > 100,
        "only {checked} citations found: is the scan broken?"
    );
    assert!(
        broken.is_empty(),
        "citations that do not resolve:\n{}",
        broken.join("\n")
    );
}

/// The checks can fail: a section, a paragraph and a paper that do not exist are rejected, and
/// lists and named paragraphs are parsed.
#[test]
fn the_citation_checks_reject_what_does_not_exist() {
    let design =
        "# d\n\n## 3. Core\n\n**Statistics.** text\n\n## 9. Formulas\n\n**Visibility**: x\n";
    assert_eq!(
        design_citations(r#"(DESIGN §4, §9 "Visibility") and DESIGN §12"#),
        [(4, None), (9, Some("Visibility".to_string())), (12, None)]
    );
    assert!(resolves(design, 9, Some("Visibility")));
    assert!(resolves(design, 3, Some("Statistics")));
    assert!(
        !resolves(design, 3, Some("Visibility")),
        "paragraph of another section"
    );
    assert!(!resolves(design, 4, None));
    assert_eq!(
        paper_citations("[001 Eq. 11], [000, last slides], [003] v[0] [0012]"),
        ["001", "000", "003"]
    );
}

/// docs/cluster.md quotes the job array script that CI runs (scripts/slurm-test) verbatim.
#[test]
fn the_cluster_doc_quotes_the_array_script_verbatim() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let script = std::fs::read_to_string(root.join("scripts/cluster/bias-array.sh")).unwrap();
    let doc = std::fs::read_to_string(root.join("docs/cluster.md")).unwrap();
    assert!(
        doc.contains(&format!("```bash\n{script}```")),
        "docs/cluster.md must quote scripts/cluster/bias-array.sh verbatim in a ```bash block"
    );
    let runner = std::fs::read_to_string(root.join("scripts/slurm-test")).unwrap();
    assert!(runner.contains("scripts/cluster/bias-array.sh"));
}
