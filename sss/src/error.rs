//! Errors for user input (scene files, meshes, material parameters).
//!
//! Every error names the file, the field and the offending value, so a researcher can fix the input
//! without reading code. Loaders return these; they never panic on user input.

use std::fmt;
use std::path::{Path, PathBuf};

/// Bad user input: which file, which field, which value, and why it was rejected.
#[derive(Debug, Clone, PartialEq)]
pub struct InputError {
    pub file: PathBuf,
    /// Dotted path of the field inside the file (`objects[2].material.mfp`), or a mesh element.
    pub field: String,
    /// The offending value as written (or a short description when there is none).
    pub value: String,
    pub reason: String,
}

impl InputError {
    pub fn new(
        file: impl AsRef<Path>,
        field: impl Into<String>,
        value: impl Into<String>,
        reason: impl Into<String>,
    ) -> Self {
        Self {
            file: file.as_ref().to_path_buf(),
            field: field.into(),
            value: value.into(),
            reason: reason.into(),
        }
    }
}

impl fmt::Display for InputError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}: field `{}` = {}: {}",
            self.file.display(),
            self.field,
            self.value,
            self.reason
        )
    }
}

impl std::error::Error for InputError {}
