//! The bodies of the fuzz targets, one per input loader, shared by the libFuzzer binaries in
//! `fuzz/fuzz_targets/` and by the corpus replay test `sss/tests/fuzz_corpus.rs` (which includes
//! this file). Each feeds bytes to a loader and panics if the loader panics, or if it fails with
//! an error that is not one line of at most `sss::error::MAX_MESSAGE_CHARS` characters.

use std::path::Path;

use geometry::load::gltf::parse_gltf;
use geometry::load::{MeshFormat, parse_mesh};
use sss::InputError;
use sss::error::MAX_MESSAGE_CHARS;
use sss::integrator::Reference;
use sss::scene::Scene;

/// Every target by name (the name of its corpus folder `fuzz/corpus/<name>`).
pub const TARGETS: [(&str, fn(&[u8])); 6] = [
    ("scene_toml", scene_toml),
    ("obj", obj),
    ("ply", ply),
    ("gltf", gltf),
    ("checkpoint", checkpoint),
    ("merge", merge),
];

/// Panics unless `result` is `Ok` or an error of one line of at most [`MAX_MESSAGE_CHARS`].
fn check<T>(result: Result<T, InputError>) -> Option<T> {
    match result {
        Ok(value) => Some(value),
        Err(error) => {
            let message = error.to_string();
            assert!(
                !message.contains(['\n', '\r']) && message.chars().count() <= MAX_MESSAGE_CHARS,
                "not one line of at most {MAX_MESSAGE_CHARS} characters: {message:?}"
            );
            None
        }
    }
}

/// A scene file (UTF-8 text); mesh paths resolve in a folder that does not exist.
pub fn scene_toml(data: &[u8]) {
    if let Ok(text) = std::str::from_utf8(data) {
        check(Scene::from_toml_str(
            text,
            Path::new("/nonexistent/reshift-fuzz/scene.toml"),
        ));
    }
}

/// An OBJ mesh.
pub fn obj(data: &[u8]) {
    check(parse_mesh(data, Path::new("fuzz.obj"), MeshFormat::Obj));
}

/// A PLY mesh.
pub fn ply(data: &[u8]) {
    check(parse_mesh(data, Path::new("fuzz.ply"), MeshFormat::Ply));
}

/// A glTF file: a `.glb` if it starts with the GLB magic `glTF`, else `.gltf` JSON. External
/// buffers cannot be read (only the GLB BIN chunk and `data:` URIs); every placed primitive must
/// index its own vertices.
pub fn gltf(data: &[u8]) {
    let name = if data.starts_with(b"glTF") {
        "fuzz.glb"
    } else {
        "fuzz.gltf"
    };
    let mut no_files = |_: &str| Err(InputError::new(name, "(file)", "", "not read when fuzzing"));
    if let Some(scene) = check(parse_gltf(data, Path::new(name), &mut no_files)) {
        for primitive in &scene.primitives {
            let vertices = primitive.mesh.positions.len();
            assert!(
                primitive
                    .mesh
                    .indices
                    .iter()
                    .flatten()
                    .all(|&i| (i as usize) < vertices)
            );
        }
        scene.merged();
    }
}

/// A reference checkpoint; one that loads must be written back to the same bytes, and its mean
/// and standard error must be computable.
pub fn checkpoint(data: &[u8]) {
    if let Some(reference) = check(Reference::from_bytes(data, Path::new("fuzz.rsref"))) {
        assert!(
            reference.to_bytes() == data,
            "a checkpoint does not round-trip"
        );
        assert_eq!(reference.mean().len(), reference.std_err().len());
    }
}

/// Two reference checkpoints, merged: the first 4 bytes (little-endian) split the rest.
pub fn merge(data: &[u8]) {
    let Some((split, rest)) = data.split_first_chunk::<4>() else {
        return;
    };
    let at = u32::from_le_bytes(*split) as usize % (rest.len() + 1);
    let (a, b) = rest.split_at(at);
    let load = |bytes, name: &str| {
        let path = Path::new(name).to_path_buf();
        check(Reference::from_bytes(bytes, &path)).map(|r| (path, r))
    };
    if let (Some(a), Some(b)) = (load(a, "a.rsref"), load(b, "b.rsref")) {
        check(Reference::merge(vec![a, b]));
    }
}
