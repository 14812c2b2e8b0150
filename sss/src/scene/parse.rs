//! Scene (and trajectory) TOML text → [`SceneFile`] (or any file type), with errors a reader can act on: a syntax error names the
//! line and column and shows the text around it; a type or unknown-field error names the field
//! path and shows the value found there, on one line.

use std::path::Path;

use serde::de::DeserializeOwned;

use crate::InputError;
use crate::error::{MAX_MESSAGE_CHARS, one_line};

/// Characters of a TOML source line shown on either side of a syntax error.
const EXCERPT_RADIUS: usize = 40;

/// TOML text → `T` (a [`super::format::SceneFile`], a trajectory file). Syntax errors name the
/// line; type and unknown-field errors name the field path (via `serde_path_to_error`) and show
/// the value found there.
pub(super) fn parse<T: DeserializeOwned>(text: &str, origin: &Path) -> Result<T, InputError> {
    let table: toml::Table = toml::from_str(text).map_err(|e| {
        let (field, value) = match e.span() {
            Some(span) => {
                let before = text.get(..span.start).unwrap_or(text);
                let line = before.matches('\n').count();
                let column = before.rsplit('\n').next().unwrap_or("").chars().count();
                let source = text.lines().nth(line).unwrap_or("");
                (
                    format!("line {}, column {}", line + 1, column + 1),
                    format!("`{}`", excerpt(source, column)),
                )
            }
            None => ("(document)".to_string(), "…".to_string()),
        };
        InputError::new(
            origin,
            field,
            value,
            format!("malformed TOML: {}", e.message().trim()),
        )
    })?;
    let root = toml::Value::Table(table);
    serde_path_to_error::deserialize::<_, T>(root.clone()).map_err(|e| {
        let path = e.path().to_string();
        let value = value_at(&root, e.path()).map_or_else(|| "(missing)".to_string(), render_value);
        InputError::new(origin, path, value, e.inner().message().trim().to_string())
    })
}

/// The characters of `line` within [`EXCERPT_RADIUS`] of `column`, trimmed, with `…` where cut.
fn excerpt(line: &str, column: usize) -> String {
    let length = line.chars().count();
    let start = column.saturating_sub(EXCERPT_RADIUS);
    let end = column.saturating_add(EXCERPT_RADIUS).min(length);
    let text: String = line.chars().skip(start).take(end - start).collect();
    let text = text.trim();
    let head = if start > 0 { "…" } else { "" };
    let tail = if end < length { "…" } else { "" };
    format!("{head}{text}{tail}")
}

/// The value at a serde path in the TOML tree, as far as the path can be followed.
fn value_at<'a>(
    root: &'a toml::Value,
    path: &serde_path_to_error::Path,
) -> Option<&'a toml::Value> {
    use serde_path_to_error::Segment;
    let mut at = root;
    for segment in path.iter() {
        at = match segment {
            Segment::Map { key } => at.get(key.as_str())?,
            Segment::Seq { index } => at.get(*index)?,
            Segment::Enum { .. } => at,
            Segment::Unknown => return Some(at),
        };
    }
    Some(at)
}

/// A TOML value on one line, at most [`MAX_MESSAGE_CHARS`] characters.
fn render_value(value: &toml::Value) -> String {
    one_line(&render_full(value), MAX_MESSAGE_CHARS)
}

fn render_full(value: &toml::Value) -> String {
    match value {
        toml::Value::Table(t) => {
            let fields: Vec<String> = t
                .iter()
                .map(|(k, v)| format!("{k} = {}", render_full(v)))
                .collect();
            format!("{{ {} }}", fields.join(", "))
        }
        other => other.to_string(),
    }
}
