//! The replica limit of comparisons and bias tests (docs/scene-format.md, "Limits").

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

    /// docs/scene-format.md lists the limit with its value.
    #[test]
    fn the_limit_is_documented() {
        let doc = include_str!("../../docs/scene-format.md");
        let row = format!("| `MAX_REPLICAS` | `{MAX_REPLICAS}` |");
        assert!(doc.contains(&row), "docs/scene-format.md lacks {row:?}");
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
