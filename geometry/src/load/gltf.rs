//! glTF 2.0: `.gltf` (JSON; its buffers in files beside it or in base64 `data:` URIs) and `.glb`
//! (the binary container: a JSON chunk, then the BIN chunk that buffer 0 may name), read within
//! the limits of [`crate::limits`]. The `gltf` crate's document model parses and validates the
//! JSON; this module reads the files, the buffers and the accessors itself, each range checked
//! against the bytes that back it before anything is read or allocated.
//!
//! **Read.** The default scene (`scene`, else `scenes[0]`; a file without scenes places every root
//! node, i.e. every node that is no node's child) and its node hierarchy: each node's `matrix` or
//! `translation`, `rotation` and `scale` (M = T·R·S), composed from the scene's root down (glTF 2.0
//! §3.5.3). Of every placed mesh, its primitives of mode TRIANGLES: `POSITION` (FLOAT VEC3,
//! required), `NORMAL` (FLOAT VEC3, optional: flat shading without) and `indices` (unsigned byte,
//! short or int, optional). Materials: `baseColorFactor`, whether a base-colour texture is set,
//! `emissiveFactor` × `KHR_materials_emissive_strength`, `KHR_materials_ior`, `doubleSided`. A
//! mesh that several nodes place is read once per node (instancing).
//!
//! **Ignored without error.** Other attributes (`TEXCOORD_n`, `TANGENT`, `COLOR_n`, `JOINTS_n`,
//! `WEIGHTS_n`, application-specific `_NAME`), textures, images, samplers, cameras, skins (a
//! skinned mesh is placed by its node's transform, in its bind pose), animations, morph targets,
//! and extensions that are used but not required. Alignment (§3.6.2.4) is not required: elements
//! are read byte by byte.
//!
//! **Refused**, each with one [`InputError`] naming the file, the JSON path of the element and the
//! value: malformed JSON (`line 4, column 8`), what the `gltf` crate's validation refuses (its
//! path, e.g. `accessors[0].bufferView`), a `.glb` with a bad header, length or chunk, `asset.version`
//! other than 2.x, `extensionsRequired` other than the two material extensions above, primitive
//! modes other than TRIANGLES, sparse accessors, accessors without a buffer view, a component type
//! or accessor type an attribute or the indices may not have, normalized (quantized) positions, a
//! buffer shorter than its `byteLength` (a missing or short buffer file names the glTF file and
//! `buffers[i].uri`), a buffer view past its buffer's end, an accessor past its view's end (with
//! `byteStride` honoured and at least the element's size), an index at or past the vertex count, a
//! non-indexed primitive whose vertex count is not a multiple of 3, non-finite positions or
//! normals, a placed position outside [`crate::limits::MAX_COORDINATE`], a node with two parents,
//! a cycle, a node nested deeper than [`MAX_GLTF_NODE_DEPTH`], a scene that lists a child node or
//! a node twice, a node with both `matrix` and TRS, a `matrix` that is not affine (last row
//! 0, 0, 0, 1), not finite or singular, a non-finite, non-unit rotation or zero scale, and
//! material factors that are negative or not finite.
//!
//! **URIs** (§2.8): a buffer's `uri` is a base64 `data:` URI or a relative path, percent-decoded,
//! resolved against the glTF file's folder; `..` may leave that folder, as a scene file's mesh paths
//! may. Other schemes (`http:`, `file:`), absolute paths, queries and fragments are refused.
//!
//! **Limits.** The glTF or GLB file and each external buffer: [`MAX_MESH_FILE_BYTES`]. The placed
//! primitives, and their vertices and triangles together, instances included:
//! [`MAX_GLTF_PRIMITIVES`], [`MAX_MESH_VERTICES`] and [`MAX_MESH_TRIANGLES`], checked on the
//! accessors' counts before any is read; every count is also checked against the bytes of its
//! buffer view before its elements are allocated. Node depth: [`MAX_GLTF_NODE_DEPTH`].

mod buffers;
mod document;
mod nodes;
mod primitives;
#[cfg(test)]
mod tests;

