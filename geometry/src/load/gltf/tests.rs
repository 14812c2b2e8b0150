//! The glTF loader on small documents built here (JSON + bytes, as `.glb` or with a `data:` URI
//! buffer), on external buffer files, and on the shared assets of paper 001 when present.

use std::path::PathBuf;

use ::gltf::json::Value;
use glam::{Mat4, Quat, Vec3, vec3};

use base64::Engine as _;

use super::*;
use crate::limits::{MAX_GLTF_NODE_DEPTH, MAX_GLTF_PRIMITIVES};
use crate::load::{MeshFormat, load_mesh};

/// A glTF document under construction: its JSON and the bytes of its one buffer.
#[derive(Clone)]
struct Doc {
    json: Value,
    bin: Vec<u8>,
}

/// The little-endian bytes of `values`.
fn floats(values: &[[f32; 3]]) -> Vec<u8> {
    values
        .iter()
        .flatten()
        .flat_map(|x| x.to_le_bytes())
        .collect()
}

/// The unit square in z = 0 (0..1 in x and y), facing +z.
const QUAD: [[f32; 3]; 4] = [
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [1.0, 1.0, 0.0],
    [0.0, 1.0, 0.0],
];
const QUAD_TRIANGLES: [[u32; 3]; 2] = [[0, 1, 2], [0, 2, 3]];

