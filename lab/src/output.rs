//! Where a job's files go: its output folder, checked before the work starts ([`output_dir`]),
//! text files that name themselves in errors ([`write_text`]) and file-name-safe method names
//! ([`file_stem`]). Every module that writes files uses these, so this one uses nothing of the
//! lab but its error type.

use std::path::{Path, PathBuf};

use crate::error::Error;

/// Creates `dir` (and parents) and checks that a file can be written in it.
pub fn output_dir(dir: &Path) -> Result<PathBuf, Error> {
    let fail = |e: std::io::Error| Error::Io(format!("output folder {}: {e}", dir.display()));
    std::fs::create_dir_all(dir).map_err(fail)?;
    let probe = dir.join(".reshift-write-test");
    std::fs::write(&probe, b"").map_err(fail)?;
    std::fs::remove_file(&probe).map_err(fail)?;
    Ok(dir.to_path_buf())
}

/// Writes `text` to `path`, naming the file in the error.
pub fn write_text(path: &Path, text: &str) -> Result<(), Error> {
    std::fs::write(path, text).map_err(|e| Error::Io(format!("{}: {e}", path.display())))
}

/// A file-name-safe form of a method name (`restir:hybrid` → `restir-hybrid`).
pub fn file_stem(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '.' {
                c
            } else {
                '-'
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn file_stems_keep_only_safe_characters() {
        assert_eq!(
            file_stem("restir:sequential/temporal=delayed"),
            "restir-sequential-temporal-delayed"
        );
        assert_eq!(file_stem("pt:1.5"), "pt-1.5");
    }

    #[test]
    fn an_output_folder_below_a_file_is_an_error_naming_it() {
        let file = std::env::temp_dir().join(format!("reshift-output-{}", std::process::id()));
        std::fs::write(&file, "x").unwrap();
        let e = output_dir(&file.join("sub")).unwrap_err().to_string();
        assert!(e.starts_with("output folder ") && e.contains("sub"), "{e}");
        std::fs::remove_file(&file).unwrap();
    }
}
