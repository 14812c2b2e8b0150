//! Limits on every size read from a file or a command-line flag (docs/scene-format.md, "Limits").
//!
//! No size from user input is trusted before allocating: an image resolution, a checkpoint
//! header, a mesh header's element counts, a light count, frame, replica and sample counts are
//! each checked here against a documented limit and against the memory they imply
//! ([`MEMORY_BUDGET`]), with a one-line [`InputError`] naming the file, the field and the value.

use std::io::Read;
use std::path::Path;

use crate::InputError;

/// Largest image width or height, in pixels.
pub const MAX_IMAGE_SIDE: u32 = 16_384;
/// Largest image, in pixels (4096², or e.g. 5120 × 3200).
pub const MAX_PIXELS: u64 = 1 << 24;
/// Memory one pixel of a frame pipeline holds, independent of the number of frames: reservoirs,
/// G-buffers, shading cells; or a reference's exact sums and G-buffer. Measured peak resident
/// memory of `reshift render --method restir:sequential` and `reshift reference` at 128×96 and
/// 512×384 (411 and 490 bytes per pixel), rounded up.
pub const PIPELINE_BYTES_PER_PIXEL: u64 = 512;
/// Memory one pixel of one frame holds once rendered (an RGB `f32` image: the CPU backend keeps
/// every frame of a run, a comparison keeps every replica's final frame).
pub const IMAGE_BYTES_PER_PIXEL: u64 = 12;
/// Most memory a job's inputs may imply, in bytes (16 GiB).
pub const MEMORY_BUDGET: u64 = 16 << 30;

/// Most frames of one run (the trajectory has 16; later frames repeat the last camera).
pub const MAX_FRAMES: u32 = 1 << 16;
/// Most replicas of one method in a comparison or a bias test (and reference batches of a bias
/// test).
pub const MAX_REPLICAS: u32 = 1 << 16;
/// Most samples per pixel per frame of one method (`pt:N`, `random-walk:N`).
pub const MAX_SPP: u32 = 1 << 20;

/// Largest scene file, in bytes.
pub const MAX_SCENE_FILE_BYTES: u64 = 1 << 24;
/// Most lights of a scene (`[[lights]]` plus `[many_lights].count`).
pub const MAX_LIGHTS: u64 = 1 << 20;
/// Most triangles of one procedural shape (guards against typos in tessellation fields).
pub const MAX_SHAPE_TRIANGLES: u64 = 1 << 22;
/// Largest mesh file (OBJ or PLY), in bytes.
pub const MAX_MESH_FILE_BYTES: u64 = 1 << 31;
/// Most vertices of one mesh file.
pub const MAX_MESH_VERTICES: u64 = 1 << 25;
/// Most triangles of one mesh file (after fan and strip triangulation).
pub const MAX_MESH_TRIANGLES: u64 = 1 << 25;
/// Most triangles of a whole scene.
pub const MAX_SCENE_TRIANGLES: u64 = 1 << 26;

/// Largest emitted quantity (radiance, intensity, irradiance) per channel: leaves 10⁸ of `f32`
/// headroom (3.4 · 10³⁸) for the BSSRDF, geometry and 1/pdf factors of a sample.
pub const MAX_EMISSION: f32 = 1e30;
/// Largest coordinate of a position or extent, in scene units: squared distances and bounding
/// boxes stay far inside `f32` range (the built-in scenes span a few units).
pub const MAX_COORDINATE: f32 = 1e7;

/// `value` if it lies in `min..=max`, else an error at `field` of `file`.
pub fn count(file: &Path, field: &str, value: u64, min: u64, max: u64) -> Result<u64, InputError> {
    if (min..=max).contains(&value) {
        Ok(value)
    } else {
        Err(InputError::new(
            file,
            field,
            value.to_string(),
            format!("must be in {min}..={max}"),
        ))
    }
}

/// A replica count in `1..=`[`MAX_REPLICAS`], or an error at `field` of `file`.
pub fn replicas(file: &Path, field: &str, n: u32) -> Result<u32, InputError> {
    count(file, field, n as u64, 1, MAX_REPLICAS as u64).map(|_| n)
}

/// A frame count in `1..=`[`MAX_FRAMES`], or an error at `field` of `file`.
pub fn frames(file: &Path, field: &str, n: u32) -> Result<u32, InputError> {
    count(file, field, n as u64, 1, MAX_FRAMES as u64).map(|_| n)
}

/// An image of `width × height`: both sides in `1..=`[`MAX_IMAGE_SIDE`], at most [`MAX_PIXELS`].
pub fn resolution(file: &Path, field: &str, width: u32, height: u32) -> Result<(), InputError> {
    let value = || format!("{width}×{height}");
    if width == 0 || height == 0 {
        return Err(InputError::new(
            file,
            field,
            value(),
            "width and height must be ≥ 1",
        ));
    }
    if width > MAX_IMAGE_SIDE || height > MAX_IMAGE_SIDE {
        return Err(InputError::new(
            file,
            field,
            value(),
            format!("width and height must be ≤ {MAX_IMAGE_SIDE}"),
        ));
    }
    let pixels = width as u64 * height as u64;
    if pixels > MAX_PIXELS {
        return Err(InputError::new(
            file,
            field,
            value(),
            format!(
                "{pixels} pixels (≈ {} of pipeline buffers) exceed the limit of {MAX_PIXELS}",
                bytes(pixels * PIPELINE_BYTES_PER_PIXEL)
            ),
        ));
    }
    Ok(())
}