impl Doc {
    /// One node placing one mesh: the quad with normals and u16 indices, material 0. The buffer:
    /// positions at 0..48, normals at 48..96, indices at 96..108.
    fn quad() -> Doc {
        let json = r#"{
            "asset": {"version": "2.0"},
            "scene": 0,
            "scenes": [{"nodes": [0]}],
            "nodes": [{"mesh": 0}],
            "meshes": [{"primitives": [
                {"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2, "material": 0}
            ]}],
            "materials": [{"name": "quad"}],
            "accessors": [
                {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
                 "min": [0, 0, 0], "max": [1, 1, 0]},
                {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3"},
                {"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"}
            ],
            "bufferViews": [
                {"buffer": 0, "byteOffset": 0, "byteLength": 48},
                {"buffer": 0, "byteOffset": 48, "byteLength": 48},
                {"buffer": 0, "byteOffset": 96, "byteLength": 12}
            ],
            "buffers": [{"byteLength": 108}]
        }"#;
        let mut bin = floats(&QUAD);
        bin.extend(floats(&[[0.0, 0.0, 1.0]; 4]));
        bin.extend([0u16, 1, 2, 0, 2, 3].iter().flat_map(|i| i.to_le_bytes()));
        Doc {
            json: json::deserialize::from_str(json).expect("valid JSON"),
            bin,
        }
    }

    /// `value` (JSON text) at the JSON pointer (`/accessors/0/count`), added if absent.
    fn with(mut self, pointer: &str, value: &str) -> Doc {
        let value: Value = json::deserialize::from_str(value).expect("valid JSON value");
        let (parent, key) = pointer.rsplit_once('/').expect("a JSON pointer");
        match self.json.pointer_mut(parent).expect("the parent exists") {
            Value::Object(map) => {
                map.insert(key.to_string(), value);
            }
            Value::Array(list) => match key.parse::<usize>().expect("an index") {
                i if i == list.len() => list.push(value),
                i => list[i] = value,
            },
            other => panic!("{parent} is {other}"),
        }
        self
    }

    /// Without the member at the JSON pointer.
    fn without(mut self, pointer: &str) -> Doc {
        let (parent, key) = pointer.rsplit_once('/').expect("a JSON pointer");
        let parent = self.json.pointer_mut(parent).expect("the parent exists");
        parent.as_object_mut().expect("an object").remove(key);
        self
    }

    /// The buffer's bytes changed by `edit`.
    fn with_bin(mut self, edit: impl FnOnce(&mut Vec<u8>)) -> Doc {
        edit(&mut self.bin);
        self
    }

    /// The JSON text.
    fn text(&self) -> Vec<u8> {
        json::serialize::to_vec(&self.json).expect("serialisable")
    }

    /// A `.gltf` whose buffer 0 is a base64 `data:` URI (unless the document names a uri).
    fn embedded(&self) -> Vec<u8> {
        let uri = format!(
            "\"data:application/octet-stream;base64,{}\"",
            base64::engine::general_purpose::STANDARD.encode(&self.bin)
        );
        match self.json.pointer("/buffers/0/uri") {
            Some(_) => self.text(),
            None => self.clone().with("/buffers/0/uri", &uri).text(),
        }
    }

    /// A `.glb`: the JSON chunk, then the buffer as the BIN chunk.
    fn glb(&self) -> Vec<u8> {
        glb_bytes(&self.text(), Some(&self.bin))
    }
}

/// A GLB of a JSON chunk and an optional BIN chunk, each padded to 4 bytes (glTF 2.0 §4.4).
fn glb_bytes(json: &[u8], bin: Option<&[u8]>) -> Vec<u8> {
    let padded = |bytes: &[u8], pad: u8| {
        let mut v = bytes.to_vec();
        v.resize(bytes.len().next_multiple_of(4), pad);
        v
    };
    let mut chunks = Vec::new();
    for (data, kind, pad) in [(Some(json), b"JSON", b' '), (bin, b"BIN\0", 0)] {
        if let Some(data) = data {
            let data = padded(data, pad);
            chunks.extend((data.len() as u32).to_le_bytes());
            chunks.extend(kind);
            chunks.extend(data);
        }
    }
    let mut out = b"glTF".to_vec();
    out.extend(2u32.to_le_bytes());
    out.extend(((12 + chunks.len()) as u32).to_le_bytes());
    out.extend(chunks);
    out
}

/// Parses bytes as the file `name`; external buffers cannot be read.
fn parse(bytes: &[u8], name: &str) -> Result<GltfScene, InputError> {
    parse_gltf(bytes, Path::new(name), &mut |relative| {
        Err(InputError::new(
            relative,
            "(file)",
            relative,
            "external buffers are not read here",
        ))
    })
}

/// A fresh folder for this process's files.
fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir()
        .join(format!("geometry-gltf-{}", std::process::id()))
        .join(name);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// `error` names `file` and an element containing `field`, and prints as one short line.
fn assert_names(error: &InputError, file: &Path, field: &str, what: &str) {
    assert_eq!(error.file, file, "{what}: {error}");
    assert!(
        error.field.contains(field),
        "{what}: field `{}` should name `{field}` ({error})",
        error.field
    );
    let text = error.to_string();
    assert!(
        !text.contains(['\n', '\r']) && text.chars().count() <= crate::error::MAX_MESSAGE_CHARS,
        "{what}: not one line of at most 200 characters: {text:?}"
    );
}

// ---------------------------------------------------------------------------------------------
// Valid documents

#[test]
fn a_quad_loads_from_glb_and_from_a_data_uri() {
    for (name, bytes) in [
        ("quad.glb", Doc::quad().glb()),
        ("quad.gltf", Doc::quad().embedded()),
    ] {
        let scene = parse(&bytes, name).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(scene.primitives.len(), 1, "{name}");
        let primitive = &scene.primitives[0];
        assert_eq!(primitive.element, "nodes[0].mesh → meshes[0].primitives[0]");
        assert_eq!(primitive.material, Some(0));
        assert_eq!(primitive.mesh.positions, QUAD.map(Vec3::from).to_vec());
        assert_eq!(primitive.mesh.indices, QUAD_TRIANGLES.to_vec());
        assert_eq!(primitive.mesh.normals, Some(vec![Vec3::Z; 4]));
        // glTF's defaults for what the material leaves out.
        let material = &scene.materials[0];
        assert_eq!(
            *material,
            GltfMaterial {
                name: Some("quad".into()),
                base_color: [1.0; 4],
                has_base_color_texture: false,
                ior: 1.5,
                emission: [0.0; 3],
                double_sided: false,
            }
        );
    }
}

/// A byte order mark before the JSON is skipped, in a `.gltf` and in a GLB's JSON chunk.
#[test]
fn a_byte_order_mark_is_skipped() {
    let mut text = b"\xEF\xBB\xBF".to_vec();
    text.extend(Doc::quad().embedded());
    assert_eq!(parse(&text, "bom.gltf").unwrap().primitives.len(), 1);
    let mut json = b"\xEF\xBB\xBF".to_vec();
    json.extend(Doc::quad().text());
    let glb = glb_bytes(&json, Some(&Doc::quad().bin));
    assert_eq!(parse(&glb, "bom.glb").unwrap().primitives.len(), 1);
}

#[test]
fn indices_of_every_unsigned_type_are_read() {
    for (component, bytes) in [
        (5121, vec![0u8, 1, 2, 0, 2, 3]),
        (
            5123,
            [0u16, 1, 2, 0, 2, 3]
                .iter()
                .flat_map(|i| i.to_le_bytes())
                .collect(),
        ),
        (
            5125,
            [0u32, 1, 2, 0, 2, 3]
                .iter()
                .flat_map(|i| i.to_le_bytes())
                .collect(),
        ),
    ] {
        let length = bytes.len();
        let doc = Doc::quad()
            .with("/accessors/2/componentType", &component.to_string())
            .with("/bufferViews/2/byteLength", &length.to_string())
            .with("/buffers/0/byteLength", &(96 + length).to_string())
            .with_bin(|bin| {
                bin.truncate(96);
                bin.extend(&bytes);
            });
        let scene = parse(&doc.glb(), "indices.glb").unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(
            scene.primitives[0].mesh.indices,
            QUAD_TRIANGLES.to_vec(),
            "componentType {component}"
        );
    }
}

#[test]
fn without_normal_or_indices() {
    let flat = Doc::quad().without("/meshes/0/primitives/0/attributes/NORMAL");
    let scene = parse(&flat.glb(), "flat.glb").unwrap();
    assert_eq!(scene.primitives[0].mesh.normals, None);
    // Non-indexed: three vertices, one triangle.
    let soup = Doc::quad()
        .without("/meshes/0/primitives/0/indices")
        .with("/accessors/0/count", "3")
        .with("/accessors/1/count", "3");
    let scene = parse(&soup.glb(), "soup.glb").unwrap();
    assert_eq!(scene.primitives[0].mesh.indices, vec![[0, 1, 2]]);
    assert_eq!(scene.primitives[0].mesh.positions.len(), 3);
}

/// Positions and normals interleaved in one view (byteStride 24); other attributes, unknown
/// used extensions and extension-less material extensions are ignored.
#[test]
fn interleaved_attributes_and_ignored_properties() {
    let mut bin = Vec::new();
    for p in QUAD {
        bin.extend(floats(&[p, [0.0, 0.0, 1.0]]));
    }
    bin.extend([0u16, 1, 2, 0, 2, 3].iter().flat_map(|i| i.to_le_bytes()));
    let doc = Doc { bin, ..Doc::quad() }
        .with("/bufferViews/0/byteLength", "96")
        .with("/bufferViews/0/byteStride", "24")
        .with("/accessors/1/bufferView", "0")
        .with("/accessors/1/byteOffset", "12")
        .with("/meshes/0/primitives/0/attributes/TEXCOORD_0", "1")
        .with("/meshes/0/primitives/0/attributes/_BATCHID", "1")
        .with(
            "/extensionsUsed",
            r#"["EXT_unknown", "KHR_materials_specular"]"#,
        )
        .with(
            "/materials/0/extensions",
            r#"{"KHR_materials_specular": {"specularFactor": 0.5}}"#,
        )
        .with(
            "/cameras",
            r#"[{"type": "perspective", "perspective": {"yfov": 1, "znear": 0.1}}]"#,
        )
        .with("/nodes/0/camera", "0");
    let scene = parse(&doc.embedded(), "interleaved.gltf").unwrap_or_else(|e| panic!("{e}"));
    let mesh = &scene.primitives[0].mesh;
    assert_eq!(mesh.positions, QUAD.map(Vec3::from).to_vec());
    assert_eq!(mesh.normals, Some(vec![Vec3::Z; 4]));
}

/// Nested nodes compose parent · child, each T·R·S; a matrix node is column-major.
#[test]
fn node_transforms_compose_from_the_root_down() {
    let doc = Doc::quad()
        .with(
            "/nodes/0",
            r#"{"translation": [10, 0, 0], "scale": [3, 3, 3], "children": [1]}"#,
        )
        .with(
            "/nodes/1",
            r#"{"mesh": 0, "translation": [0, 0, 1],
                "rotation": [0, 0, 0.70710678, 0.70710678], "scale": [2, 2, 2]}"#,
        );
    let scene = parse(&doc.glb(), "nested.glb").unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        scene.primitives[0].element,
        "nodes[1].mesh → meshes[0].primitives[0]"
    );
    // Vertex 1 = (1, 0, 0): child scale → (2, 0, 0), rotation 90° about z → (0, 2, 0),
    // translation → (0, 2, 1); parent scale → (0, 6, 3), translation → (10, 6, 3).
    let moved = scene.primitives[0].mesh.positions[1];
    assert!((moved - vec3(10.0, 6.0, 3.0)).length() < 1e-5, "{moved}");
    let expected = Mat4::from_scale_rotation_translation(
        Vec3::splat(3.0),
        Quat::IDENTITY,
        vec3(10.0, 0.0, 0.0),
    ) * Mat4::from_scale_rotation_translation(
        Vec3::splat(2.0),
        Quat::from_rotation_z(std::f32::consts::FRAC_PI_2),
        vec3(0.0, 0.0, 1.0),
    );
    assert!((expected.transform_point3(Vec3::X) - moved).length() < 1e-5);
    // The rotation turns the normals: +z stays +z.
    assert!(scene.primitives[0].mesh.normals.as_ref().unwrap()[0].abs_diff_eq(Vec3::Z, 1e-6));

    // A matrix: scale 2 in x, translation (1, 2, 3) in elements 12..15.
    let matrix = Doc::quad().with(
        "/nodes/0/matrix",
        "[2, 0, 0, 0,  0, 1, 0, 0,  0, 0, 1, 0,  1, 2, 3, 1]",
    );
    let scene = parse(&matrix.glb(), "matrix.glb").unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(scene.primitives[0].mesh.positions[2], vec3(3.0, 3.0, 3.0));
}

