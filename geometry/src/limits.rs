//! Limits on the meshes read from files (docs/scene-format.md, "Limits"), and the bounded file
//! reading and byte formatting every loader of the workspace shares.
//!
//! No size from a mesh file is trusted before allocating: its bytes, vertex and triangle counts
//! and coordinates are each checked against a documented limit, with a one-line [`InputError`]
//! naming the file, the element and the value.

use std::io::Read;
use std::path::Path;

use crate::InputError;

/// Largest mesh file (OBJ, PLY, glTF or GLB), and largest external glTF buffer, in bytes.
pub const MAX_MESH_FILE_BYTES: u64 = 1 << 31;
/// Most vertices of one mesh file (of a glTF file: of all its placed primitives together).
pub const MAX_MESH_VERTICES: u64 = 1 << 25;
/// Most triangles of one mesh file (after fan and strip triangulation; of a glTF file: of all its
/// placed primitives together, a mesh placed by several nodes counted once per node).
pub const MAX_MESH_TRIANGLES: u64 = 1 << 25;
/// Most nodes on the path from a glTF scene's root to any node, both included.
pub const MAX_GLTF_NODE_DEPTH: u32 = 64;
/// Most triangle primitives one glTF file places, a mesh placed by several nodes counted once per
/// node: each is a mesh of its own, so tiny instanced primitives are bounded apart from their
/// triangles.
pub const MAX_GLTF_PRIMITIVES: u64 = 1 << 20;
/// Largest coordinate of a position or extent, in scene units: squared distances and bounding
/// boxes stay far inside `f32` range (the built-in scenes span a few units).
pub const MAX_COORDINATE: f32 = 1e7;

/// The bytes of the regular file at `path`, if it has at most `max` of them (checked before
/// reading, and read through a bounded reader in case the file grows; devices such as
/// `/dev/zero` are refused).
pub fn read_file(path: &Path, max: u64) -> Result<Vec<u8>, InputError> {
    let value = || path.display().to_string();
    let failed = |e: std::io::Error| InputError::new(path, "(file)", value(), e.to_string());
    let file = std::fs::File::open(path).map_err(failed)?;
    let metadata = file.metadata().map_err(failed)?;
    if !metadata.is_file() {
        return Err(InputError::new(
            path,
            "(file)",
            value(),
            "not a regular file",
        ));
    }
    if metadata.len() > max {
        return Err(InputError::new(
            path,
            "(file)",
            bytes(metadata.len()),
            format!("larger than the limit of {}", bytes(max)),
        ));
    }
    let mut data = Vec::new();
    file.take(max.saturating_add(1))
        .read_to_end(&mut data)
        .map_err(failed)?;
    if data.len() as u64 > max {
        return Err(InputError::new(
            path,
            "(file)",
            format!("more than {}", bytes(max)),
            format!("larger than the limit of {}", bytes(max)),
        ));
    }
    Ok(data)
}

/// `n` bytes with a binary unit (`1.5 GiB`).
pub fn bytes(n: u64) -> String {
    const UNITS: [&str; 7] = ["bytes", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"];
    let mut value = n as f64;
    let mut unit = 0;
    while value >= 1024.0 && unit + 1 < UNITS.len() {
        value /= 1024.0;
        unit += 1;
    }
    if unit == 0 {
        format!("{n} bytes")
    } else {
        format!("{value:.1} {}", UNITS[unit])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bytes_have_a_binary_unit() {
        assert_eq!(bytes(512), "512 bytes");
        assert_eq!(bytes(3 << 29), "1.5 GiB");
    }

    #[test]
    fn read_file_refuses_what_is_too_large_or_not_a_file() {
        let dir = std::env::temp_dir();
        let e = read_file(&dir, 1 << 20).unwrap_err();
        assert_eq!(e.reason, "not a regular file");
        let path = dir.join(format!("geometry-limits-{}.txt", std::process::id()));
        std::fs::write(&path, [0u8; 100]).unwrap();
        assert_eq!(read_file(&path, 100).map(|d| d.len()), Ok(100));
        let e = read_file(&path, 99).unwrap_err();
        std::fs::remove_file(&path).unwrap();
        assert_eq!(e.value, "100 bytes");
        assert!(e.reason.contains("99 bytes"), "{e}");
    }
}