/// `needed` bytes for `what` are within [`MEMORY_BUDGET`]; `needed = None` is an overflow.
pub fn memory(
    file: &Path,
    field: &str,
    value: &str,
    needed: Option<u64>,
    what: &str,
) -> Result<(), InputError> {
    match needed {
        Some(n) if n <= MEMORY_BUDGET => Ok(()),
        _ => Err(InputError::new(
            file,
            field,
            value,
            format!(
                "{what} would need {}, more than the budget of {}",
                needed.map_or_else(|| "more than 2⁶⁴ bytes".to_string(), bytes),
                bytes(MEMORY_BUDGET)
            ),
        )),
    }
}

/// Bytes a run of `frames` frames at `pixels` pixels holds: its pipeline and its frames.
pub fn run_bytes(pixels: u64, frames: u32) -> Option<u64> {
    let frame_bytes = (frames as u64).checked_mul(IMAGE_BYTES_PER_PIXEL)?;
    pixels.checked_mul(PIPELINE_BYTES_PER_PIXEL.checked_add(frame_bytes)?)
}

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
    fn resolution_limits_name_the_value_and_the_memory() {
        let file = Path::new("s.toml");
        assert!(resolution(file, "camera.resolution", 4096, 4096).is_ok());
        assert!(resolution(file, "camera.resolution", MAX_IMAGE_SIDE, 1024).is_ok());
        let e = resolution(file, "camera.resolution", 100_000, 100_000).unwrap_err();
        assert_eq!(e.value, "100000×100000");
        assert!(e.reason.contains("16384"), "{e}");
        let e = resolution(file, "camera.resolution", 16_384, 16_384).unwrap_err();
        assert!(e.reason.contains("128.0 GiB"), "{e}");
        assert!(resolution(file, "camera.resolution", 0, 5).is_err());
    }

    /// docs/scene-format.md lists every limit with its value.
    #[test]
    fn the_limits_are_documented() {
        let doc = include_str!("../../docs/scene-format.md");
        let rows: [(&str, String); 17] = [
            ("MAX_IMAGE_SIDE", MAX_IMAGE_SIDE.to_string()),
            ("MAX_PIXELS", MAX_PIXELS.to_string()),
            (
                "PIPELINE_BYTES_PER_PIXEL",
                PIPELINE_BYTES_PER_PIXEL.to_string(),
            ),
            ("IMAGE_BYTES_PER_PIXEL", IMAGE_BYTES_PER_PIXEL.to_string()),
            ("MEMORY_BUDGET", MEMORY_BUDGET.to_string()),
            ("MAX_FRAMES", MAX_FRAMES.to_string()),
            ("MAX_REPLICAS", MAX_REPLICAS.to_string()),
            ("MAX_SPP", MAX_SPP.to_string()),
            ("MAX_SCENE_FILE_BYTES", MAX_SCENE_FILE_BYTES.to_string()),
            ("MAX_LIGHTS", MAX_LIGHTS.to_string()),
            ("MAX_SHAPE_TRIANGLES", MAX_SHAPE_TRIANGLES.to_string()),
            ("MAX_MESH_FILE_BYTES", MAX_MESH_FILE_BYTES.to_string()),
            ("MAX_MESH_VERTICES", MAX_MESH_VERTICES.to_string()),
            ("MAX_MESH_TRIANGLES", MAX_MESH_TRIANGLES.to_string()),
            ("MAX_SCENE_TRIANGLES", MAX_SCENE_TRIANGLES.to_string()),
            ("MAX_EMISSION", format!("{MAX_EMISSION:e}")),
            ("MAX_COORDINATE", format!("{MAX_COORDINATE:e}")),
        ];
        for (name, value) in rows {
            let row = format!("| `{name}` | `{value}` |");
            assert!(doc.contains(&row), "docs/scene-format.md lacks {row:?}");
        }
    }

    #[test]
    fn memory_and_counts() {
        let file = Path::new("(command line)");
        assert_eq!(run_bytes(10, 2), Some(10 * (512 + 24)));
        assert_eq!(run_bytes(u64::MAX, 1), None);
        assert!(memory(file, "--frames", "16", run_bytes(1 << 20, 16), "the run").is_ok());
        let e = memory(
            file,
            "--frames",
            "65536",
            run_bytes(1 << 24, 1 << 16),
            "the run",
        );
        assert!(e.unwrap_err().reason.contains("12.0 TiB"));
        assert!(memory(file, "x", "y", None, "z").is_err());
        assert_eq!(count(file, "--replicas", 3, 1, 8), Ok(3));
        let e = count(file, "--replicas", 0, 1, 8).unwrap_err();
        assert_eq!(
            e.to_string(),
            "(command line): field `--replicas` = 0: must be in 1..=8"
        );
        assert_eq!(bytes(512), "512 bytes");
        assert_eq!(bytes(3 << 29), "1.5 GiB");
    }
}
