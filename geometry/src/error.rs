//! Errors for user input (scene files, meshes, checkpoints, command-line values).
//!
//! Every error names the file, the field and the offending value, so a researcher can fix the input
//! without reading code. Loaders return these; they never panic on user input. Messages are one
//! line of at most [`MAX_MESSAGE_CHARS`] characters: [`one_line`] collapses whitespace and elides
//! the middle of long text, and [`InputError`]'s `Display` shortens its longest part first.

use std::fmt;
use std::path::{Path, PathBuf};

/// The longest error message, in characters (`char`s), that [`InputError`] prints.
pub const MAX_MESSAGE_CHARS: usize = 200;

/// The fewest characters a part of a message is shortened to.
const MIN_PART_CHARS: usize = 16;

/// Bad user input: which file, which field, which value, and why it was rejected.
#[derive(Debug, Clone, PartialEq)]
pub struct InputError {
    pub file: PathBuf,
    /// Dotted path of the field inside the file (`objects[2].material.mfp`), or a mesh element.
    pub field: String,
    /// The offending value as written (or a short description when there is none).
    pub value: String,
    pub reason: String,
}

impl InputError {
    pub fn new(
        file: impl AsRef<Path>,
        field: impl Into<String>,
        value: impl Into<String>,
        reason: impl Into<String>,
    ) -> Self {
        Self {
            file: file.as_ref().to_path_buf(),
            field: field.into(),
            value: value.into(),
            reason: reason.into(),
        }
    }
}

impl fmt::Display for InputError {
    /// `<file>: field `<field>` = <value>: <reason>`, one line of at most
    /// [`MAX_MESSAGE_CHARS`] characters: while too long, the longest part is elided in its middle.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut parts = [
            self.file.display().to_string(),
            self.field.clone(),
            self.value.clone(),
            self.reason.clone(),
        ]
        .map(|p| one_line(&p, usize::MAX));
        let template = ": field `` = : ".chars().count();
        loop {
            let total = template + parts.iter().map(|p| p.chars().count()).sum::<usize>();
            let Some(longest) = (0..parts.len()).max_by_key(|&i| parts[i].chars().count()) else {
                break;
            };
            let length = parts[longest].chars().count();
            if total <= MAX_MESSAGE_CHARS || length <= MIN_PART_CHARS {
                break;
            }
            let keep = length
                .saturating_sub(total - MAX_MESSAGE_CHARS)
                .max(MIN_PART_CHARS);
            parts[longest] = one_line(&parts[longest], keep);
        }
        let [file, field, value, reason] = parts;
        write!(f, "{file}: field `{field}` = {value}: {reason}")
    }
}

impl std::error::Error for InputError {}

/// `text` on one line (every run of whitespace, newlines included, becomes one space; ends
/// trimmed) and at most `max` characters: a longer text keeps its start and end around ` … `.
pub fn one_line(text: &str, max: usize) -> String {
    let mut line = String::with_capacity(text.len().min(max.saturating_mul(4)));
    for word in text.split_whitespace() {
        if !line.is_empty() {
            line.push(' ');
        }
        line.push_str(word);
    }
    let length = line.chars().count();
    if length <= max {
        return line;
    }
    const MARK: &str = " … ";
    let keep = max.saturating_sub(MARK.chars().count());
    let head = keep.div_ceil(2);
    let tail = keep - head;
    let start: String = line.chars().take(head).collect();
    let end: String = line.chars().skip(length - tail).collect();
    format!("{start}{MARK}{end}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_line_collapses_whitespace_and_elides_the_middle() {
        assert_eq!(one_line("  a\n\tb  c \r\n", 80), "a b c");
        let long = format!("start {} end", "x".repeat(1000));
        let short = one_line(&long, 40);
        assert_eq!(short.chars().count(), 40);
        assert!(
            short.starts_with("start ") && short.ends_with(" end"),
            "{short}"
        );
        assert!(short.contains(" … "), "{short}");
        // Multi-byte characters are counted as characters, never split.
        let greek = "αβγδε".repeat(100);
        assert_eq!(one_line(&greek, 21).chars().count(), 21);
    }

    #[test]
    fn display_is_one_line_of_at_most_200_characters() {
        let short = InputError::new("a.toml", "camera.vfov", "200", "must lie in (0, 180)");
        assert_eq!(
            short.to_string(),
            "a.toml: field `camera.vfov` = 200: must lie in (0, 180)"
        );
        let long = InputError::new(
            format!("/very/{}/scene.toml", "deep/".repeat(30)),
            "line 1, column 100001",
            format!("`{}`", "[".repeat(200_000)),
            "malformed TOML:\ncannot recurse further; max recursion depth met",
        );
        let text = long.to_string();
        assert!(text.chars().count() <= MAX_MESSAGE_CHARS, "{text}");
        assert!(!text.contains('\n'), "{text}");
        // Every part is still there, shortened in its middle.
        for part in [
            "/very/",
            "scene.toml",
            "column 100001",
            "`[[",
            "recursion depth met",
        ] {
            assert!(text.contains(part), "{part:?} missing: {text}");
        }
    }
}
