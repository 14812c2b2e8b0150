//! Scenes (DESIGN §4): the TOML scene format (`docs/scene-format.md`), camera with its 16-frame
//! trajectory and jitter, lights with power-proportional selection, the G-buffer, and the
//! built-in evaluation scenes of paper 001 §6 (`scenes/*.toml`).

pub mod assets;
mod builtin;
mod camera;
mod emitter_field;
mod format;
mod gbuffer;
mod light;
mod load;
mod many_lights;
pub mod motion;
mod parse;
pub mod trajectory;

use std::borrow::Cow;
use std::path::{Path, PathBuf};
use std::sync::Arc;

pub use camera::{Camera, FRAMES};
pub use gbuffer::{GBuffer, GPixel, REPROJECTION_DEPTH_TOLERANCE, REPROJECTION_NORMAL_COSINE};
pub use light::{DIRECTIONAL_DISTANCE, Light, LightSample, Lights};
pub use many_lights::ManyLights;
pub use motion::Motion;
pub use trajectory::{Pose, Trajectory};

use geometry::Geometry;
use geometry::limits::read_file;

use crate::InputError;
use crate::limits::MAX_SCENE_FILE_BYTES;
use crate::material::Material;

/// A scene object; its index in [`Scene::objects`] is its object id in [`Scene::geometry`].
#[derive(Clone, Debug, PartialEq)]
pub struct Object {
    pub name: String,
    /// Index into [`Scene::materials`].
    pub material: u32,
}

/// A loaded scene. The file's area lights are not in `geometry` (they neither occlude nor appear
/// in camera rays) unless the scene file adds objects with matching geometry; emissive objects
/// are in both: geometry, and one light per triangle. A clone shares the geometry (a stream
/// that moves the camera owns its scene: `engine::Stream`).
///
/// Objects may move ([`motion`]): `geometry` is then their pose at frame `posed_at`, and
/// [`Scene::at_frame`] poses the scene at another frame. Whatever traces rays at frame `f`
/// traces them in `scene.at_frame(f)`.
#[derive(Clone)]
pub struct Scene {
    /// The file stem of the scene file.
    pub name: String,
    /// The scene file as given to [`Scene::load`] (`scenes/<name>.toml` for built-in scenes):
    /// errors found after loading name it.
    pub file: PathBuf,
    pub camera: Camera,
    pub materials: Vec<Material>,
    pub objects: Vec<Object>,
    pub geometry: Arc<Geometry>,
    /// The moving objects, `None` where nothing moves.
    pub motion: Option<Arc<Motion>>,
    /// The frame `geometry` is posed at (0 as loaded).
    pub posed_at: u32,
    pub lights: Lights,
    /// Degenerate triangles (zero area, non-finite) removed from the objects' meshes.
    pub dropped_degenerate: usize,
}

impl Scene {
    /// The built-in scenes of procedural geometry: `(name, one-line description)`.
    pub const BUILTIN: &[(&str, &str)] = builtin::BUILTIN;
    /// The built-in scenes that read their meshes from the asset directory ([`assets`]).
    pub const WITH_ASSETS: &[(&str, &str)] = builtin::WITH_ASSETS;

    /// Loads a scene file (at most [`MAX_SCENE_FILE_BYTES`]); mesh paths are relative to its
    /// folder.
    pub fn load(path: &Path) -> Result<Scene, InputError> {
        let bytes = read_file(path, MAX_SCENE_FILE_BYTES)?;
        let text = String::from_utf8(bytes).map_err(|e| {
            InputError::new(
                path,
                "(file)",
                format!("byte {}", e.utf8_error().valid_up_to()),
                "not UTF-8 text",
            )
        })?;
        Scene::from_toml_str(&text, path)
    }

    /// Parses scene text; `origin` names the file in errors and anchors relative mesh paths.
    pub fn from_toml_str(text: &str, origin: &Path) -> Result<Scene, InputError> {
        load::scene_from_toml(text, origin)
    }

    /// The built-in scene `name` of [`Scene::BUILTIN`] or [`Scene::WITH_ASSETS`], or `None` for
    /// an unknown name; a scene of the second list fails where the asset directory is not set or
    /// lacks its files.
    pub fn named(name: &str) -> Option<Result<Scene, InputError>> {
        let text = builtin::source(name)?;
        let origin = Path::new("scenes").join(format!("{name}.toml"));
        Some(Scene::from_toml_str(text, &origin))
    }

    /// The built-in scene `name` (see [`Scene::BUILTIN`]), or `None` for an unknown name.
    /// Panics where it fails to load: built-in files are tested to parse, and a scene of
    /// [`Scene::WITH_ASSETS`] needs its assets ([`Scene::named`] returns the error).
    pub fn builtin(name: &str) -> Option<Scene> {
        Some(Scene::named(name)?.unwrap_or_else(|e| panic!("built-in scene {name}: {e}")))
    }

    /// The scene with its objects posed at `frame`: itself where nothing moves or it shows that
    /// pose already ([`Motion::settled`]), else a clone with the geometry of `frame`
    /// ([`Motion::geometry_at`]).
    pub fn at_frame(&self, frame: u32) -> Cow<'_, Scene> {
        match &self.motion {
            Some(motion) if motion.settled(self.posed_at) != motion.settled(frame) => {
                Cow::Owned(Scene {
                    geometry: motion.geometry_at(frame),
                    posed_at: frame,
                    ..self.clone()
                })
            }
            _ => Cow::Borrowed(self),
        }
    }

    /// The first moving object's name, `None` where nothing moves: for the one-line refusal of
    /// what renders only scenes at rest.
    pub fn moving_object(&self) -> Option<&str> {
        let object = self.motion.as_ref()?.moving_objects().next()?;
        Some(&self.objects[object as usize].name)
    }

    pub fn material_of_object(&self, object: u32) -> &Material {
        &self.materials[self.objects[object as usize].material as usize]
    }
}
