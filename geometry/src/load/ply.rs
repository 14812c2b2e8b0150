//! PLY, ascii and binary (little- and big-endian): the `vertex` element (`x`, `y`, `z`, and
//! `nx`, `ny`, `nz` when all three are present), `face` (a `vertex_indices` or `vertex_index`
//! list; polygons fan-triangulated) and `tristrips` (a `vertex_indices` list; `-1` restarts a
//! strip, odd triangles of a strip have their first two vertices swapped so that the whole strip
//! keeps the winding of its first triangle; triangles that repeat a vertex, which strips use to
//! stitch, are skipped). Other elements and properties are read and ignored.
//!
//! Counts in the header are checked before anything is allocated: against the mesh limits
//! ([`crate::limits`]) and against the bytes the file has left (each element needs at least its
//! binary size, or two characters per ascii value). Errors name the element, its index, the
//! property and the value (`element face[12].vertex_indices[2]` = 99).

use std::path::Path;

use glam::Vec3;

use super::super::mesh::TriangleMesh;
use crate::InputError;
use crate::limits::{MAX_MESH_TRIANGLES, MAX_MESH_VERTICES, bytes as human};

#[derive(Clone, Copy, Debug, PartialEq)]
enum Encoding {
    Ascii,
    LittleEndian,
    BigEndian,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(name: &str) -> Option<Scalar> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    fn is_integer(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }

    /// The range of an integer type.
    fn range(self) -> (i64, i64) {
        match self {
            Scalar::I8 => (i8::MIN as i64, i8::MAX as i64),
            Scalar::U8 => (0, u8::MAX as i64),
            Scalar::I16 => (i16::MIN as i64, i16::MAX as i64),
            Scalar::U16 => (0, u16::MAX as i64),
            Scalar::I32 => (i32::MIN as i64, i32::MAX as i64),
            _ => (0, u32::MAX as i64),
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

#[derive(Debug)]
struct Property {
    name: String,
    kind: Kind,
}

/// What an element is to the mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Role {
    Vertex,
    Face,
    Strips,
    Ignored,
}

#[derive(Debug)]
struct Element {
    name: String,
    count: u64,
    properties: Vec<Property>,
    role: Role,
}

impl Element {
    /// The fewest payload bytes one element occupies.
    fn min_bytes(&self, encoding: Encoding) -> u64 {
        let values = self.properties.iter().map(|p| match (encoding, p.kind) {
            (Encoding::Ascii, _) => 2,
            (_, Kind::Scalar(s)) => s.size() as u64,
            (_, Kind::List { count, .. }) => count.size() as u64,
        });
        values.sum::<u64>().max(1)
    }

    fn has_scalar(&self, name: &str) -> bool {
        self.properties
            .iter()
            .any(|p| p.name == name && matches!(p.kind, Kind::Scalar(_)))
    }

    /// The position of the index list property of a face or strip element.
    fn index_list(&self) -> Option<usize> {
        let names: &[&str] = match self.role {
            Role::Face => &["vertex_indices", "vertex_index"],
            Role::Strips => &["vertex_indices"],
            _ => &[],
        };
        self.properties
            .iter()
            .position(|p| names.contains(&p.name.as_str()))
    }
}

struct Header {
    encoding: Encoding,
    elements: Vec<Element>,
    /// Offset of the first payload byte.
    payload: usize,
}

/// Parses a PLY file; `path` names it in errors.
pub fn parse(bytes: &[u8], path: &Path) -> Result<TriangleMesh, InputError> {
    let header = header(bytes, path)?;
    check_counts(&header, bytes.len() - header.payload, path)?;
    let mut source = Source {
        bytes,
        at: header.payload,
        encoding: header.encoding,
        line: 0,
        words: Vec::new(),
        next_word: 0,
    };
    let vertex_count = header
        .elements
        .iter()
        .find(|e| e.role == Role::Vertex)
        .map_or(0, |e| e.count);
    let mut mesh = TriangleMesh {
        positions: Vec::with_capacity(vertex_count as usize),
        ..TriangleMesh::default()
    };
    let mut normals = Vec::new();
    let mut indices: Vec<i64> = Vec::new();
    for element in &header.elements {
        let with_normals = ["nx", "ny", "nz"].iter().all(|n| element.has_scalar(n));
        let list_at = element.index_list();
        if element.properties.is_empty() {
            continue;
        }
        for i in 0..element.count {
            let at = |property: &str| format!("element {}[{i}].{property}", element.name);
            source.begin(path, || format!("element {}[{i}]", element.name))?;
            let mut xyz = [0.0f32; 3];
            let mut normal = [0.0f32; 3];
            for (p, property) in element.properties.iter().enumerate() {
                let field = || at(&property.name);
                let err = |(v, why): ReadError| InputError::new(path, field(), v, why);
                match property.kind {
                    Kind::Scalar(scalar) => {
                        let value = source.read(scalar).map_err(err)?;
                        let slot = match property.name.as_str() {
                            "x" => Some(&mut xyz[0]),
                            "y" => Some(&mut xyz[1]),
                            "z" => Some(&mut xyz[2]),
                            "nx" => Some(&mut normal[0]),
                            "ny" => Some(&mut normal[1]),
                            "nz" => Some(&mut normal[2]),
                            _ => None,
                        };
                        if let (Role::Vertex, Some(slot)) = (element.role, slot) {
                            *slot = value as f32;
                        }
                    }
                    Kind::List { count, item } => {
                        let length = source.read(count).map_err(err)?;
                        let n = source.list_length(length, item).map_err(err)?;
                        indices.clear();
                        for k in 0..n {
                            let value = source.read(item).map_err(|(v, why)| {
                                InputError::new(path, format!("{}[{k}]", field()), v, why)
                            })?;
                            if list_at == Some(p) {
                                indices.push(value as i64);
                            }
                        }
                    }
                }
            }
            source.end(path, || format!("element {}[{i}]", element.name))?;
            let list_error = |(v, why): ReadError| {
                let name = list_at.map_or("", |p| element.properties[p].name.as_str());
                InputError::new(path, at(name), v, why)
            };
            match element.role {
                Role::Vertex => {
                    let vertex = || format!("element vertex[{i}]");
                    let checked = |r: Result<Vec3, ReadError>| {
                        r.map_err(|(v, why)| InputError::new(path, vertex(), v, why))
                    };
                    mesh.positions.push(checked(super::position(xyz))?);
                    if with_normals {
                        normals.push(checked(super::normal(normal))?);
                    }
                }
                Role::Face => {
                    face(&indices, vertex_count, &mut mesh.indices).map_err(list_error)?
                }
                Role::Strips => {
                    strip(&indices, vertex_count, &mut mesh.indices).map_err(list_error)?
                }
                Role::Ignored => {}
            }
            if mesh.indices.len() as u64 > MAX_MESH_TRIANGLES {
                return Err(InputError::new(
                    path,
                    format!("element {}[{i}]", element.name),
                    format!("{} triangles", mesh.indices.len()),
                    format!("more than {MAX_MESH_TRIANGLES} triangles"),
                ));
            }
        }
    }
    if mesh.indices.is_empty() {
        return Err(InputError::new(
            path,
            "element face",
            "0 triangles",
            "PLY file has no faces or strips",
        ));
    }
    if !normals.is_empty() {
        mesh.normals = Some(normals);
    }
    Ok(mesh)
}

/// Fan-triangulates one face, `(0, k, k + 1)`; the error is `(value, reason)`.
fn face(list: &[i64], vertices: u64, out: &mut Vec<[u32; 3]>) -> Result<(), (String, String)> {
    if list.len() < 3 {
        return Err((
            format!("{list:?}"),
            "a face needs at least 3 vertices".into(),
        ));
    }
    let ids = checked(list, vertices, false)?;
    out.extend((1..ids.len() - 1).map(|k| [ids[0], ids[k], ids[k + 1]]));
    Ok(())
}

/// The triangles of one strip list with `-1` restarts (see the module documentation).
fn strip(list: &[i64], vertices: u64, out: &mut Vec<[u32; 3]>) -> Result<(), (String, String)> {
    let ids = checked(list, vertices, true)?;
    for run in ids.split(|&v| v == u32::MAX) {
        for (k, w) in run.windows(3).enumerate() {
            let tri = if k % 2 == 0 {
                [w[0], w[1], w[2]]
            } else {
                [w[1], w[0], w[2]]
            };
            if tri[0] != tri[1] && tri[1] != tri[2] && tri[0] != tri[2] {
                out.push(tri);
            }
        }
    }
    Ok(())
}

/// The indices as `u32`, each in `0..vertices` (`-1` as `u32::MAX` where `restart` allows it).
fn checked(list: &[i64], vertices: u64, restart: bool) -> Result<Vec<u32>, (String, String)> {
    list.iter()
        .enumerate()
        .map(|(k, &v)| {
            if restart && v == -1 {
                Ok(u32::MAX)
            } else if v >= 0 && (v as u64) < vertices {
                Ok(v as u32)
            } else {
                Err((
                    format!("{v} (item {k})"),
                    format!("vertex index out of range 0..{vertices}"),
                ))
            }
        })
        .collect()
}

/// Parses the header up to `end_header`.
fn header(bytes: &[u8], path: &Path) -> Result<Header, InputError> {
    let mut at = 0;
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    let mut number = 0;
    loop {
        number += 1;
        let Some(length) = bytes[at..].iter().position(|&b| b == b'\n') else {
            return Err(InputError::new(
                path,
                format!("header line {number}"),
                "(end of file)",
                "the header has no `end_header` line",
            ));
        };
        let text = String::from_utf8_lossy(&bytes[at..at + length]);
        at += length + 1;
        let bad = |reason: &str| {
            InputError::new(path, format!("header line {number}"), text.trim(), reason)
        };
        let words: Vec<&str> = text.split_whitespace().collect();
        if number == 1 {
            if words != ["ply"] {
                return Err(bad("not a PLY file (the first line must be `ply`)"));
            }
            continue;
        }
        match words.as_slice() {
            [] | ["comment", ..] | ["obj_info", ..] => {}
            ["format", format, version] => {
                if !version.starts_with('1') {
                    return Err(bad("unsupported PLY version (expected 1.0)"));
                }
                encoding = Some(match *format {
                    "ascii" => Encoding::Ascii,
                    "binary_little_endian" => Encoding::LittleEndian,
                    "binary_big_endian" => Encoding::BigEndian,
                    _ => return Err(bad("unknown format")),
                });
            }
            ["element", name, count] => {
                let count: u64 = count
                    .parse()
                    .map_err(|_| bad("element count is not a non-negative integer"))?;
                let role = match *name {
                    "vertex" => Role::Vertex,
                    "face" => Role::Face,
                    "tristrips" => Role::Strips,
                    _ => Role::Ignored,
                };
                if role != Role::Ignored && elements.iter().any(|e| e.name == *name) {
                    return Err(bad("a second element of this name"));
                }
                elements.push(Element {
                    name: name.to_string(),
                    count,
                    properties: Vec::new(),
                    role,
                });
            }
            ["property", rest @ ..] => {
                let element = elements
                    .last_mut()
                    .ok_or_else(|| bad("property before any element"))?;
                let scalar =
                    |name: &str| Scalar::parse(name).ok_or_else(|| bad("unknown property type"));
                let (kind, name) = match rest {
                    ["list", count, item, name] => {
                        let count = scalar(count)?;
                        if !count.is_integer() {
                            return Err(bad("a list length must have an integer type"));
                        }
                        (
                            Kind::List {
                                count,
                                item: scalar(item)?,
                            },
                            name,
                        )
                    }
                    [scalar_type, name] => (Kind::Scalar(scalar(scalar_type)?), name),
                    _ => return Err(bad("expected `property <type> <name>` or a list")),
                };
                element.properties.push(Property {
                    name: name.to_string(),
                    kind,
                });
            }
            ["end_header"] => {
                let encoding = encoding.ok_or_else(|| bad("no `format` line before it"))?;
                let header = Header {
                    encoding,
                    elements,
                    payload: at,
                };
                check_properties(&header, path)?;
                return Ok(header);
            }
            _ => return Err(bad("not a PLY header line")),
        }
    }
}

/// The vertex element has scalar `x`, `y`, `z`; faces and strips have an integer index list.
fn check_properties(header: &Header, path: &Path) -> Result<(), InputError> {
    let bad = |element: &Element, value: String, reason: &str| {
        Err(InputError::new(
            path,
            format!("element {}", element.name),
            value,
            reason,
        ))
    };
    let names = |e: &Element| {
        let names: Vec<&str> = e.properties.iter().map(|p| p.name.as_str()).collect();
        format!("properties [{}]", names.join(", "))
    };
    if !header.elements.iter().any(|e| e.role == Role::Vertex) {
        return Err(InputError::new(
            path,
            "element vertex",
            "(missing)",
            "PLY file has no vertex element",
        ));
    }
    for element in &header.elements {
        match element.role {
            Role::Vertex if !["x", "y", "z"].iter().all(|n| element.has_scalar(n)) => {
                return bad(element, names(element), "vertex needs scalar x, y, z");
            }
            Role::Face | Role::Strips => {
                match element.index_list().map(|p| element.properties[p].kind) {
                    Some(Kind::List { item, .. }) if item.is_integer() => {}
                    _ => {
                        return bad(
                            element,
                            names(element),
                            "needs an integer list `vertex_indices`",
                        );
                    }
                }
            }
            _ => {}
        }
    }
    Ok(())
}

/// Header counts against the mesh limits and the payload's size, before any allocation.
fn check_counts(header: &Header, payload: usize, path: &Path) -> Result<(), InputError> {
    let mut needed = 0u64;
    for element in &header.elements {
        let field = format!("element {}", element.name);
        let limit = match element.role {
            Role::Vertex => Some((MAX_MESH_VERTICES, "vertices")),
            Role::Face | Role::Strips => Some((MAX_MESH_TRIANGLES, "entries")),
            Role::Ignored => None,
        };
        if let Some((limit, what)) = limit
            && element.count > limit
        {
            return Err(InputError::new(
                path,
                field,
                element.count.to_string(),
                format!("more than the limit of {limit} {what}"),
            ));
        }
        needed = element
            .count
            .checked_mul(element.min_bytes(header.encoding))
            .and_then(|n| n.checked_add(needed))
            .unwrap_or(u64::MAX);
        // An ascii file may lack the last newline.
        if needed > payload as u64 + 1 {
            return Err(InputError::new(
                path,
                field,
                element.count.to_string(),
                format!(
                    "the header's counts need at least {} of data, the file has {} after the header",
                    human(needed),
                    human(payload as u64)
                ),
            ));
        }
    }
    Ok(())
}

/// The payload, read one value at a time: binary from a cursor, ascii one line per element.
struct Source<'a> {
    bytes: &'a [u8],
    at: usize,
    encoding: Encoding,
    /// Payload line of the current ascii element (1-based).
    line: usize,
    words: Vec<&'a str>,
    next_word: usize,
}

/// A read error: `(value, reason)`.
type ReadError = (String, String);

impl<'a> Source<'a> {
    /// Starts an element: reads its (non-blank) line in ascii.
    fn begin(&mut self, path: &Path, field: impl Fn() -> String) -> Result<(), InputError> {
        if self.encoding != Encoding::Ascii {
            return Ok(());
        }
        loop {
            if self.at >= self.bytes.len() {
                return Err(InputError::new(
                    path,
                    field(),
                    "(end of file)",
                    "the file ends before the header's element count",
                ));
            }
            let rest: &'a [u8] = &self.bytes[self.at..];
            let length = rest.iter().position(|&b| b == b'\n').unwrap_or(rest.len());
            self.at += length + 1;
            self.line += 1;
            let text = std::str::from_utf8(&rest[..length]).map_err(|_| {
                InputError::new(
                    path,
                    format!("{} (payload line {})", field(), self.line),
                    String::from_utf8_lossy(&rest[..length]),
                    "an ascii PLY line that is not text",
                )
            })?;
            self.words.clear();
            self.words.extend(text.split_whitespace());
            self.next_word = 0;
            if !self.words.is_empty() {
                return Ok(());
            }
        }
    }

