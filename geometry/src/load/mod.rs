//! Mesh files: Wavefront OBJ ([`obj`]), PLY ([`ply`]: ascii and binary; vertices, faces
//! and triangle strips) and glTF 2.0 ([`gltf`]: `.gltf` and `.glb`; the default scene's triangle
//! primitives, placed by their nodes), read within the limits of [`crate::limits`].
//!
//! Every problem is an [`InputError`] naming the file, the element and the value.
//! Degenerate triangles are kept here; callers drop and count them with
//! [`TriangleMesh::drop_degenerate`].

pub mod gltf;
pub mod obj;
pub mod ply;

use std::path::Path;

use glam::Vec3;

use super::mesh::TriangleMesh;
use crate::InputError;
use crate::limits::{MAX_COORDINATE, MAX_MESH_FILE_BYTES, read_file};

/// A mesh file format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshFormat {
    Obj,
    Ply,
    /// glTF 2.0 JSON (`.gltf`): all primitives of the default scene, placed by their nodes and
    /// merged into one mesh ([`gltf::GltfScene::merged`]).
    Gltf,
    /// Binary glTF 2.0 (`.glb`), read as [`MeshFormat::Gltf`].
    Glb,
}

impl MeshFormat {
    /// The format of `path` by its extension (`.obj`, `.ply`, `.gltf` or `.glb`, any case).
    pub fn of(path: &Path) -> Result<MeshFormat, InputError> {
        let extension = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match extension.as_deref() {
            Some("obj") => Ok(MeshFormat::Obj),
            Some("ply") => Ok(MeshFormat::Ply),
            Some("gltf") => Ok(MeshFormat::Gltf),
            Some("glb") => Ok(MeshFormat::Glb),
            _ => Err(InputError::new(
                path,
                "extension",
                format!("{:?}", path.extension().unwrap_or_default()),
                "unsupported mesh format (expected .obj, .ply, .gltf or .glb)",
            )),
        }
    }
}

/// Loads a triangle mesh, choosing the format by extension.
pub fn load_mesh(path: &Path) -> Result<TriangleMesh, InputError> {
    let format = MeshFormat::of(path)?;
    parse_mesh(&read_file(path, MAX_MESH_FILE_BYTES)?, path, format)
}

/// Parses the bytes of a mesh file; `path` names it in errors, and a glTF file's external buffers
/// are read from its folder. Normals are normalised.
pub fn parse_mesh(
    bytes: &[u8],
    path: &Path,
    format: MeshFormat,
) -> Result<TriangleMesh, InputError> {
    let mut mesh = match format {
        MeshFormat::Obj => obj::parse(bytes, path)?,
        MeshFormat::Ply => ply::parse(bytes, path)?,
        MeshFormat::Gltf | MeshFormat::Glb => gltf::parse_gltf(bytes, path, &mut |relative| {
            gltf::read_beside(path, relative)
        })?
        .merged(),
    };
    if let Some(normals) = &mut mesh.normals {
        normals.iter_mut().for_each(|n| *n = n.normalize_or_zero());
    }
    Ok(mesh)
}

/// A vertex position, finite and within [`MAX_COORDINATE`], or `(value, reason)`.
fn position(xyz: [f32; 3]) -> Result<Vec3, (String, String)> {
    let p = Vec3::from(xyz);
    if p.is_finite() && p.abs().max_element() <= MAX_COORDINATE {
        Ok(p)
    } else {
        Err((
            format!("{:?}", p.to_array()),
            format!("a vertex position must be finite, each |coordinate| ≤ {MAX_COORDINATE:e}"),
        ))
    }
}

