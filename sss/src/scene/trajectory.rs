//! A camera trajectory file: one pose per frame, the camera path a viewer recorded or a user
//! wrote, for `--trajectory` (docs/scene-format.md, "Trajectory files"):
//!
//! ```toml
//! schema = "reshift-trajectory/1"
//! vfov = 45.0            # optional: degrees; default the scene camera's
//! [[pose]]               # frame 0
//! eye = [0.0, 1.0, 4.0]
//! target = [0.0, 0.4, 0.0]
//! up = [0.0, 1.0, 0.0]   # optional: default +y
//! [[pose]]               # frame 1, …
//! ```
//!
//! A scene's camera on a trajectory ([`super::Camera::with_trajectory`]) keeps its resolution
//! and jitter; frames past the last pose stay there. Numbers are written as the `f64` of each
//! `f32` (`f64` decimals round-trip exactly; an `f32`'s shortest decimal read as `f64` and then
//! rounded to `f32` can round twice), so a trajectory written and read back renders the same
//! bits.

use std::fmt::Write;
use std::path::Path;

use geometry::limits::read_file;
use glam::Vec3;
use serde::Deserialize;

use super::Camera;
use super::load::Ctx;
use super::parse::parse;
use crate::InputError;
use crate::limits::{self, MAX_FRAMES};

/// The `schema` line of a trajectory file.
pub const SCHEMA: &str = "reshift-trajectory/1";

/// Largest trajectory file, in bytes (a pose is under 200 bytes; [`MAX_FRAMES`] poses fit).
pub const MAX_TRAJECTORY_FILE_BYTES: u64 = 1 << 24;

/// Where the camera is at one frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    pub eye: Vec3,
    pub target: Vec3,
    pub up: Vec3,
}

/// A camera path: at least one pose, each a view a camera can frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Trajectory {
    /// Vertical field of view in degrees, if the trajectory sets one.
    pub vfov: Option<f32>,
    pub poses: Vec<Pose>,
}

/// The file as written.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TrajectoryFile {
    schema: String,
    vfov: Option<f32>,
    #[serde(default)]
    pose: Vec<PoseDesc>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PoseDesc {
    eye: [f32; 3],
    target: [f32; 3],
    up: Option<[f32; 3]>,
}

impl Trajectory {
    /// `poses` (and `vfov`) checked as a file's would be; errors name `origin`.
    pub fn new(
        vfov: Option<f32>,
        poses: Vec<Pose>,
        origin: &Path,
    ) -> Result<Trajectory, InputError> {
        let ctx = Ctx { file: origin };
        if let Some(v) = vfov
            && !(v > 0.0 && v < 180.0)
        {
            return Err(ctx.err("vfov", v.to_string(), "must lie in (0, 180) degrees"));
        }
        limits::count(origin, "pose", poses.len() as u64, 1, MAX_FRAMES as u64)?;
        for (i, p) in poses.iter().enumerate() {
            let field = |name: &str| format!("pose[{i}].{name}");
            ctx.vec3(&field("eye"), p.eye.to_array())?;
            ctx.vec3(&field("target"), p.target.to_array())?;
            ctx.vec3(&field("up"), p.up.to_array())?;
            if p.up.length_squared() == 0.0 {
                return Err(ctx.err(field("up"), format!("{}", p.up), "must be non-zero"));
            }
            ctx.view(&field("target"), p.eye, p.target, p.up)?;
        }
        Ok(Trajectory { vfov, poses })
    }

    /// Reads a trajectory file (at most [`MAX_TRAJECTORY_FILE_BYTES`]).
    pub fn load(path: &Path) -> Result<Trajectory, InputError> {
        let bytes = read_file(path, MAX_TRAJECTORY_FILE_BYTES)?;
        let text = String::from_utf8(bytes).map_err(|e| {
            let at = format!("byte {}", e.utf8_error().valid_up_to());
            InputError::new(path, "(file)", at, "not UTF-8 text")
        })?;
        Trajectory::from_toml(&text, path)
    }

    /// Parses a trajectory's TOML text; `origin` names it in errors.
    pub fn from_toml(text: &str, origin: &Path) -> Result<Trajectory, InputError> {
        let file: TrajectoryFile = parse(text, origin)?;
        if file.schema != SCHEMA {
            let reason = format!("expected {SCHEMA:?}");
            return Err(InputError::new(
                origin,
                "schema",
                format!("{:?}", file.schema),
                reason,
            ));
        }
        let poses = file
            .pose
            .iter()
            .map(|p| Pose {
                eye: Vec3::from_array(p.eye),
                target: Vec3::from_array(p.target),
                up: Vec3::from_array(p.up.unwrap_or([0.0, 1.0, 0.0])),
            })
            .collect();
        Trajectory::new(file.vfov, poses, origin)
    }