    /// Ends an element: in ascii, its line must have no values left.
    fn end(&self, path: &Path, field: impl Fn() -> String) -> Result<(), InputError> {
        let left = self.words.len() - self.next_word;
        if self.encoding == Encoding::Ascii && left > 0 {
            return Err(InputError::new(
                path,
                format!("{} (payload line {})", field(), self.line),
                self.words[self.next_word..].join(" "),
                format!("{left} value(s) more than the element's properties"),
            ));
        }
        Ok(())
    }

    /// The next value of type `scalar`, as `f64` (exact for every PLY type).
    fn read(&mut self, scalar: Scalar) -> Result<f64, ReadError> {
        match self.encoding {
            Encoding::Ascii => self.read_ascii(scalar),
            _ => self.read_binary(scalar),
        }
    }

    fn read_ascii(&mut self, scalar: Scalar) -> Result<f64, ReadError> {
        let Some(&word) = self.words.get(self.next_word) else {
            return Err((
                format!("(payload line {})", self.line),
                "the line has fewer values than the element's properties".into(),
            ));
        };
        self.next_word += 1;
        let bad = |what: &str| (word.to_string(), format!("not {what}"));
        if scalar.is_integer() {
            let (lo, hi) = scalar.range();
            match word.parse::<i64>() {
                Ok(v) if (lo..=hi).contains(&v) => Ok(v as f64),
                _ => Err(bad(&format!("an integer in {lo}..={hi}"))),
            }
        } else {
            word.parse::<f64>().map_err(|_| bad("a number"))
        }
    }

