//! The asset directory: where scene files find mesh files they name with `asset = "…"` (the
//! public assets of paper 001's implementation, which the project never copies). It is the
//! directory given to [`set_dir`] (the CLI's `--assets DIR`), else the environment variable
//! [`ASSETS_ENV`].

use std::path::{Path, PathBuf};
use std::sync::RwLock;

use crate::InputError;

/// The environment variable that names the asset directory.
pub const ASSETS_ENV: &str = "RESHIFT_ASSETS";

/// Where the assets of paper 001's scenes come from (their public repository).
pub const ASSETS_SOURCE: &str = "https://github.com/MircoWerner/ReSTIR-SSS-Assets";

/// The directory [`set_dir`] gave, if any.
static DIR: RwLock<Option<PathBuf>> = RwLock::new(None);

/// Makes `dir` the asset directory of this process (it takes precedence over [`ASSETS_ENV`]).
pub fn set_dir(dir: &Path) {
    *DIR.write().unwrap_or_else(|e| e.into_inner()) = Some(dir.to_path_buf());
}

/// The asset directory and the setting that named it (`--assets` or [`ASSETS_ENV`]), if any.
pub fn dir() -> Option<(PathBuf, &'static str)> {
    let set = DIR.read().unwrap_or_else(|e| e.into_inner()).clone();
    set.map(|d| (d, "--assets"))
        .or_else(|| std::env::var_os(ASSETS_ENV).map(|d| (PathBuf::from(d), ASSETS_ENV)))
}

/// The file `relative` of the asset directory, or an error at `field` of `scene` that names the
/// setting and where to get the assets.
pub fn resolve(scene: &Path, field: &str, relative: &str) -> Result<PathBuf, InputError> {
    let value = format!("{relative:?}");
    let Some((dir, setting)) = dir() else {
        return Err(InputError::new(
            scene,
            field,
            value,
            format!(
                "no asset directory: set {ASSETS_ENV} or --assets to a clone of {ASSETS_SOURCE}"
            ),
        ));
    };
    let path = dir.join(relative);
    if path.is_file() {
        Ok(path)
    } else {
        Err(InputError::new(
            scene,
            field,
            path.display().to_string(),
            format!("not found in the asset directory ({setting}): clone {ASSETS_SOURCE} there"),
        ))
    }
}

/// With `1`, tests that need the shared assets fail where they are missing instead of skipping.
pub const REQUIRE_ASSETS_ENV: &str = "RESHIFT_REQUIRE_ASSETS";

/// Where the tests and CI find the assets: this folder of the nearest ancestor of the
/// repository that has it (`../shared/assets/restir-sss` beside a checkout).
pub const SHARED_ASSETS: &str = "shared/assets/restir-sss";

/// For tests: the [`SHARED_ASSETS`] folder of the nearest ancestor of `from` (a crate's
/// manifest directory), made this process's asset directory. Where there is none, prints why
/// `test` skips and returns `None`, unless [`REQUIRE_ASSETS_ENV`] is `1`: then it panics.
pub fn shared_or_skip(from: &Path, test: &str) -> Option<PathBuf> {
    match from
        .ancestors()
        .map(|a| a.join(SHARED_ASSETS))
        .find(|d| d.is_dir())
    {
        Some(dir) => {
            set_dir(&dir);
            Some(dir)
        }
        None if std::env::var(REQUIRE_ASSETS_ENV).as_deref() == Ok("1") => {
            panic!(
                "{test}: no {SHARED_ASSETS} above {} ({REQUIRE_ASSETS_ENV}=1)",
                from.display()
            )
        }
        None => {
            eprintln!(
                "{test}: skipped: no {SHARED_ASSETS} above {}",
                from.display()
            );
            None
        }
    }
}