use std::path::Path;

use ::gltf::json;
use json::mesh::Semantic;
use json::validation::Checked;

use super::super::mesh::TriangleMesh;
use crate::InputError;
use crate::limits::{MAX_MESH_FILE_BYTES, read_file};
use buffers::Buffers;
use primitives::Reader;

/// One material as the file gives it (glTF's defaults where a property is absent).
#[derive(Clone, Debug, PartialEq)]
pub struct GltfMaterial {
    /// `name`.
    pub name: Option<String>,
    /// `pbrMetallicRoughness.baseColorFactor`, linear RGBA (default 1, 1, 1, 1).
    pub base_color: [f32; 4],
    /// Whether `pbrMetallicRoughness.baseColorTexture` is set: textures are not read, the caller
    /// decides what a textured base colour becomes.
    pub has_base_color_texture: bool,
    /// `KHR_materials_ior` (default 1.5): 0 or at least 1.
    pub ior: f32,
    /// `emissiveFactor` × `KHR_materials_emissive_strength` (default strength 1), linear RGB.
    pub emission: [f32; 3],
    /// `doubleSided` (default false).
    pub double_sided: bool,
}

/// One triangle primitive placed in the file's scene space: the transforms of every node on the
/// path from the scene's root applied.
#[derive(Clone, Debug, PartialEq)]
pub struct GltfPrimitive {
    /// Positions, triangles, and normals iff the primitive has `NORMAL` (through the inverse
    /// transpose and renormalised; a mirroring node flips the winding, as
    /// [`TriangleMesh::transformed`] does).
    pub mesh: TriangleMesh,
    /// Index into [`GltfScene::materials`]; `None` = glTF's default material (§3.9.6).
    pub material: Option<usize>,
    /// The JSON path that places it, for messages: `nodes[0].mesh → meshes[0].primitives[0]`.
    pub element: String,
}

/// What a glTF file's default scene holds.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GltfScene {
    /// Every material of the file, in file order (whether placed or not).
    pub materials: Vec<GltfMaterial>,
    /// The placed triangle primitives, in node order (depth first from the scene's roots).
    pub primitives: Vec<GltfPrimitive>,
}

impl GltfScene {
    /// All primitives as one mesh ([`TriangleMesh::merged`]); normals only if every primitive
    /// has them.
    pub fn merged(&self) -> TriangleMesh {
        TriangleMesh::merged(self.primitives.iter().map(|p| &p.mesh))
    }
}

/// Reads a `.gltf` or `.glb` file; external buffers are read from the file's folder.
pub fn load_gltf(path: &Path) -> Result<GltfScene, InputError> {
    let bytes = read_file(path, MAX_MESH_FILE_BYTES)?;
    parse_gltf(&bytes, path, &mut |relative| read_beside(path, relative))
}

/// Parses the bytes of a glTF file (GLB when they start with the magic `glTF`, which a path
/// ending in `.glb` requires; JSON otherwise). `path` names the file in errors. `resolve` returns
/// the bytes of an external buffer given its `uri` as a relative path, already checked and
/// percent-decoded, or an error whose `reason` says why (it is reported under `path` and
/// `buffers[i].uri`). `data:` URIs and the GLB BIN chunk never reach it.
pub fn parse_gltf(
    bytes: &[u8],
    path: &Path,
    resolve: &mut dyn FnMut(&str) -> Result<Vec<u8>, InputError>,
) -> Result<GltfScene, InputError> {
    let container = document::container(bytes, path)?;
    let root = document::parse(container.json, path)?;
    document::check(&root, container.json, path)?;
    let materials = root
        .materials
        .iter()
        .enumerate()
        .map(|(i, m)| material(m, i, path))
        .collect::<Result<Vec<_>, _>>()?;
    let parents = nodes::hierarchy(&root, path)?;
    let roots = nodes::scene_roots(&root, &parents, path)?;
    let placements = nodes::placements(&root, &roots, path)?;
    nodes::check_totals(&root, &placements, path)?;
    let buffers = Buffers::new(&root, path, container.bin, resolve);
    let mut reader = Reader::new(&root, path, buffers);
    let mut primitives = Vec::new();
    for (node, world) in &placements {
        reader.place(*node, world, &mut primitives)?;
    }
    Ok(GltfScene {
        materials,
        primitives,
    })
}