    fn read_binary(&mut self, scalar: Scalar) -> Result<f64, ReadError> {
        let size = scalar.size();
        let Some(raw) = self.bytes.get(self.at..self.at + size) else {
            return Err((
                format!("offset {}", self.at),
                "the file ends before the header's element count".into(),
            ));
        };
        self.at += size;
        let mut b = [0u8; 8];
        b[..size].copy_from_slice(raw);
        if self.encoding == Encoding::BigEndian {
            b[..size].reverse();
        }
        Ok(match scalar {
            Scalar::I8 => b[0] as i8 as f64,
            Scalar::U8 => b[0] as f64,
            Scalar::I16 => i16::from_le_bytes([b[0], b[1]]) as f64,
            Scalar::U16 => u16::from_le_bytes([b[0], b[1]]) as f64,
            Scalar::I32 => i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Scalar::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Scalar::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Scalar::F64 => f64::from_le_bytes(b),
        })
    }

    /// A list length read as `value`: non-negative, and no longer than what is left to read.
    fn list_length(&self, value: f64, item: Scalar) -> Result<u64, ReadError> {
        let n = value as i64;
        if n < 0 {
            return Err((n.to_string(), "negative list length".into()));
        }
        let n = n as u64;
        let left = match self.encoding {
            Encoding::Ascii => (self.words.len() - self.next_word) as u64,
            _ => ((self.bytes.len() - self.at) / item.size()) as u64,
        };
        if n > left {
            return Err((
                n.to_string(),
                format!("list length, but only {left} values are left"),
            ));
        }
        Ok(n)
    }
}
