//! Limits on every size read from a file or a command-line flag (docs/scene-format.md, "Limits").
//!
//! No size from user input is trusted before allocating: an image resolution, a checkpoint
//! header, a light count, frame and sample counts are each checked here against a documented
//! limit and against the memory they imply ([`MEMORY_BUDGET`]), with a one-line [`InputError`]
//! naming the file, the field and the value. The limits of mesh files, with the bounded file
//! reading every loader shares, are `geometry::limits`; the memory of a frame pipeline is
//! `engine::limits`; the replica count is `lab::limits`.

use std::path::Path;

use geometry::limits::bytes;

use crate::InputError;

/// Largest image width or height, in pixels.
pub const MAX_IMAGE_SIDE: u32 = 16_384;
/// Largest image, in pixels (4096², or e.g. 5120 × 3200).
pub const MAX_PIXELS: u64 = 1 << 24;
/// Most memory a job's inputs may imply, in bytes (16 GiB).
pub const MEMORY_BUDGET: u64 = 16 << 30;

/// Most frames of one run (the trajectory has 16; later frames repeat the last camera).
pub const MAX_FRAMES: u32 = 1 << 16;
/// Most samples per pixel per frame of one method (`pt:N`, `random-walk:N`).
pub const MAX_SPP: u32 = 1 << 20;

/// Largest scene file, in bytes.
pub const MAX_SCENE_FILE_BYTES: u64 = 1 << 24;
/// Most lights of a scene (`[[lights]]` plus `[many_lights].count`).
pub const MAX_LIGHTS: u64 = 1 << 20;
/// Most triangles of one procedural shape (guards against typos in tessellation fields).
pub const MAX_SHAPE_TRIANGLES: u64 = 1 << 22;
/// Most triangles of a whole scene.
pub const MAX_SCENE_TRIANGLES: u64 = 1 << 26;

/// Largest emitted quantity (radiance, intensity, irradiance) per channel: leaves 10⁸ of `f32`
/// headroom (3.4 · 10³⁸) for the BSSRDF, geometry and 1/pdf factors of a sample.
pub const MAX_EMISSION: f32 = 1e30;

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
            format!("{pixels} pixels exceed the limit of {MAX_PIXELS}"),
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resolution_limits_name_the_value_and_the_limit() {
        let file = Path::new("s.toml");
        assert!(resolution(file, "camera.resolution", 4096, 4096).is_ok());
        assert!(resolution(file, "camera.resolution", MAX_IMAGE_SIDE, 1024).is_ok());
        let e = resolution(file, "camera.resolution", 100_000, 100_000).unwrap_err();
        assert_eq!(e.value, "100000×100000");
        assert!(e.reason.contains("16384"), "{e}");
        let e = resolution(file, "camera.resolution", 16_384, 16_384).unwrap_err();
        assert_eq!(e.reason, "268435456 pixels exceed the limit of 16777216");
        assert!(resolution(file, "camera.resolution", 0, 5).is_err());
    }

    #[test]
    fn memory_and_counts() {
        let file = Path::new("(command line)");
        assert!(memory(file, "--frames", "16", Some(MEMORY_BUDGET), "the run").is_ok());
        let e = memory(file, "--frames", "65536", Some(12 << 40), "the run");
        assert!(e.unwrap_err().reason.contains("12.0 TiB"));
        assert!(memory(file, "x", "y", None, "z").is_err());
        assert_eq!(count(file, "--replicas", 3, 1, 8), Ok(3));
        let e = count(file, "--replicas", 0, 1, 8).unwrap_err();
        assert_eq!(
            e.to_string(),
            "(command line): field `--replicas` = 0: must be in 1..=8"
        );
    }
}