#[test]
fn a_mirroring_node_flips_the_winding() {
    let doc = Doc::quad().with("/nodes/0/scale", "[-1, 1, 1]");
    let scene = parse(&doc.glb(), "mirror.glb").unwrap();
    let mesh = &scene.primitives[0].mesh;
    assert_eq!(mesh.indices, vec![[0, 2, 1], [0, 3, 2]]);
    // The geometric normal keeps following the shading normal (+z).
    let [a, b, c] = mesh.triangle(0);
    assert!((b - a).cross(c - a).z > 0.0);
    assert_eq!(mesh.normals.as_ref().unwrap()[0], Vec3::Z);
}

/// Without scenes every root node is placed, with its children; a mesh placed twice is read twice.
#[test]
fn without_scenes_every_root_is_placed_and_meshes_are_instanced() {
    let doc = Doc::quad()
        .without("/scene")
        .without("/scenes")
        .with("/nodes/0/children", "[1]")
        .with("/nodes/1", r#"{"mesh": 0, "translation": [0, 0, 5]}"#)
        .with("/nodes/2", r#"{"mesh": 0, "translation": [0, 0, -5]}"#)
        .without("/meshes/0/primitives/0/material");
    let scene = parse(&doc.glb(), "roots.glb").unwrap();
    let placed: Vec<_> = scene
        .primitives
        .iter()
        .map(|p| p.element.as_str())
        .collect();
    assert_eq!(
        placed,
        [
            "nodes[0].mesh → meshes[0].primitives[0]",
            "nodes[1].mesh → meshes[0].primitives[0]",
            "nodes[2].mesh → meshes[0].primitives[0]",
        ]
    );
    assert_eq!(scene.primitives[1].mesh.positions[0], vec3(0.0, 0.0, 5.0));
    assert_eq!(scene.primitives[2].mesh.positions[0], vec3(0.0, 0.0, -5.0));
    assert!(scene.primitives.iter().all(|p| p.material.is_none()));
    let merged = scene.merged();
    assert_eq!((merged.positions.len(), merged.triangle_count()), (12, 6));
    assert_eq!(merged.indices[2], [4, 5, 6]);
}

/// `.glb` and `.gltf` load through `load_mesh`, merged; external buffers are read beside the file
/// (percent-decoded, in a subfolder or up through `..`).
#[test]
fn mesh_files_and_external_buffers() {
    let dir = temp_dir("external");
    assert_eq!(MeshFormat::of(Path::new("a.GLB")), Ok(MeshFormat::Glb));
    assert_eq!(MeshFormat::of(Path::new("a.gltf")), Ok(MeshFormat::Gltf));
    let glb = dir.join("quad.glb");
    std::fs::write(&glb, Doc::quad().glb()).unwrap();
    let mesh = load_mesh(&glb).unwrap();
    assert_eq!((mesh.positions.len(), mesh.triangle_count()), (4, 2));
    assert_eq!(mesh.normals.as_ref().map(Vec::len), Some(4));

    std::fs::create_dir_all(dir.join("data")).unwrap();
    std::fs::create_dir_all(dir.join("scene")).unwrap();
    for (uri, file) in [
        ("quad%20bytes.bin", "quad bytes.bin"),
        ("data/quad.bin", "data/quad.bin"),
        ("../data/quad.bin", "data/quad.bin"),
    ] {
        std::fs::write(dir.join(file), &Doc::quad().bin).unwrap();
        let folder = if uri.starts_with("..") { "scene" } else { "." };
        let gltf = dir.join(folder).join("quad.gltf");
        let doc = Doc::quad().with("/buffers/0/uri", &format!("{uri:?}"));
        std::fs::write(&gltf, doc.text()).unwrap();
        let scene = load_gltf(&gltf).unwrap_or_else(|e| panic!("{uri}: {e}"));
        assert_eq!(
            scene.primitives[0].mesh.indices,
            QUAD_TRIANGLES.to_vec(),
            "{uri}"
        );
        assert_eq!(load_mesh(&gltf).unwrap().triangle_count(), 2, "{uri}");
    }
}

// ---------------------------------------------------------------------------------------------
// Malformed documents

/// A document with one fault, as the bytes of a file, and the element its error must name.
struct Case {
    name: &'static str,
    /// A `.glb` (else a `.gltf`).
    glb: bool,
    bytes: Vec<u8>,
    field: &'static str,
}

impl Case {
    fn file(&self) -> &'static str {
        if self.glb { "case.glb" } else { "case.gltf" }
    }
}

fn glb_case(name: &'static str, doc: Doc, field: &'static str) -> Case {
    Case {
        name,
        glb: true,
        bytes: doc.glb(),
        field,
    }
}

fn gltf_case(name: &'static str, doc: Doc, field: &'static str) -> Case {
    Case {
        name,
        glb: false,
        bytes: doc.embedded(),
        field,
    }
}

/// A quad GLB with `edit` applied to its bytes.
fn raw_glb(name: &'static str, edit: impl FnOnce(&mut Vec<u8>), field: &'static str) -> Case {
    let mut bytes = Doc::quad().glb();
    edit(&mut bytes);
    Case {
        name,
        glb: true,
        bytes,
        field,
    }
}

/// A chain of `n` nodes, each the child of the one before; the last places the mesh.
fn chain(n: usize) -> Doc {
    let nodes: Vec<String> = (0..n)
        .map(|i| match i + 1 < n {
            true => format!(r#"{{"children": [{}]}}"#, i + 1),
            false => r#"{"mesh": 0}"#.to_string(),
        })
        .collect();
    Doc::quad().with("/nodes", &format!("[{}]", nodes.join(",")))
}

/// Every self-contained malformed variant (also written to the fuzz corpus).
fn malformed() -> Vec<Case> {
    let q = Doc::quad;
    // 33 nodes place a mesh of 2²⁰ triangles: 2²⁵ + 2²⁰ in all, over the limit at the 33rd.
    let instances: Vec<String> = (0..33).map(|_| r#"{"mesh": 0}"#.to_string()).collect();
    let roots: Vec<String> = (0..33).map(|i| i.to_string()).collect();
    vec![
        // Buffers, views, accessors.
        gltf_case(
            "truncated-data-uri",
            q().with_bin(|b| b.truncate(100)),
            "buffers[0].uri",
        ),
        glb_case(
            "truncated-bin",
            q().with_bin(|b| b.truncate(100)),
            "buffers[0].byteLength",
        ),
        glb_case(
            "accessor-past-view",
            q().with("/accessors/0/count", "5"),
            "accessors[0].count",
        ),
        glb_case(
            "accessor-offset-past-view",
            q().with("/accessors/0/byteOffset", "40"),
            "accessors[0].byteOffset",
        ),
        glb_case(
            "view-past-buffer",
            q().with("/bufferViews/2/byteLength", "20"),
            "bufferViews[2].byteLength",
        ),
        glb_case(
            "index-out-of-range",
            q().with_bin(|b| b[106] = 7),
            "accessors[2] (index 5)",
        ),
        glb_case(
            "position-component-type",
            q().with("/accessors/0/componentType", "5123"),
            "accessors[0].componentType",
        ),
        glb_case(
            "position-accessor-type",
            q().with("/accessors/0/type", r#""VEC4""#),
            "accessors[0].type",
        ),
        glb_case(
            "normal-accessor-type",
            q().with("/accessors/1/type", r#""VEC2""#),
            "accessors[1].type",
        ),
        glb_case(
            "index-component-type",
            q().with("/accessors/2/componentType", "5126"),
            "accessors[2].componentType",
        ),
        glb_case(
            "normalized-positions",
            q().with("/accessors/0/normalized", "true"),
            "accessors[0].normalized",
        ),
        glb_case(
            "sparse-accessor",
            q().with(
                "/accessors/0/sparse",
                r#"{"count": 1, "indices": {"bufferView": 2, "componentType": 5123},
                    "values": {"bufferView": 0}}"#,
            ),
            "accessors[0].sparse",
        ),
        glb_case(
            "mode-lines",
            q().with("/meshes/0/primitives/0/mode", "1"),
            "meshes[0].primitives[0].mode",
        ),
        glb_case(
            "absurd-count",
            q().with("/accessors/0/count", "4000000000")
                .with("/bufferViews/0/byteLength", "12")
                .with("/buffers/0/byteLength", "12")
                .with_bin(|b| b.truncate(12)),
            "nodes[0].mesh → meshes[0].primitives[0]",
        ),
        glb_case(
            "count-past-bytes",
            q().with("/accessors/0/count", "1000000"),
            "accessors[0].count",
        ),
        glb_case(
            "instancing-over-the-limit",
            q().with("/accessors/2/count", &(3 << 20).to_string())
                .with("/nodes", &format!("[{}]", instances.join(",")))
                .with("/scenes/0/nodes", &format!("[{}]", roots.join(","))),
            "nodes[32].mesh → meshes[0].primitives[0]",
        ),
        glb_case(
            "stride-below-element",
            q().with("/bufferViews/0/byteStride", "8"),
            "bufferViews[0].byteStride",
        ),
        glb_case(
            "normal-count",
            q().with("/accessors/1/count", "3"),
            "accessors[1].count",
        ),
        glb_case(
            "non-indexed-count",
            q().without("/meshes/0/primitives/0/indices"),
            "accessors[0].count",
        ),
        glb_case(
            "nan-position",
            q().with_bin(|b| b[12..16].copy_from_slice(&f32::NAN.to_le_bytes())),
            "accessors[0] (vertex 1)",
        ),
        glb_case(
            "nan-normal",
            q().with_bin(|b| b[48..52].copy_from_slice(&f32::INFINITY.to_le_bytes())),
            "accessors[1] (vertex 0)",
        ),
        glb_case(
            "placed-position-out-of-range",
            q().with("/nodes/0/scale", "[1e8, 1, 1]"),
            "nodes[0].mesh → meshes[0].primitives[0] (vertex 1)",
        ),
        glb_case(
            "position-index-missing",
            q().with("/meshes/0/primitives/0/attributes/POSITION", "9"),
            r#"meshes[0].primitives[0].attributes["POSITION"]"#,
        ),
        glb_case(
            "buffer-view-missing",
            q().with("/accessors/1/bufferView", "9"),
            "accessors[1].bufferView",
        ),
        glb_case(
            "buffer-missing",
            q().with("/bufferViews/1/buffer", "3"),
            "bufferViews[1].buffer",
        ),
        glb_case(
            "invalid-component-type",
            q().with("/accessors/2/componentType", "1234"),
            "accessors[2].componentType",
        ),
        glb_case(
            "accessor-without-view",
            q().without("/accessors/1/bufferView"),
            "accessors[1].bufferView",
        ),
        // Nodes and scenes.
        glb_case(
            "node-cycle",
            q().with("/nodes/0/children", "[1]")
                .with("/nodes/1", r#"{"children": [0]}"#),
            "nodes[0].children[0]",
        ),
        glb_case(
            "node-own-child",
            q().with("/nodes/0/children", "[0]"),
            "nodes[0].children[0]",
        ),
        glb_case(
            "node-two-parents",
            q().with("/nodes/0/children", "[2]")
                .with("/nodes/1", r#"{"children": [2]}"#)
                .with("/nodes/2", r#"{"mesh": 0}"#)
                .with("/scenes/0/nodes", "[0, 1]"),
            "nodes[1].children[0]",
        ),
        glb_case("node-too-deep", chain(70), "nodes[64]"),
        glb_case(
            "scene-lists-a-child",
            q().with("/nodes/0/children", "[1]")
                .with("/nodes/1", r#"{"mesh": 0}"#)
                .with("/scenes/0/nodes", "[0, 1]"),
            "scenes[0].nodes[1]",
        ),
        glb_case(
            "scene-lists-a-node-twice",
            q().with("/scenes/0/nodes", "[0, 0]"),
            "scenes[0].nodes[1]",
        ),
        glb_case(
            "matrix-not-affine",
            q().with(
                "/nodes/0/matrix",
                "[1, 0, 0, 1,  0, 1, 0, 0,  0, 0, 1, 0,  0, 0, 0, 1]",
            ),
            "nodes[0].matrix",
        ),
        glb_case(
            "matrix-singular",
            q().with(
                "/nodes/0/matrix",
                "[1, 0, 0, 0,  2, 0, 0, 0,  0, 0, 1, 0,  0, 0, 0, 1]",
            ),
            "nodes[0].matrix",
        ),
        glb_case(
            "matrix-and-trs",
            q().with(
                "/nodes/0/matrix",
                "[1, 0, 0, 0,  0, 1, 0, 0,  0, 0, 1, 0,  0, 0, 0, 1]",
            )
            .with("/nodes/0/translation", "[1, 0, 0]"),
            "nodes[0].matrix",
        ),
        glb_case(
            "scale-zero",
            q().with("/nodes/0/scale", "[1, 0, 1]"),
            "nodes[0].scale",
        ),
        glb_case(
            "rotation-not-unit",
            q().with("/nodes/0/rotation", "[0, 0, 0, 2]"),
            "nodes[0].rotation",
        ),
        // Document.
        glb_case(
            "extension-required",
            q().with("/extensionsRequired", r#"["KHR_draco_mesh_compression"]"#),
            "extensionsRequired[0]",
        ),
        glb_case(
            "asset-version-1",
            q().with("/asset/version", r#""1.0""#),
            "asset.version",
        ),
        glb_case(
            "emission-negative",
            q().with("/materials/0/emissiveFactor", "[-1, 0, 0]"),
            "materials[0].emissiveFactor",
        ),
        glb_case(
            "ior-below-one",
            q().with(
                "/materials/0/extensions",
                r#"{"KHR_materials_ior": {"ior": 0.5}}"#,
            ),
            "materials[0].extensions.KHR_materials_ior.ior",
        ),
        Case {
            name: "malformed-json",
            glb: false,
            bytes: b"{\n  \"asset\": {\"version\": \"2.0\"},\n  \"nodes\": [{\"mesh\": 0,, }]\n}\n"
                .to_vec(),
            field: "line 3, column",
        },
        Case {
            name: "json-not-an-object",
            glb: false,
            bytes: b"[1, 2, 3]".to_vec(),
            field: "line 1, column",
        },
        // URIs.
        gltf_case(
            "data-uri-bad-base64",
            q().with(
                "/buffers/0/uri",
                r#""data:application/octet-stream;base64,AAAA@@@@""#,
            ),
            "buffers[0].uri",
        ),
        gltf_case(
            "data-uri-not-base64",
            q().with("/buffers/0/uri", r#""data:application/octet-stream,abc""#),
            "buffers[0].uri",
        ),
        gltf_case(
            "uri-http",
            q().with("/buffers/0/uri", r#""http://example.invalid/quad.bin""#),
            "buffers[0].uri",
        ),
        gltf_case(
            "uri-absolute",
            q().with("/buffers/0/uri", r#""/tmp/quad.bin""#),
            "buffers[0].uri",
        ),
        gltf_case(
            "uri-bad-percent",
            q().with("/buffers/0/uri", r#""quad%2.bin""#),
            "buffers[0].uri",
        ),
        Case {
            name: "buffer-without-uri",
            glb: false,
            bytes: Doc::quad().text(),
            field: "buffers[0].uri",
        },
        // The GLB container.
        raw_glb("glb-magic", |b| b[3] = b'X', "GLB header.magic"),
        raw_glb("glb-version", |b| b[4] = 1, "GLB header.version"),
        raw_glb("glb-length", |b| b[8] ^= 4, "GLB header.length"),
        raw_glb("glb-short-header", |b| b.truncate(9), "GLB header"),
        raw_glb(
            "glb-first-chunk-bin",
            |b| b[16..20].copy_from_slice(b"BIN\0"),
            "GLB chunk[0].type",
        ),
        raw_glb(
            "glb-truncated-chunk",
            |b| {
                let json = u32::from_le_bytes([b[12], b[13], b[14], b[15]]) as usize;
                let at = 20 + json;
                b[at..at + 4].copy_from_slice(&1000u32.to_le_bytes());
            },
            "GLB chunk[1].length",
        ),
        raw_glb(
            "glb-truncated-chunk-header",
            |b| {
                b.extend([1, 2, 3, 4]);
                let length = b.len() as u32;
                b[8..12].copy_from_slice(&length.to_le_bytes());
            },
            "GLB chunk[2]",
        ),
        Case {
            name: "glb-without-bin",
            glb: true,
            bytes: glb_bytes(&Doc::quad().text(), None),
            field: "buffers[0].uri",
        },
    ]
}

#[test]
fn malformed_documents_are_one_input_error_each() {
    let cases = malformed();
    assert!(cases.len() >= 40, "{} cases", cases.len());
    for case in &cases {
        let error = match parse(&case.bytes, case.file()) {
            Ok(_) => panic!("{}: must be rejected", case.name),
            Err(error) => error,
        };
        assert_names(&error, Path::new(case.file()), case.field, case.name);
    }
}

/// The values that show the fault are in the error.
#[test]
fn errors_show_the_value() {
    let value = |name: &str| {
        let case = malformed().into_iter().find(|c| c.name == name).unwrap();
        parse(&case.bytes, case.file()).unwrap_err()
    };
    let absurd = value("absurd-count");
    assert!(absurd.value.contains("4000000000"), "{absurd}");
    assert!(absurd.reason.contains("limit"), "{absurd}");
    assert_eq!(value("index-out-of-range").value, "7");
    assert_eq!(value("buffer-view-missing").value, "9");
    assert_eq!(value("invalid-component-type").value, "1234");
    assert_eq!(
        value("extension-required").value,
        "KHR_draco_mesh_compression"
    );
    let json = value("malformed-json");
    assert!(json.value.contains(",,"), "{json}");
    assert!(value("uri-http").reason.contains("http:"));
}

/// 1 025 nodes place a mesh of 1 024 empty primitives: 2²⁰ + 1 024 in all, refused at the first
/// over the limit before anything is read.
#[test]
fn placed_primitives_are_limited() {
    let primitive = r#"{"attributes": {"POSITION": 0}, "indices": 2}"#;
    let primitives = vec![primitive; 1024].join(",");
    let nodes = vec![r#"{"mesh": 0}"#; 1025].join(",");
    let roots: Vec<String> = (0..1025).map(|i| i.to_string()).collect();
    let doc = Doc::quad()
        .with("/meshes/0/primitives", &format!("[{primitives}]"))
        .with("/nodes", &format!("[{nodes}]"))
        .with("/scenes/0/nodes", &format!("[{}]", roots.join(",")));
    let error = parse(&doc.glb(), "many.glb").unwrap_err();
    assert_names(
        &error,
        Path::new("many.glb"),
        "nodes[1024].mesh → meshes[0].primitives[0]",
        "primitives",
    );
    assert!(error.reason.contains("1048576 primitives"), "{error}");
}

/// Missing and short buffer files name the glTF file and `buffers[0].uri`, with the uri.
#[test]
fn missing_or_short_buffer_files() {
    let dir = temp_dir("missing");
    let gltf = dir.join("quad.gltf");
    std::fs::write(
        &gltf,
        Doc::quad().with("/buffers/0/uri", r#""absent.bin""#).text(),
    )
    .unwrap();
    let error = load_gltf(&gltf).unwrap_err();
    assert_names(&error, &gltf, "buffers[0].uri", "missing file");
    assert_eq!(error.value, "absent.bin");
    assert!(error.reason.contains("absent.bin"), "{error}");

    std::fs::write(dir.join("short.bin"), &Doc::quad().bin[..50]).unwrap();
    std::fs::write(
        &gltf,
        Doc::quad().with("/buffers/0/uri", r#""short.bin""#).text(),
    )
    .unwrap();
    let error = load_mesh(&gltf).unwrap_err();
    assert_names(&error, &gltf, "buffers[0].uri", "short file");
    assert!(error.reason.contains("50 bytes"), "{error}");
}

// ---------------------------------------------------------------------------------------------
// Documentation, fuzz corpus, shared assets

#[test]
fn the_gltf_limits_are_documented() {
    let doc = include_str!("../../../../docs/scene-format.md");
    for row in [
        format!("| `MAX_GLTF_NODE_DEPTH` | `{MAX_GLTF_NODE_DEPTH}` |"),
        format!("| `MAX_GLTF_PRIMITIVES` | `{MAX_GLTF_PRIMITIVES}` |"),
    ] {
        assert!(doc.contains(&row), "docs/scene-format.md lacks {row:?}");
    }
}

/// Writes the malformed variants and a few valid seeds to `fuzz/corpus/gltf/`:
/// `cargo test -p geometry --release -- --ignored write_fuzz_corpus`.
#[test]
#[ignore = "writes fuzz/corpus/gltf"]
fn write_fuzz_corpus() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../fuzz/corpus/gltf");
    std::fs::create_dir_all(&dir).unwrap();
    for case in malformed() {
        let extension = if case.glb { "glb" } else { "gltf" };
        let file = dir.join(format!("regress-{}.{extension}", case.name));
        std::fs::write(file, &case.bytes).unwrap();
    }
    let triangle = Doc::quad()
        .without("/meshes/0/primitives/0/indices")
        .without("/meshes/0/primitives/0/attributes/NORMAL")
        .with("/accessors/0/count", "3");
    let nested = Doc::quad()
        .with(
            "/nodes/0",
            r#"{"rotation": [0, 0, 0.70710678, 0.70710678], "children": [1]}"#,
        )
        .with(
            "/nodes/1",
            r#"{"mesh": 0, "matrix": [2, 0, 0, 0,  0, 1, 0, 0,  0, 0, 1, 0,  1, 2, 3, 1]}"#,
        );
    for (name, bytes) in [
        ("seed-quad.glb", Doc::quad().glb()),
        ("seed-quad.gltf", Doc::quad().embedded()),
        ("seed-triangle.gltf", triangle.embedded()),
        ("seed-nested.glb", nested.glb()),
    ] {
        std::fs::write(dir.join(name), bytes).unwrap();
    }
}

/// Paper 001's assets (shared/assets/restir-sss), read in place; skipped with a note where they
/// are absent, unless RESHIFT_REQUIRE_ASSETS=1.
fn assets() -> Option<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/assets/restir-sss");
    if dir.is_dir() {
        return Some(dir);
    }
    let why = format!("{} is missing", dir.display());
    assert!(
        std::env::var("RESHIFT_REQUIRE_ASSETS").as_deref() != Ok("1"),
        "RESHIFT_REQUIRE_ASSETS=1: {why}"
    );
    eprintln!("skipping the shared glTF assets: {why}");
    None
}

/// The bounds of the POSITION accessor's `min`/`max` box placed by node 0's TRS, read from the
/// file's JSON independently of the loader.
fn expected_bounds(file: &Path) -> (Vec3, Vec3) {
    let text = std::fs::read(file).unwrap();
    let root: Value = json::deserialize::from_slice(&text).unwrap();
    let vector = |v: &Value| -> Vec<f32> {
        v.as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap() as f32)
            .collect()
    };
    let node = &root["nodes"][0];
    let or = |key: &str, default: Vec<f32>| node.get(key).map_or(default, vector);
    let t = or("translation", vec![0.0; 3]);
    let r = or("rotation", vec![0.0, 0.0, 0.0, 1.0]);
    let s = or("scale", vec![1.0; 3]);
    let xf = Mat4::from_scale_rotation_translation(
        vec3(s[0], s[1], s[2]),
        Quat::from_xyzw(r[0], r[1], r[2], r[3]).normalize(),
        vec3(t[0], t[1], t[2]),
    );
    let position = root["meshes"][0]["primitives"][0]["attributes"]["POSITION"]
        .as_u64()
        .unwrap() as usize;
    let accessor = &root["accessors"][position];
    let (lo, hi) = (vector(&accessor["min"]), vector(&accessor["max"]));
    (0..8).fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(a, b), corner| {
        let pick = |axis: usize| match corner >> axis & 1 {
            0 => lo[axis],
            _ => hi[axis],
        };
        let p = xf.transform_point3(vec3(pick(0), pick(1), pick(2)));
        (a.min(p), b.max(p))
    })
}

fn assert_bounds(mesh: &TriangleMesh, file: &Path) {
    let (lo, hi) = mesh.bounds();
    let (want_lo, want_hi) = expected_bounds(file);
    assert!(
        lo.abs_diff_eq(want_lo, 1e-3) && hi.abs_diff_eq(want_hi, 1e-3),
        "{}: bounds {lo}..{hi}, expected {want_lo}..{want_hi}",
        file.display()
    );
}

#[test]
fn paper_assets_load() {
    let Some(dir) = assets() else {
        return;
    };
    let ajax = dir.join("ajax/ajax.gltf");
    let scene = load_gltf(&ajax).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(scene.primitives.len(), 1);
    let mesh = &scene.primitives[0].mesh;
    assert_eq!(
        (mesh.positions.len(), mesh.triangle_count()),
        (55_189, 60_000)
    );
    assert_eq!(mesh.normals.as_ref().map(Vec::len), Some(55_189));
    let material = &scene.materials[scene.primitives[0].material.unwrap()];
    assert_eq!(material.name.as_deref(), Some("ajax"));
    assert_eq!(material.ior, 1.45f32);
    assert!(material.double_sided);
    // 90° about x: x stays, y = −(file z), z = file y.
    assert_bounds(mesh, &ajax);
    let (lo, hi) = mesh.bounds();
    for (axis, extent) in [(0, 11.6), (1, 18.1), (2, 9.1)] {
        assert!((hi[axis] - extent).abs() < 0.05 && (lo[axis] + extent).abs() < 0.05);
    }

    let background = dir.join("background/background.gltf");
    let scene = load_gltf(&background).unwrap_or_else(|e| panic!("{e}"));
    let mesh = &scene.primitives[0].mesh;
    assert_eq!(
        (mesh.positions.len(), mesh.triangle_count()),
        (1_681, 3_200)
    );
    assert!(scene.materials[0].has_base_color_texture);
    assert_bounds(mesh, &background);

    for (name, emission, textured) in [
        ("plane_emissive.gltf", [16.5, 0.0, 16.5], false),
        ("plane.gltf", [0.0; 3], true),
    ] {
        let plane = dir.join("plane").join(name);
        let scene = load_gltf(&plane).unwrap_or_else(|e| panic!("{e}"));
        let mesh = &scene.primitives[0].mesh;
        assert_eq!(
            (mesh.positions.len(), mesh.triangle_count()),
            (4, 2),
            "{name}"
        );
        let mut corners: Vec<[f32; 3]> = mesh.positions.iter().map(|p| p.to_array()).collect();
        corners.sort_by(|a, b| a.partial_cmp(b).unwrap());
        assert_eq!(
            corners,
            [
                [-1.0, 0.0, -1.0],
                [-1.0, 0.0, 1.0],
                [1.0, 0.0, -1.0],
                [1.0, 0.0, 1.0]
            ],
            "{name}"
        );
        let material = &scene.materials[0];
        assert_eq!(material.emission, emission, "{name}");
        assert_eq!(material.has_base_color_texture, textured, "{name}");
        assert!(material.double_sided, "{name}");
        assert_bounds(mesh, &plane);
    }
}