/// The bytes of the external buffer `relative` beside the glTF file `gltf`; the error's reason
/// names the buffer file.
pub(super) fn read_beside(gltf: &Path, relative: &str) -> Result<Vec<u8>, InputError> {
    let file = gltf.parent().unwrap_or(Path::new("")).join(relative);
    read_file(&file, MAX_MESH_FILE_BYTES).map_err(|e| {
        let shown = file.display().to_string();
        let why = if e.value == shown {
            e.reason.clone()
        } else {
            format!("{} ({})", e.reason, e.value)
        };
        InputError::new(&file, e.field, e.value, format!("{shown}: {why}"))
    })
}

// ---------------------------------------------------------------------------------------------
// Materials

/// A material's factors (glTF 2.0 §3.9.2, §3.9.5; KHR_materials_ior,
/// KHR_materials_emissive_strength).
fn material(m: &json::Material, i: usize, path: &Path) -> Result<GltfMaterial, InputError> {
    let at = |field: &str| format!("materials[{i}].{field}");
    let base_color = m.pbr_metallic_roughness.base_color_factor.0;
    non_negative(&base_color, path, || {
        at("pbrMetallicRoughness.baseColorFactor")
    })?;
    let factor = m.emissive_factor.0;
    non_negative(&factor, path, || at("emissiveFactor"))?;
    let extensions = m.extensions.as_ref();
    let strength = extensions
        .and_then(|e| e.emissive_strength.as_ref())
        .map_or(1.0, |s| s.emissive_strength.0);
    non_negative(&[strength], path, || {
        at("extensions.KHR_materials_emissive_strength.emissiveStrength")
    })?;
    let emission = factor.map(|f| f * strength);
    non_negative(&emission, path, || {
        at("emissiveFactor (× emissiveStrength)")
    })?;
    let ior = extensions
        .and_then(|e| e.ior.as_ref())
        .map_or(1.5, |x| x.ior.0);
    if !(ior.is_finite() && (ior == 0.0 || ior >= 1.0)) {
        return Err(InputError::new(
            path,
            at("extensions.KHR_materials_ior.ior"),
            ior.to_string(),
            "an index of refraction is 0 or at least 1, and finite",
        ));
    }
    Ok(GltfMaterial {
        name: m.name.clone(),
        base_color,
        has_base_color_texture: m.pbr_metallic_roughness.base_color_texture.is_some(),
        ior,
        emission,
        double_sided: m.double_sided,
    })
}

/// Every value finite and ≥ 0, or an error at `field`.
fn non_negative(
    values: &[f32],
    path: &Path,
    field: impl FnOnce() -> String,
) -> Result<(), InputError> {
    if values.iter().all(|v| v.is_finite() && *v >= 0.0) {
        Ok(())
    } else {
        Err(InputError::new(
            path,
            field(),
            format!("{values:?}"),
            "material factors must be finite and non-negative",
        ))
    }
}

// ---------------------------------------------------------------------------------------------
// Shared by the submodules

/// The accessor a primitive names for `semantic`.
fn attribute(primitive: &json::mesh::Primitive, semantic: Semantic) -> Option<usize> {
    primitive
        .attributes
        .get(&Checked::Valid(semantic))
        .map(|a| a.value())
}

/// `list[index]`, or an error at `field` (the document model's validation makes this rare).
fn item<'a, T>(
    list: &'a [T],
    index: usize,
    path: &Path,
    field: impl FnOnce() -> String,
) -> Result<&'a T, InputError> {
    list.get(index).ok_or_else(|| {
        InputError::new(
            path,
            field(),
            index.to_string(),
            format!("no such item (the file has {})", list.len()),
        )
    })
}