    /// The TOML text of this trajectory (read back by [`Trajectory::from_toml`] bit for bit).
    pub fn to_toml(&self) -> String {
        let v = |v: Vec3| {
            let [x, y, z] = v.to_array().map(f64::from);
            format!("[{x:?}, {y:?}, {z:?}]")
        };
        let mut text =
            format!("# reshift camera trajectory: one [[pose]] per frame\nschema = \"{SCHEMA}\"\n");
        if let Some(vfov) = self.vfov {
            let _ = writeln!(text, "vfov = {:?}", f64::from(vfov));
        }
        for (frame, p) in self.poses.iter().enumerate() {
            let _ = writeln!(text, "\n[[pose]] # frame {frame}");
            let _ = writeln!(
                text,
                "eye = {}\ntarget = {}\nup = {}",
                v(p.eye),
                v(p.target),
                v(p.up)
            );
        }
        text
    }

    /// The poses of `camera` at frames `0..frames` (its field of view is not recorded).
    pub fn of_camera(camera: &Camera, frames: u32) -> Trajectory {
        let poses = (0..frames.max(1)).map(|f| camera.pose(f)).collect();
        Trajectory { vfov: None, poses }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{FRAMES, Scene};

    fn origin() -> &'static Path {
        Path::new("path.toml")
    }

    /// A scene camera's own poses written, read back and applied give the same primary rays bit
    /// for bit at every frame and past the end; control: a trajectory with one eye moved by one
    /// ulp-scale step changes that frame's rays.
    #[test]
    fn a_camera_on_its_own_trajectory_renders_the_same_rays() {
        let camera = Scene::builtin("bumpy").unwrap().camera;
        let written = Trajectory::of_camera(&camera, FRAMES).to_toml();
        let read = Trajectory::from_toml(&written, origin()).unwrap();
        assert_eq!(read, Trajectory::of_camera(&camera, FRAMES));
        let replay = camera.with_trajectory(&read);
        for frame in [0, 1, 7, FRAMES - 1, FRAMES + 4] {
            for (px, py) in [(0, 0), (17, 9), (63, 47)] {
                assert_eq!(
                    replay.ray(frame, px, py),
                    camera.ray(frame, px, py),
                    "frame {frame}"
                );
            }
        }
        let mut moved = read.clone();
        moved.poses[3].eye.x += 1e-3;
        let moved = camera.with_trajectory(&moved);
        assert!(moved.ray(3, 17, 9) != camera.ray(3, 17, 9), "control");
        assert_eq!(moved.ray(4, 17, 9), camera.ray(4, 17, 9));
    }

    /// The field of view of a trajectory replaces the scene's; without one it is kept.
    #[test]
    fn a_trajectory_may_set_the_field_of_view() {
        let camera = Scene::builtin("bumpy").unwrap().camera;
        let mut path = Trajectory::of_camera(&camera, 2);
        assert_eq!(
            camera.with_trajectory(&path).tan_half_fov(),
            camera.tan_half_fov()
        );
        path.vfov = Some(90.0);
        let wide = camera.with_trajectory(&path).tan_half_fov();
        assert!((wide - 1.0).abs() < 1e-6, "{wide}");
    }

    /// The example of docs/scene-format.md ("Trajectory files") is a valid file of two poses.
    #[test]
    fn the_documented_example_reads() {
        let doc = include_str!("../../../docs/scene-format.md");
        let section = &doc[doc.find("### Trajectory files").expect("section")..];
        let start = section.find("```toml\n").expect("example") + "```toml\n".len();
        let example = &section[start..start + section[start..].find("```").unwrap()];
        let read = Trajectory::from_toml(example, Path::new("scene-format.md")).unwrap();
        assert_eq!((read.vfov, read.poses.len()), (Some(45.0), 2));
        assert_eq!(read.poses[1].up, Vec3::Y);
    }

    /// Bad files get one line naming the file, the element and the value.
    #[test]
    fn bad_trajectories_are_refused_with_the_element_named() {
        let pose = "[[pose]]\neye = [0.0, 1.0, 4.0]\ntarget = [0.0, 0.4, 0.0]\n";
        let cases = [
            (
                format!("schema = \"reshift-trajectory/9\"\n{pose}"),
                "schema",
            ),
            (format!("schema = \"{SCHEMA}\"\n"), "`pose` = 0"),
            (
                format!("schema = \"{SCHEMA}\"\nvfov = 180.0\n{pose}"),
                "`vfov` = 180",
            ),
            (
                format!(
                    "schema = \"{SCHEMA}\"\n{pose}[[pose]]\neye = [0.0, 1.0, 4.0]\ntarget = [0.0, 5.0, 4.0]\n"
                ),
                "pose[1].target",
            ),
            (
                format!(
                    "schema = \"{SCHEMA}\"\n[[pose]]\neye = [0.0, 1.0, 1e39]\ntarget = [0.0, 0.4, 0.0]\n"
                ),
                "pose[0].eye",
            ),
            (
                format!("schema = \"{SCHEMA}\"\n{pose}up = [0.0, 0.0, 0.0]\n"),
                "pose[0].up",
            ),
            (format!("schema = \"{SCHEMA}\"\n{pose}roll = 1.0\n"), "roll"),
        ];
        for (text, named) in cases {
            let e = Trajectory::from_toml(&text, origin())
                .unwrap_err()
                .to_string();
            assert!(e.contains("path.toml") && e.contains(named), "{named}: {e}");
            assert!(!e.contains('\n'), "{e}");
        }
    }
}
