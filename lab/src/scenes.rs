//! Scenes as a user names them: a built-in name, a measured-material sphere
//! `sphere-<material>` ([`material_sphere`]) or a scene file, with the key that names the
//! scene's cached references, and the camera at the resolution of a job.

use std::path::Path;

use engine::hash::fnv1a;
use geometry::limits::read_file;
use sss::InputError;
use sss::limits::MAX_SCENE_FILE_BYTES;
use sss::material::MEASURED_NAMES;
use sss::scene::Scene;
use sss::scene::trajectory::{MAX_TRAJECTORY_FILE_BYTES, Trajectory};

/// A scene as named by the user, with its cache key.
pub struct LoadedScene {
    pub scene: Scene,
    /// The built-in name, or `file-<stem>-<FNV-1a of the text>` for a scene file.
    pub key: String,
}

/// `spec`: a built-in name (of `Scene::BUILTIN` or `Scene::WITH_ASSETS`), or a path to a scene
/// file (anything with a `/` or ending in `.toml`). Unknown names list the built-ins.
pub fn load_scene(spec: &str) -> Result<LoadedScene, InputError> {
    if let Some(scene) = Scene::named(spec) {
        return Ok(LoadedScene {
            scene: scene?,
            key: spec.to_string(),
        });
    }
    if let Some(scene) = material_sphere(spec) {
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
    // The built-in names are listed by `reshift scenes`, the presets by sss::material::MEASURED_NAMES.
    Err(InputError::new(
        "(command line)",
        "--scene",
        format!("{spec:?}"),
        format!(
            "unknown scene: neither a built-in one (`reshift scenes` lists them), \
             {SPHERE_PREFIX}<preset> nor a *.toml file"
        ),
    ))
}

/// The prefix of the measured-material spheres.
pub const SPHERE_PREFIX: &str = "sphere-";

/// `sphere-<material>`: the `bumpy` setup (camera, floor, quad light, shadow-casting plate)
/// with a smooth sphere of radius 0.5 made of a measured material of Jensen et al. 2001
/// (`sss::material::measured`, lengths in mm) at 1 unit = 25 mm (`scale = 0.04`), so the sphere
/// is 12.5 mm across in radius and the volume mean free paths span 0.01 (cream) to 0.5 (chicken,
/// red) of it. `None` for other names.
pub fn material_sphere(name: &str) -> Option<Scene> {
    let material = name.strip_prefix(SPHERE_PREFIX)?;
    MEASURED_NAMES.contains(&material).then_some(())?;
    let text = SPHERE_TEMPLATE.replace("{material}", material);
    let origin = Path::new("scenes").join(format!("{name}.toml"));
    // The template is tested to parse for every material; a failure here is a bug in it.
    Some(Scene::from_toml_str(&text, &origin).unwrap_or_else(|e| panic!("{name}: {e}")))
}

/// [`material_sphere`]'s scene, `{material}` a measured preset.
const SPHERE_TEMPLATE: &str = r#"
[camera]
resolution = [256, 192]
vfov = 35.0
eye = [0.0, 1.1, 3.0]
target = [0.0, 0.5, 0.0]
eye_end = [0.25, 1.15, 2.9]
target_end = [0.02, 0.5, 0.0]

[[materials]]
name = "{material}"
type = "translucent"
preset = "{material}"
scale = 0.04

[[materials]]
name = "floor"
type = "lambert"
albedo = [0.5, 0.5, 0.5]

[[materials]]
name = "occluder"
type = "lambert"
albedo = [0.2, 0.2, 0.2]

[[objects]]
name = "object"
material = "{material}"
shape = { type = "sphere", radius = 0.5, segments = 96, rings = 48 }
transform = { translate = [0.0, 0.52, 0.0] }

[[objects]]
name = "floor"
material = "floor"
shape = { type = "quad", size = [8.0, 8.0] }

[[objects]]
name = "occluder"
material = "occluder"
shape = { type = "box", size = [2.0, 0.05, 2.0] }
transform = { translate = [0.9, 1.5, 0.0] }

[[lights]]
type = "quad"
corner = [-2.5, 3.0, -0.5]
edge_u = [2.0, 0.0, 0.0]
edge_v = [0.0, 0.0, 2.0]
radiance = [8.0, 8.0, 8.0]
"#;

impl LoadedScene {
    /// The scene with its camera on the trajectory file at `path` (`--trajectory`), keyed
    /// `<key>-path-<FNV-1a of the file>` so that a cached reference of one camera path is never
    /// taken for another's; with the trajectory's pose count, the frames that replay it.
    pub fn on_trajectory(self, path: &Path) -> Result<(LoadedScene, u32), InputError> {
        let text = read_file(path, MAX_TRAJECTORY_FILE_BYTES)?;
        let trajectory = Trajectory::load(path)?;
        let frames = trajectory.poses.len() as u32;
        let scene = Scene {
            camera: self.scene.camera.with_trajectory(&trajectory),
            ..self.scene
        };
        let key = format!("{}-path-{:016x}", self.key, fnv1a(&text));
        Ok((LoadedScene { scene, key }, frames))
    }
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
        assert!(
            e.contains("unknown scene") && e.contains("reshift scenes"),
            "{e}"
        );
    }

    /// Every measured material has its sphere, named by its key, with lit and shadowed parts of
    /// the sphere in view (the regions of the ground-truth experiment); other names have none.
    #[test]
    fn every_measured_material_has_a_sphere() {
        use crate::regions::{Region, Regions};
        use sss::material::Material;
        use sss::scene::GBuffer;
        for material in MEASURED_NAMES {
            let name = format!("{SPHERE_PREFIX}{material}");
            let loaded = load_scene(&name).unwrap();
            assert_eq!(
                (loaded.key.as_str(), loaded.scene.name.as_str()),
                (name.as_str(), name.as_str())
            );
            let scene = with_resolution(loaded.scene, Some((32, 24)));
            let Material::Translucent(t) = scene.materials[0] else {
                panic!("{name}: translucent material first")
            };
            // As every built-in: d ≥ 1e-3, ten times the BVH's hit tolerance.
            assert!(t.d().min_element() >= 1e-3, "{name}: d = {}", t.d());
            let regions = Regions::classify(&scene, &GBuffer::render(&scene, 15), 1);
            let counts = Region::ALL.map(|r| regions.count(r));
            assert!(counts[1] > 20 && counts[3] > 20, "{name}: {counts:?}");
        }
        assert!(material_sphere("sphere-granite").is_none());
        assert!(material_sphere("marble").is_none());
        let e = load_scene("sphere-granite").err().unwrap().to_string();
        assert!(
            e.contains("unknown scene: neither a built-in one (`reshift scenes` lists them)")
                && e.contains("sphere-granite")
                && e.contains("sphere-<preset>")
                && !e.contains(" … "),
            "{e}"
        );
    }
}
