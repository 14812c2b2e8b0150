//! Mesh files: Wavefront OBJ (via `tobj`, triangulated) and PLY (via `ply-rs`; ascii and binary;
//! `vertex` and `face` elements only, faces with n ≥ 3 vertices fan-triangulated).
//!
//! Every problem is an [`InputError`] naming the file, the element/field and the value.
//! Degenerate triangles are kept here; callers drop and count them with
//! [`TriangleMesh::drop_degenerate`].

use std::fs::File;
use std::io::BufReader;
use std::path::Path;

use glam::Vec3;
use ply_rs::parser::Parser;
use ply_rs::ply::{DefaultElement, Property};

use super::mesh::TriangleMesh;
use crate::InputError;

/// Loads a triangle mesh, choosing the format by extension (`.obj` or `.ply`, any case).
pub fn load_mesh(path: &Path) -> Result<TriangleMesh, InputError> {
    let extension = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let mut mesh = match extension.as_deref() {
        Some("obj") => load_obj(path)?,
        Some("ply") => load_ply(path)?,
        _ => {
            return Err(InputError::new(
                path,
                "extension",
                format!("{:?}", path.extension().unwrap_or_default()),
                "unsupported mesh format (expected .obj or .ply)",
            ));
        }
    };
    validate(path, &mesh)?;
    if let Some(normals) = &mut mesh.normals {
        normals.iter_mut().for_each(|n| *n = n.normalize_or_zero());
    }
    Ok(mesh)
}

fn load_obj(path: &Path) -> Result<TriangleMesh, InputError> {
    if !path.is_file() {
        return Err(InputError::new(
            path,
            "file",
            path.display().to_string(),
            "mesh file not found",
        ));
    }
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ..Default::default()
    };
    let (models, _materials) = tobj::load_obj(path, &options)
        .map_err(|e| InputError::new(path, "obj", e.to_string(), "malformed OBJ"))?;
    let mut mesh = TriangleMesh::default();
    let mut normals = Some(Vec::new());
    for model in &models {
        let m = &model.mesh;
        let base = mesh.positions.len() as u32;
        mesh.positions.extend(
            m.positions
                .chunks_exact(3)
                .map(|p| Vec3::new(p[0], p[1], p[2])),
        );
        mesh.indices.extend(
            m.indices
                .chunks_exact(3)
                .map(|t| [t[0] + base, t[1] + base, t[2] + base]),
        );
        // Shading normals only if every model has one per vertex; otherwise flat shading.
        normals = match normals {
            Some(mut all) if m.normals.len() == m.positions.len() => {
                all.extend(
                    m.normals
                        .chunks_exact(3)
                        .map(|n| Vec3::new(n[0], n[1], n[2])),
                );
                Some(all)
            }
            _ => None,
        };
    }
    mesh.normals = normals.filter(|n| !n.is_empty());
    if mesh.indices.is_empty() {
        return Err(InputError::new(path, "f", "none", "OBJ file has no faces"));
    }
    Ok(mesh)
}

