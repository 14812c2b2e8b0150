//! The replica limit of comparisons and bias tests (docs/scene-format.md, "Limits"; the other
//! limits are `sss::limits`, `geometry::limits` and `engine::limits`, whose documentation the
//! tests here check with this crate's).

use std::path::Path;

use sss::InputError;
use sss::limits::count;

/// Most replicas of one method in a comparison or a bias test (and reference batches of a bias
/// test).
pub const MAX_REPLICAS: u32 = 1 << 16;

/// A replica count in `1..=`[`MAX_REPLICAS`], or an error at `field` of `file`.
pub fn replicas(file: &Path, field: &str, n: u32) -> Result<u32, InputError> {
    count(file, field, n as u64, 1, MAX_REPLICAS as u64).map(|_| n)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// docs/scene-format.md lists every limit with its value: those of this crate and of the
    /// crates below it (`geometry`, `sss`, `engine`), all visible here.
    #[test]
    fn the_limits_are_documented() {
        use engine::limits::{IMAGE_BYTES_PER_PIXEL, PIPELINE_BYTES_PER_PIXEL};
        use geometry::limits::{
            MAX_COORDINATE, MAX_MESH_FILE_BYTES, MAX_MESH_TRIANGLES, MAX_MESH_VERTICES,
        };
        use sss::limits::{
            MAX_EMISSION, MAX_FRAMES, MAX_IMAGE_SIDE, MAX_LIGHTS, MAX_PIXELS, MAX_SCENE_FILE_BYTES,
            MAX_SCENE_TRIANGLES, MAX_SHAPE_TRIANGLES, MAX_SPP, MEMORY_BUDGET,
        };

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
    fn replicas_lie_in_one_to_the_limit() {
        let file = Path::new("(command line)");
        assert_eq!(replicas(file, "--replicas", 1), Ok(1));
        assert_eq!(replicas(file, "--replicas", MAX_REPLICAS), Ok(MAX_REPLICAS));
        let e = replicas(file, "--replicas", 0).unwrap_err();
        assert_eq!(e.reason, "must be in 1..=65536");
        assert!(replicas(file, "--replicas", MAX_REPLICAS + 1).is_err());
    }
}
