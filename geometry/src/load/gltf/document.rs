//! The container (JSON or GLB, glTF 2.0 §4.4) and the document: parsed by the `gltf` crate's
//! model, checked for what the loader does not read, then validated by the model.

use std::path::Path;

use ::gltf::json;
use json::mesh::Semantic;
use json::validation::Validate;

use super::attribute;
use crate::InputError;

/// The JSON of a glTF file and, for a GLB, its BIN chunk.
pub(super) struct Container<'a> {
    pub(super) json: &'a [u8],
    pub(super) bin: Option<&'a [u8]>,
}

/// GLB magic and chunk types (glTF 2.0 §4.4).
const GLB_MAGIC: &[u8; 4] = b"glTF";
const CHUNK_JSON: u32 = 0x4E4F_534A;
const CHUNK_BIN: u32 = 0x004E_4942;
const GLB_HEADER_BYTES: usize = 12;
const CHUNK_HEADER_BYTES: usize = 8;

/// Splits a GLB into its chunks, or takes the bytes as JSON. A UTF-8 byte order mark before the
/// JSON is skipped (glTF 2.0 §2.7 asks writers to leave it out; some do not).
pub(super) fn container<'a>(bytes: &'a [u8], path: &Path) -> Result<Container<'a>, InputError> {
    let container = split(bytes, path)?;
    Ok(Container {
        json: container
            .json
            .strip_prefix(b"\xEF\xBB\xBF")
            .unwrap_or(container.json),
        ..container
    })
}

/// The JSON and BIN of a GLB, or the bytes as JSON.
fn split<'a>(bytes: &'a [u8], path: &Path) -> Result<Container<'a>, InputError> {
    let is_glb = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("glb"));
    if bytes.starts_with(GLB_MAGIC) {
        glb(bytes, path)
    } else if is_glb {
        let magic = String::from_utf8_lossy(&bytes[..bytes.len().min(4)]).into_owned();
        Err(InputError::new(
            path,
            "GLB header.magic",
            format!("{magic:?}"),
            "a .glb file starts with the magic `glTF` (glTF 2.0 §4.4.2)",
        ))
    } else {
        Ok(Container {
            json: bytes,
            bin: None,
        })
    }
}

/// The little-endian u32 at `at`, if the bytes reach that far.
fn word(bytes: &[u8], at: usize) -> Option<u32> {
    let w = bytes.get(at..at.checked_add(4)?)?;
    Some(u32::from_le_bytes([w[0], w[1], w[2], w[3]]))
}

/// A chunk type as its four characters.
fn chunk_name(kind: u32) -> String {
    format!("{:?}", String::from_utf8_lossy(&kind.to_le_bytes()))
}

/// The chunks of a GLB (glTF 2.0 §4.4): a 12-byte header (magic, version 2, total length), a
/// JSON chunk, then optionally the BIN chunk; chunks of other types are ignored (§4.4.3.1).
fn glb<'a>(bytes: &'a [u8], path: &Path) -> Result<Container<'a>, InputError> {
    let err = |field: String, value: String, reason: String| {
        InputError::new(path, format!("GLB {field}"), value, reason)
    };
    let (Some(version), Some(length)) = (word(bytes, 4), word(bytes, 8)) else {
        return Err(err(
            "header".into(),
            format!("{} bytes", bytes.len()),
            format!("shorter than the {GLB_HEADER_BYTES}-byte GLB header"),
        ));
    };
    if version != 2 {
        return Err(err(
            "header.version".into(),
            version.to_string(),
            "only GLB version 2 (glTF 2.0) is read".into(),
        ));
    }
    if length as usize != bytes.len() {
        return Err(err(
            "header.length".into(),
            length.to_string(),
            format!("the file has {} bytes", bytes.len()),
        ));
    }
    let (mut json, mut bin) = (None, None);
    let mut at = GLB_HEADER_BYTES;
    let mut chunk = 0;
    while at < bytes.len() {
        let (Some(size), Some(kind)) = (word(bytes, at), word(bytes, at + 4)) else {
            return Err(err(
                format!("chunk[{chunk}]"),
                format!("{} bytes", bytes.len() - at),
                format!("a chunk header has {CHUNK_HEADER_BYTES} bytes"),
            ));
        };
        let start = at + CHUNK_HEADER_BYTES;
        let data = bytes.get(start..start.saturating_add(size as usize));
        let Some(data) = data.filter(|d| d.len() == size as usize) else {
            return Err(err(
                format!("chunk[{chunk}].length"),
                size.to_string(),
                format!("only {} bytes follow the chunk header", bytes.len() - start),
            ));
        };
        match (chunk, kind) {
            (0, CHUNK_JSON) => json = Some(data),
            (1, CHUNK_BIN) => bin = Some(data),
            (0, _) | (_, CHUNK_JSON | CHUNK_BIN) => {
                return Err(err(
                    format!("chunk[{chunk}].type"),
                    chunk_name(kind),
                    "the first chunk is JSON, the optional second BIN, and there is one of each"
                        .into(),
                ));
            }
            _ => {}
        }
        at = start + data.len();
        chunk += 1;
    }
    let json = json.ok_or_else(|| {
        err(
            "chunk[0]".into(),
            "(absent)".into(),
            "a GLB file needs a JSON chunk".into(),
        )
    })?;
    Ok(Container { json, bin })
}