fn load_ply(path: &Path) -> Result<TriangleMesh, InputError> {
    let file = File::open(path)
        .map_err(|e| InputError::new(path, "file", path.display().to_string(), e.to_string()))?;
    let ply = Parser::<DefaultElement>::new()
        .read_ply(&mut BufReader::new(file))
        .map_err(|e| InputError::new(path, "ply", e.to_string(), "malformed PLY"))?;
    if let Some(name) = ply
        .header
        .elements
        .keys()
        .find(|name| *name != "vertex" && *name != "face")
    {
        let count = ply.header.elements[name].count;
        return Err(InputError::new(
            path,
            format!("element {name}"),
            count.to_string(),
            "unsupported PLY element (only `vertex` and `face` are read)",
        ));
    }
    let no_elements = Vec::new();
    let vertices = ply.payload.get("vertex").unwrap_or(&no_elements);
    let faces = ply.payload.get("face").unwrap_or(&no_elements);
    if vertices.is_empty() || faces.is_empty() {
        return Err(InputError::new(
            path,
            "element face",
            "0",
            "PLY file has no vertices or no faces",
        ));
    }

    let scalar =
        |element: &DefaultElement, i: usize, key: &str| -> Result<Option<f32>, InputError> {
            let value = match element.get(key) {
                None => return Ok(None),
                Some(Property::Float(x)) => *x,
                Some(Property::Double(x)) => *x as f32,
                Some(Property::Char(x)) => *x as f32,
                Some(Property::UChar(x)) => *x as f32,
                Some(Property::Short(x)) => *x as f32,
                Some(Property::UShort(x)) => *x as f32,
                Some(Property::Int(x)) => *x as f32,
                Some(Property::UInt(x)) => *x as f32,
                Some(other) => {
                    return Err(InputError::new(
                        path,
                        format!("vertex[{i}].{key}"),
                        format!("{other:?}"),
                        "expected a number",
                    ));
                }
            };
            Ok(Some(value))
        };
    let mut positions = Vec::with_capacity(vertices.len());
    let mut normals = Some(Vec::with_capacity(vertices.len()));
    for (i, vertex) in vertices.iter().enumerate() {
        let mut p = [0.0f32; 3];
        for (axis, key) in ["x", "y", "z"].into_iter().enumerate() {
            p[axis] = scalar(vertex, i, key)?.ok_or_else(|| {
                InputError::new(
                    path,
                    format!("vertex[{i}].{key}"),
                    "missing",
                    "vertex needs x, y, z",
                )
            })?;
        }
        positions.push(Vec3::from(p));
        let n = [
            scalar(vertex, i, "nx")?,
            scalar(vertex, i, "ny")?,
            scalar(vertex, i, "nz")?,
        ];
        normals = match (normals, n) {
            (Some(mut all), [Some(x), Some(y), Some(z)]) => {
                all.push(Vec3::new(x, y, z));
                Some(all)
            }
            _ => None,
        };
    }

    let mut indices = Vec::with_capacity(faces.len());
    for (i, face) in faces.iter().enumerate() {
        let field = || format!("face[{i}].vertex_indices");
        let list: Vec<i64> = match face
            .get("vertex_indices")
            .or_else(|| face.get("vertex_index"))
        {
            Some(Property::ListChar(l)) => l.iter().map(|&v| v as i64).collect(),
            Some(Property::ListUChar(l)) => l.iter().map(|&v| v as i64).collect(),
            Some(Property::ListShort(l)) => l.iter().map(|&v| v as i64).collect(),
            Some(Property::ListUShort(l)) => l.iter().map(|&v| v as i64).collect(),
            Some(Property::ListInt(l)) => l.iter().map(|&v| v as i64).collect(),
            Some(Property::ListUInt(l)) => l.iter().map(|&v| v as i64).collect(),
            other => {
                return Err(InputError::new(
                    path,
                    field(),
                    format!("{other:?}"),
                    "expected an integer list",
                ));
            }
        };
        if list.len() < 3 {
            return Err(InputError::new(
                path,
                field(),
                format!("{list:?}"),
                "a face needs at least 3 vertices",
            ));
        }
        if let Some(&bad) = list.iter().find(|&&v| v < 0 || v >= positions.len() as i64) {
            return Err(InputError::new(
                path,
                field(),
                bad.to_string(),
                format!("index out of range 0..{}", positions.len()),
            ));
        }
        // Fan triangulation: (0, k, k + 1).
        indices.extend(
            (1..list.len() - 1).map(|k| [list[0] as u32, list[k] as u32, list[k + 1] as u32]),
        );
    }
    Ok(TriangleMesh {
        positions,
        indices,
        normals,
    })
}

