//! The memory a run holds per pixel (docs/scene-format.md, "Limits"): the figures behind the
//! memory checks of runs, comparisons and bias tests (`sss::limits::memory`).

/// Memory one pixel of a frame pipeline holds, independent of the number of frames: reservoirs,
/// G-buffers, shading cells; or a reference's exact sums and G-buffer. Measured peak resident
/// memory of `reshift render --method restir:sequential` and `reshift reference` at 128×96 and
/// 512×384 (411 and 490 bytes per pixel), rounded up.
pub const PIPELINE_BYTES_PER_PIXEL: u64 = 512;
/// Memory one pixel of one frame holds once rendered (an RGB `f32` image: the CPU backend keeps
/// every frame of a run, a comparison keeps every replica's final frame).
pub const IMAGE_BYTES_PER_PIXEL: u64 = 12;

/// Bytes a run of `frames` frames at `pixels` pixels holds: its pipeline and its frames; `None`
/// on overflow.
pub fn run_bytes(pixels: u64, frames: u32) -> Option<u64> {
    let frame_bytes = (frames as u64).checked_mul(IMAGE_BYTES_PER_PIXEL)?;
    pixels.checked_mul(PIPELINE_BYTES_PER_PIXEL.checked_add(frame_bytes)?)
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::*;

    #[test]
    fn run_bytes_count_the_pipeline_and_every_frame() {
        assert_eq!(run_bytes(10, 2), Some(10 * (512 + 24)));
        assert_eq!(run_bytes(u64::MAX, 1), None);
        let file = Path::new("(command line)");
        let memory = |needed| sss::limits::memory(file, "--frames", "n", needed, "the run");
        assert!(memory(run_bytes(1 << 20, 16)).is_ok());
        let e = memory(run_bytes(1 << 24, 1 << 16)).unwrap_err();
        assert!(e.reason.contains("12.0 TiB"), "{e}");
    }
}
