//! Wavefront OBJ: `v` positions, `vn` normals and `f` faces (`v`, `v/vt`, `v//vn`, `v/vt/vn`;
//! 1-based, or negative relative to the last vertex defined so far), polygons fan-triangulated.
//! Every other statement (`vt`, `o`, `g`, `s`, `usemtl`, `mtllib`, `l`, comments, …) is ignored;
//! material libraries are not opened.
//!
//! Shading normals are kept when every face corner names one: each distinct (position, normal)
//! pair becomes one vertex. Otherwise the mesh is flat-shaded.
//!
//! Errors name the line, the face (1-based, in file order) and the index or number at fault.

use std::collections::HashMap;
use std::path::Path;

use glam::Vec3;

use super::super::mesh::TriangleMesh;
use crate::InputError;
use crate::limits::{MAX_MESH_TRIANGLES, MAX_MESH_VERTICES};

/// One face corner: 0-based position index and, if given, 0-based normal index.
type Corner = (u32, Option<u32>);

/// Parses OBJ text; `path` names the file in errors.
pub fn parse(bytes: &[u8], path: &Path) -> Result<TriangleMesh, InputError> {
    let mut positions: Vec<Vec3> = Vec::new();
    let mut normals: Vec<Vec3> = Vec::new();
    let mut triangles: Vec<[Corner; 3]> = Vec::new();
    let mut faces = 0u64;
    let mut corners: Vec<Corner> = Vec::new();
    for (number, raw) in bytes.split(|&b| b == b'\n').enumerate() {
        let line = number + 1;
        let text = String::from_utf8_lossy(raw);
        let mut words = text.split_whitespace();
        let err = |field: String, value: &str, reason: String| {
            InputError::new(path, field, value, reason)
        };
        match words.next() {
            Some(kind @ ("v" | "vn")) => {
                let list = if kind == "v" {
                    &mut positions
                } else {
                    &mut normals
                };
                let field = || format!("line {line}: {kind} {}", list.len() + 1);
                if list.len() as u64 >= MAX_MESH_VERTICES {
                    return Err(err(
                        field(),
                        &text,
                        format!("more than {MAX_MESH_VERTICES} `{kind}` statements"),
                    ));
                }
                let mut xyz = [0.0f32; 3];
                for (axis, x) in xyz.iter_mut().enumerate() {
                    let word = words
                        .next()
                        .ok_or_else(|| err(field(), &text, "expected 3 numbers".to_string()))?;
                    *x = word.parse().map_err(|_| {
                        err(
                            format!("{}.{}", field(), ["x", "y", "z"][axis]),
                            word,
                            "not a number".to_string(),
                        )
                    })?;
                }
                let checked = if kind == "v" {
                    super::position(xyz)
                } else {
                    super::normal(xyz)
                };
                list.push(checked.map_err(|(value, reason)| err(field(), &value, reason))?);
            }
            Some("f") => {
                faces += 1;
                corners.clear();
                for (k, word) in words.enumerate() {
                    let field = || format!("line {line}: face {faces} corner {}", k + 1);
                    corners.push(
                        corner(word, positions.len(), normals.len())
                            .map_err(|(value, reason)| err(field(), &value, reason))?,
                    );
                }
                if corners.len() < 3 {
                    return Err(err(
                        format!("line {line}: face {faces}"),
                        &text,
                        "a face needs at least 3 vertices".to_string(),
                    ));
                }
                if (triangles.len() + corners.len() - 2) as u64 > MAX_MESH_TRIANGLES {
                    return Err(err(
                        format!("line {line}: face {faces}"),
                        &format!("{} triangles so far", triangles.len()),
                        format!("more than {MAX_MESH_TRIANGLES} triangles"),
                    ));
                }
                // Fan triangulation: (0, k, k + 1).
                triangles.extend(
                    (1..corners.len() - 1).map(|k| [corners[0], corners[k], corners[k + 1]]),
                );
            }
            _ => {}
        }
    }
    if triangles.is_empty() {
        return Err(InputError::new(path, "f", "none", "OBJ file has no faces"));
    }
    Ok(if triangles.iter().flatten().all(|c| c.1.is_some()) {
        with_normals(&positions, &normals, &triangles)
    } else {
        TriangleMesh {
            positions,
            indices: triangles.iter().map(|t| t.map(|c| c.0)).collect(),
            normals: None,
        }
    })
}

/// `v`, `v/vt`, `v//vn` or `v/vt/vn` with `positions` and `normals` defined so far; the error is
/// `(value, reason)`.
fn corner(word: &str, positions: usize, normals: usize) -> Result<Corner, (String, String)> {
    let mut parts = word.split('/');
    let v = index(parts.next().unwrap_or(""), positions, "vertex")?;
    let _texture = parts.next();
    let n = match parts.next() {
        None | Some("") => None,
        Some(n) => Some(index(n, normals, "normal")?),
    };
    if parts.next().is_some() {
        return Err((
            word.to_string(),
            "expected v, v/vt, v//vn or v/vt/vn".into(),
        ));
    }
    Ok((v, n))
}

/// A 1-based or negative (relative) OBJ index into `count` items defined so far, 0-based.
fn index(text: &str, count: usize, what: &str) -> Result<u32, (String, String)> {
    let range = || {
        if count == 0 {
            format!("no {what} is defined before this face")
        } else {
            format!("{what} index out of range: 1..={count} or -{count}..=-1")
        }
    };
    let value: i64 = text
        .parse()
        .map_err(|_| (text.to_string(), format!("{what} index is not an integer")))?;
    let count = count as i64;
    let resolved = match value {
        0 => {
            return Err((
                text.to_string(),
                format!("{what} index 0: OBJ indices start at 1"),
            ));
        }
        v if v > 0 && v <= count => v - 1,
        v if v < 0 && -v <= count => count + v,
        _ => return Err((text.to_string(), range())),
    };
    Ok(resolved as u32)
}

/// One vertex per distinct (position, normal) pair of the triangles' corners.
fn with_normals(positions: &[Vec3], normals: &[Vec3], triangles: &[[Corner; 3]]) -> TriangleMesh {
    let mut ids: HashMap<(u32, u32), u32> = HashMap::new();
    let mut mesh = TriangleMesh {
        normals: Some(Vec::new()),
        ..TriangleMesh::default()
    };
    for triangle in triangles {
        let tri = triangle.map(|(v, n)| {
            let n = n.unwrap_or_default();
            *ids.entry((v, n)).or_insert_with(|| {
                mesh.positions.push(positions[v as usize]);
                if let Some(all) = &mut mesh.normals {
                    all.push(normals[n as usize]);
                }
                mesh.positions.len() as u32 - 1
            })
        });
        mesh.indices.push(tri);
    }
    mesh
}