/// The document model of the JSON; syntax errors name the line and column.
pub(super) fn parse(text: &[u8], path: &Path) -> Result<json::Root, InputError> {
    json::deserialize::from_slice(text).map_err(|e| {
        let message = e.to_string();
        let reason = message
            .rsplit_once(" at line ")
            .map_or(message.as_str(), |(r, _)| r);
        InputError::new(
            path,
            format!("line {}, column {}", e.line(), e.column()),
            excerpt(text, e.line(), e.column()),
            format!("malformed glTF JSON: {reason}"),
        )
    })
}

/// The text around `column` (1-based) of `line`.
fn excerpt(text: &[u8], line: usize, column: usize) -> String {
    let row = text
        .split(|&b| b == b'\n')
        .nth(line.saturating_sub(1))
        .unwrap_or_default();
    let start = column.saturating_sub(16).min(row.len());
    let end = column.saturating_add(16).min(row.len());
    let shown = String::from_utf8_lossy(&row[start..end]);
    if shown.trim().is_empty() {
        "(end of line)".into()
    } else {
        format!("`{}`", shown.trim())
    }
}

/// The extensions this loader understands, so a file may require them.
const SUPPORTED_EXTENSIONS: [&str; 2] = ["KHR_materials_emissive_strength", "KHR_materials_ior"];

/// Checks what the document model leaves to the reader, then runs its validation.
pub(super) fn check(root: &json::Root, text: &[u8], path: &Path) -> Result<(), InputError> {
    let version = &root.asset.version;
    if version.split('.').next() != Some("2") {
        return Err(InputError::new(
            path,
            "asset.version",
            format!("{version:?}"),
            "only glTF 2.x is read",
        ));
    }
    for (i, name) in root.extensions_required.iter().enumerate() {
        if !SUPPORTED_EXTENSIONS.contains(&name.as_str()) {
            return Err(InputError::new(
                path,
                format!("extensionsRequired[{i}]"),
                name.clone(),
                "the file needs an extension this loader does not read (it reads KHR_materials_ior \
                 and KHR_materials_emissive_strength)",
            ));
        }
    }
    check_position_indices(root, path)?;
    validate(root, text, path)
}

/// Every `POSITION` names an existing accessor: the document model's validation indexes the
/// accessors with it unchecked.
fn check_position_indices(root: &json::Root, path: &Path) -> Result<(), InputError> {
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            if let Some(a) = attribute(primitive, Semantic::Positions)
                && a >= root.accessors.len()
            {
                return Err(InputError::new(
                    path,
                    format!("meshes[{m}].primitives[{p}].attributes[\"POSITION\"]"),
                    a.to_string(),
                    format!("no such accessor (the file has {})", root.accessors.len()),
                ));
            }
        }
    }
    Ok(())
}

/// The document model's own validation (glTF 2.0 schema: indices in range, enumerations,
/// required properties); the first problem becomes the error, with its JSON path and value.
fn validate(root: &json::Root, text: &[u8], path: &Path) -> Result<(), InputError> {
    let mut problems = Vec::new();
    root.validate(root, json::Path::new, &mut |at, problem| {
        problems.push((at(), problem))
    });
    let Some((at, problem)) = problems.first() else {
        return Ok(());
    };
    let (field, value) = match at.as_str().split_once(" = ") {
        Some((field, value)) => (field.to_string(), value.to_string()),
        None => (at.to_string(), value_at(text, at.as_str())),
    };
    let reason = match problem {
        json::validation::Error::IndexOutOfBounds => "refers to an item that does not exist",
        json::validation::Error::Invalid => "not a valid value here (glTF 2.0 schema)",
        json::validation::Error::Missing => "required by glTF 2.0, but missing",
        json::validation::Error::Oversize => "too large",
        json::validation::Error::Unsupported => "not supported",
    };
    let more = match problems.len() {
        1 => String::new(),
        n => format!(" ({} more problems)", n - 1),
    };
    Err(InputError::new(
        path,
        field,
        value,
        format!("{reason}{more}"),
    ))
}

/// The JSON value at a validation path (`meshes[0].primitives[1].attributes["NORMAL"]`), or
/// `(absent)`.
fn value_at(text: &[u8], at: &str) -> String {
    let found = || -> Option<String> {
        let document: json::Value = json::deserialize::from_slice(text).ok()?;
        let mut value = &document;
        let mut rest = at;
        while !rest.is_empty() {
            if let Some(r) = rest.strip_prefix("[\"") {
                let (key, r) = r.split_once("\"]")?;
                value = value.get(key)?;
                rest = r;
            } else if let Some(r) = rest.strip_prefix('[') {
                let (index, r) = r.split_once(']')?;
                value = value.get(index.parse::<usize>().ok()?)?;
                rest = r;
            } else {
                let r = rest.strip_prefix('.').unwrap_or(rest);
                let end = r.find(['.', '[']).unwrap_or(r.len());
                if end > 0 {
                    value = value.get(&r[..end])?;
                }
                rest = &r[end..];
            }
        }
        Some(value.to_string())
    };
    found().unwrap_or_else(|| "(absent)".into())
}