/// A vertex normal, finite (any length; normalised later), or `(value, reason)`.
fn normal(xyz: [f32; 3]) -> Result<Vec3, (String, String)> {
    let n = Vec3::from(xyz);
    if n.is_finite() {
        Ok(n)
    } else {
        Err((format!("{n}"), "a vertex normal must be finite".into()))
    }
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
            "line 1: v 1.z",
            "zero",
        );
        expect_error(
            &write("nan.obj", b"v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n"),
            "line 2: v 2",
            "NaN",
        );
        expect_error(
            &write("far.obj", b"v 0 0 0\nv 1e30 0 0\nv 0 1 0\nf 1 2 3\n"),
            "line 2: v 2",
            "1e30",
        );
        expect_error(
            &write(
                "bad.ply",
                b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float\nend_header\n",
            ),
            "header line 4",
            "property float",
        );
        let nan = binary_ply(
            &[(0.0, 0.0, 0.0), (1.0, 0.0, f64::NAN), (0.0, 1.0, 0.0)],
            &[[0, 1, 2]],
        );
        expect_error(&write("nan.ply", &nan), "element vertex[1]", "NaN");
        // Bodies for PLY_HEADER (5 vertices, 2 faces), each with one fault.
        for (name, body, field, value) in [
            (
                "nan_ascii.ply",
                "0 0 0 0 0 1\nnan 0 0 0 0 1\n1 1 0 0 0 1\n0 1 0 0 0 1\n0 0 1 0 0 1\n3 0 1 2\n3 0 2 3\n",
                "element vertex[1]",
                "NaN",
            ),
            (
                "range.ply",
                "0 0 0 0 0 1\n1 0 0 0 0 1\n1 1 0 0 0 1\n0 1 0 0 0 1\n0 0 1 0 0 1\n3 0 1 9\n3 0 2 3\n",
                "element face[0].vertex_indices",
                "9",
            ),
            (
                "short.ply",
                "0 0 0 0 0 1\n1 0 0 0 0 1\n1 1 0 0 0 1\n0 1 0 0 0 1\n0 0 1 0 0 1\n2 0 1\n3 0 2 3\n",
                "element face[0]",
                "[0, 1]",
            ),
            (
                "extra.ply",
                "0 0 0 0 0 1\n1 0 0 0 0 1 7\n1 1 0 0 0 1\n0 1 0 0 0 1\n0 0 1 0 0 1\n3 0 1 2\n3 0 2 3\n",
                "element vertex[1] (payload line 2)",
                "7",
            ),
        ] {
            expect_error(
                &write(name, format!("{PLY_HEADER}{body}").as_bytes()),
                field,
                value,
            );
        }
    }

    /// OBJ face errors name the line, the face, the corner and the index as written.
    #[test]
    fn obj_face_errors_name_face_and_index() {
        let vertices = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
        for (face, corner, value, reason) in [
            ("f 1 2 4", 3, "4", "1..=3"),
            ("f 0 1 2", 1, "0", "start at 1"),
            ("f 1 -4 2", 2, "-4", "-3..=-1"),
            ("f 1 2 x", 3, "x", "not an integer"),
            ("f 1//1 2 3", 1, "1", "no normal is defined"),
        ] {
            let path = write(
                "face.obj",
                format!("{vertices}f 1 2 3\n{face}\n").as_bytes(),
            );
            let error = expect_error(&path, &format!("line 5: face 2 corner {corner}"), value);
            assert_eq!(error.value, value);
            assert!(error.reason.contains(reason), "{error}");
        }
    }

    /// Negative indices are relative to the vertices defined so far; `vt` is ignored.
    #[test]
    fn obj_relative_indices_and_texture_coordinates() {
        let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf -3/1 -2/1 -1/1\nv 1 1 0\nf 2 4 3\n";
        let mesh = load_mesh(&write("relative.obj", obj.as_bytes())).unwrap();
        assert_eq!(mesh.indices, vec![[0, 1, 2], [1, 3, 2]]);
        assert_eq!(mesh.normals, None);
    }

    /// The header's counts are checked against the limits and the file's size before anything
    /// is allocated: a 3-vertex file that claims 60 000 000 000 vertices is a one-line error.
    #[test]
    fn ply_header_counts_are_not_trusted() {
        let huge = PLY_HEADER.replace("element vertex 5", "element vertex 60000000000");
        let error = expect_error(
            &write("huge.ply", format!("{huge}0 0 0 0 0 1\n").as_bytes()),
            "element vertex",
            "60000000000",
        );
        assert!(error.reason.contains("limit"), "{error}");
        let many = PLY_HEADER.replace("element vertex 5", "element vertex 1000000");
        let error = expect_error(
            &write("many.ply", format!("{many}0 0 0 0 0 1\n").as_bytes()),
            "element vertex",
            "1000000",
        );
        assert!(error.reason.contains("after the header"), "{error}");
        let binary = binary_ply(&[(0.0, 0.0, 0.0); 3], &[[0, 1, 2]]);
        let text = String::from_utf8_lossy(&binary).replace("element face 1", "element face 99");
        let error = expect_error(
            &write("short_binary.ply", &binary_with_header(&binary, &text)),
            "element face",
            "99",
        );
        assert!(error.reason.contains("after the header"), "{error}");
    }

    /// `binary` with its header replaced by the header of `text` (same payload).
    fn binary_with_header(binary: &[u8], text: &str) -> Vec<u8> {
        let end = b"end_header\n";
        let split = binary.windows(end.len()).position(|w| w == end).unwrap() + end.len();
        let header_end = text.find("end_header\n").unwrap() + end.len();
        let mut out = text.as_bytes()[..header_end].to_vec();
        out.extend_from_slice(&binary[split..]);
        out
    }

    /// A 2×3 grid of vertices as one strip, with a restart (`-1`) and a stitching triangle that
    /// repeats a vertex, equals the triangle list it encodes (same winding), in ascii and in
    /// binary little-endian.
    #[test]
    fn ply_triangle_strips_match_the_triangle_list() {
        // 3 4 5
        // 0 1 2      strip 0 3 1 4 2 5 = (0 3 1), (1 3 4) swapped, (1 4 2), (2 4 5) swapped.
        let vertices = [
            (0.0, 0.0, 0.0),
            (1.0, 0.0, 0.0),
            (2.0, 0.0, 0.0),
            (0.0, 1.0, 0.0),
            (1.0, 1.0, 0.0),
            (2.0, 1.0, 0.0),
        ];
        let list = [[0, 3, 1], [1, 3, 4], [1, 4, 2], [2, 4, 5]];
        // The strip in two pieces: 0 3 1 4 with a stitch (4 4), then a restart and 1 4 2 5.
        let strips: &[i32] = &[0, 3, 1, 4, 4, -1, 1, 4, 2, 5];
        let expected = load_mesh(&write("list.ply", &binary_ply(&vertices, &list))).unwrap();
        let header = |format: &str| {
            format!(
                "ply\nformat {format} 1.0\nelement vertex 6\nproperty float x\nproperty float y\n\
                 property float z\nelement tristrips 1\nproperty list int int vertex_indices\nend_header\n"
            )
        };
        let mut ascii = header("ascii");
        for (x, y, z) in vertices {
            ascii += &format!("{x} {y} {z}\n");
        }
        let items: Vec<String> = strips.iter().map(i32::to_string).collect();
        ascii += &format!("{} {}\n", strips.len(), items.join(" "));
        let mut binary = header("binary_little_endian").into_bytes();
        for (x, y, z) in vertices {
            for v in [x, y, z as f32] {
                binary.extend(v.to_le_bytes());
            }
        }
        binary.extend((strips.len() as i32).to_le_bytes());
        strips.iter().for_each(|i| binary.extend(i.to_le_bytes()));
        for (name, bytes) in [("strip.ply", ascii.into_bytes()), ("strip_le.ply", binary)] {
            let mesh = load_mesh(&write(name, &bytes)).unwrap();
            assert_eq!(mesh.positions, expected.positions, "{name}");
            assert_eq!(mesh.indices, expected.indices, "{name}");
            // One winding: every triangle's geometric normal is −z, like the list's.
            for i in 0..mesh.triangle_count() {
                let [a, b, c] = mesh.triangle(i);
                assert!((b - a).cross(c - a).z < 0.0, "{name} triangle {i}");
            }
        }
    }

    /// Big-endian binary and a face element before the vertices, with extra properties on both.
    #[test]
    fn ply_big_endian_with_extra_properties() {
        let mut bytes = "ply\nformat binary_big_endian 1.0\ncomment made by hand\n\
            element face 1\nproperty uchar flags\nproperty list uchar ushort vertex_index\n\
            element vertex 3\nproperty double x\nproperty double y\nproperty double z\n\
            property uchar red\nelement edge 1\nproperty int a\nend_header\n"
            .as_bytes()
            .to_vec();
        bytes.extend([7u8, 3]);
        [0u16, 1, 2]
            .iter()
            .for_each(|i| bytes.extend(i.to_be_bytes()));
        for p in [[0.0f64, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
            p.iter().for_each(|x| bytes.extend(x.to_be_bytes()));
            bytes.push(255);
        }
        bytes.extend(5i32.to_be_bytes());
        let mesh = load_mesh(&write("big.ply", &bytes)).unwrap();
        assert_eq!(mesh.indices, vec![[0, 1, 2]]);
        assert_eq!(mesh.positions[1], Vec3::X);
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
