//! Scenes as a user names them: a built-in name or a scene file, with the key that names the
//! scene's cached references, and the camera at the resolution of a job.

use std::path::Path;

use engine::hash::fnv1a;
use sss::InputError;
use sss::limits::{MAX_SCENE_FILE_BYTES, read_file};
use sss::scene::Scene;

/// A scene as named by the user, with its cache key.
pub struct LoadedScene {
    pub scene: Scene,
    /// The built-in name, or `file-<stem>-<FNV-1a of the text>` for a scene file.
    pub key: String,
}

/// `spec`: a built-in name, or a path to a scene file (anything with a `/` or ending in
/// `.toml`). Unknown names list the built-ins.
pub fn load_scene(spec: &str) -> Result<LoadedScene, InputError> {
    if let Some(scene) = Scene::builtin(spec) {
        return Ok(LoadedScene {
            scene,
            key: spec.to_string(),
        });
    }
    let path = Path::new(spec);
    if spec.ends_with(".toml") || spec.contains('/') || path.exists() {
        let text = read_file(path, MAX_SCENE_FILE_BYTES)?;
        let scene = Scene::load(path)?;
        let key = format!("file-{}-{:016x}", scene.name, fnv1a(&text));
        return Ok(LoadedScene { scene, key });
    }
    let names: Vec<&str> = Scene::BUILTIN.iter().map(|(n, _)| *n).collect();
    Err(InputError::new(
        "(command line)",
        "--scene",
        format!("{spec:?}"),
        format!(
            "unknown scene; built-in: {} (or a path to a .toml file)",
            names.join(", ")
        ),
    ))
}

/// The scene with the camera at `resolution` (`None`: the scene file's own).
pub fn with_resolution(scene: Scene, resolution: Option<(u32, u32)>) -> Scene {
    match resolution {
        Some((w, h)) => Scene {
            camera: scene.camera.with_resolution(w, h),
            ..scene
        },
        None => scene,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builtins_load_by_name_and_unknown_names_list_them() {
        let bumpy = load_scene("bumpy").unwrap();
        assert_eq!(bumpy.key, "bumpy");
        let small = with_resolution(bumpy.scene, Some((8, 6)));
        assert_eq!((small.camera.width(), small.camera.height()), (8, 6));
        let e = load_scene("nope").err().unwrap().to_string();
        assert!(e.contains("unknown scene") && e.contains("bumpy"), "{e}");
    }
}