/// Rejects out-of-range indices and non-finite positions or normals.
fn validate(path: &Path, mesh: &TriangleMesh) -> Result<(), InputError> {
    if let Some((i, p)) = mesh
        .positions
        .iter()
        .enumerate()
        .find(|(_, p)| !p.is_finite())
    {
        return Err(InputError::new(
            path,
            format!("vertex[{i}]"),
            format!("{p}"),
            "non-finite vertex position",
        ));
    }
    let normals = mesh.normals.as_deref().unwrap_or_default();
    if let Some((i, n)) = normals.iter().enumerate().find(|(_, n)| !n.is_finite()) {
        return Err(InputError::new(
            path,
            format!("normal[{i}]"),
            format!("{n}"),
            "non-finite vertex normal",
        ));
    }
    let count = mesh.positions.len() as u32;
    if let Some((i, t)) = mesh
        .indices
        .iter()
        .enumerate()
        .find(|(_, t)| t.iter().any(|&v| v >= count))
    {
        return Err(InputError::new(
            path,
            format!("face[{i}]"),
            format!("{t:?}"),
            format!("index out of range 0..{count}"),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    /// Writes `contents` to a fresh file in a per-process temp directory.
    fn write(name: &str, contents: &[u8]) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("sss-geometry-load-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(name);
        std::fs::write(&path, contents).unwrap();
        path
    }

    fn expect_error(path: &Path, field: &str, value: &str) -> InputError {
        let error = load_mesh(path).expect_err("must be rejected");
        assert_eq!(error.file, path);
        assert!(
            error.field.contains(field),
            "field `{}` should name `{field}` ({error})",
            error.field
        );
        assert!(
            error.value.contains(value),
            "value `{}` should show `{value}` ({error})",
            error.value
        );
        error
    }

    const PLY_HEADER: &str = "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\n\
        property float z\nproperty float nx\nproperty float ny\nproperty float nz\n\
        element face 2\nproperty list uchar int vertex_indices\nend_header\n";

    #[test]
    fn obj_quads_are_triangulated_with_normals() {
        let obj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 2\n\
                   f 1//1 2//1 3//1 4//1\no second\nv 0 0 1\nv 1 0 1\nv 0 1 1\nf 5//1 6//1 7//1\n";
        let mesh = load_mesh(&write("quad.obj", obj.as_bytes())).unwrap();
        assert_eq!(mesh.triangle_count(), 3);
        assert!((mesh.area() - 1.5).abs() < 1e-9);
        let normals = mesh.normals.as_ref().expect("normals");
        assert_eq!(normals.len(), mesh.positions.len());
        assert!(
            normals.iter().all(|&n| n == Vec3::Z),
            "normalised: {normals:?}"
        );
        let without =
            load_mesh(&write("flat.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")).unwrap();
        assert_eq!((without.triangle_count(), without.normals), (1, None));
    }

    #[test]
    fn ply_ascii_fans_polygons() {
        let body = "0 0 0 0 0 1\n1 0 0 0 0 1\n1 1 0 0 0 1\n0 1 0 0 0 1\n0.5 0.5 1 0 0 1\n4 0 1 2 3\n3 0 1 4\n";
        let mesh = load_mesh(&write("fan.PLY", format!("{PLY_HEADER}{body}").as_bytes())).unwrap();
        assert_eq!(mesh.indices, vec![[0, 1, 2], [0, 2, 3], [0, 1, 4]]);
        assert_eq!(mesh.positions[4], Vec3::new(0.5, 0.5, 1.0));
        assert_eq!(mesh.normals.as_ref().map(Vec::len), Some(5));
    }

    /// A binary little-endian PLY with float x, y and double z, and uint triangle lists.
    fn binary_ply(vertices: &[(f32, f32, f64)], faces: &[[u32; 3]]) -> Vec<u8> {
        let header = format!(
            "ply\nformat binary_little_endian 1.0\nelement vertex {}\nproperty float x\nproperty float y\n\
             property double z\nelement face {}\nproperty list uchar uint vertex_indices\nend_header\n",
            vertices.len(),
            faces.len()
        );
        let mut bytes = header.into_bytes();
        for &(x, y, z) in vertices {
            bytes.extend(x.to_le_bytes());
            bytes.extend(y.to_le_bytes());
            bytes.extend(z.to_le_bytes());
        }
        for face in faces {
            bytes.push(3);
            face.iter().for_each(|i| bytes.extend(i.to_le_bytes()));
        }
        bytes
    }

    #[test]
    fn ply_binary_little_endian() {
        let vertices = [
            (0.0, 0.0, 0.0),
            (2.0, 0.0, 0.0),
            (2.0, 2.0, 0.0),
            (0.0, 0.0, 2.0),
        ];
        let mesh = load_mesh(&write(
            "binary.ply",
            &binary_ply(&vertices, &[[0, 1, 2], [0, 1, 3]]),
        ))
        .unwrap();
        assert_eq!(mesh.indices, vec![[0, 1, 2], [0, 1, 3]]);
        assert_eq!(mesh.positions[3], Vec3::new(0.0, 0.0, 2.0));
        assert_eq!(mesh.normals, None);
        assert!((mesh.area() - 4.0).abs() < 1e-9);
    }

    #[test]
    fn bad_files_are_input_errors() {
        let dir = std::env::temp_dir();
        expect_error(
            &dir.join("sss-geometry-no-such-file.obj"),
            "file",
            "no-such-file",
        );
        expect_error(
            &dir.join("sss-geometry-no-such-file.ply"),
            "file",
            "no-such-file",
        );
        expect_error(&write("mesh.stl", b"solid"), "extension", "stl");
        expect_error(
            &write("bad.obj", b"v 0 0 zero\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"),
            "obj",
            "",
        );
        expect_error(
            &write("nan.obj", b"v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n"),
            "vertex[1]",
            "NaN",
        );
        expect_error(
            &write(
                "bad.ply",
                b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float\nend_header\n",
            ),
            "ply",
            "",
        );
        let strips = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
            element tristrips 1\nproperty list int int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
        expect_error(
            &write("strips.ply", strips.as_bytes()),
            "element tristrips",
            "1",
        );
        let nan = binary_ply(
            &[(0.0, 0.0, 0.0), (1.0, 0.0, f64::NAN), (0.0, 1.0, 0.0)],
            &[[0, 1, 2]],
        );
        expect_error(&write("nan.ply", &nan), "vertex[1]", "NaN");
        // ply-rs's ascii grammar has no NaN: the parse error names the line and its text.
        let body =
            "0 0 0 0 0 1\nnan 0 0 0 0 1\n1 1 0 0 0 1\n0 1 0 0 0 1\n0 0 1 0 0 1\n3 0 1 2\n3 0 2 3\n";
        expect_error(
            &write("nan_ascii.ply", format!("{PLY_HEADER}{body}").as_bytes()),
            "ply",
            "nan 0 0",
        );
        let body =
            "0 0 0 0 0 1\n1 0 0 0 0 1\n1 1 0 0 0 1\n0 1 0 0 0 1\n0 0 1 0 0 1\n3 0 1 9\n3 0 2 3\n";
        expect_error(
            &write("range.ply", format!("{PLY_HEADER}{body}").as_bytes()),
            "face[0]",
            "9",
        );
        let body =
            "0 0 0 0 0 1\n1 0 0 0 0 1\n1 1 0 0 0 1\n0 1 0 0 0 1\n0 0 1 0 0 1\n2 0 1\n3 0 2 3\n";
        expect_error(
            &write("short.ply", format!("{PLY_HEADER}{body}").as_bytes()),
            "face[0]",
            "[0, 1]",
        );
    }

    #[test]
    fn degenerate_triangles_load_and_are_counted() {
        // Face 1 repeats a vertex, face 2 is collinear: both load, both are dropped.
        let header = PLY_HEADER.replace("element face 2", "element face 3");
        let body = "0 0 0 0 0 1\n1 0 0 0 0 1\n1 1 0 0 0 1\n2 2 0 0 0 1\n0 0 1 0 0 1\n3 0 1 2\n3 0 1 1\n3 0 2 3\n";
        let mut mesh = load_mesh(&write(
            "degenerate.ply",
            format!("{header}{body}").as_bytes(),
        ))
        .unwrap();
        assert_eq!(mesh.triangle_count(), 3);
        assert_eq!(mesh.drop_degenerate(), 2);
        assert_eq!(mesh.indices, vec![[0, 1, 2]]);
    }
}
