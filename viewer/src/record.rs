//! `reshift view --record DIR`: what was seen, written when the viewer closes. Every rendered
//! frame (as displayed: tonemapped, or the false-colour error) goes into `DIR/view.png`, an
//! animated PNG by the lab's own writer ([`lab::report::video::write_apng`]), and its pose into
//! `DIR/trajectory.toml`, a camera trajectory (`reshift-trajectory/1`, one `[[pose]]` per frame)
//! that `compare --trajectory` replays, so what a researcher saw can be measured.

use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::camera::Pose;

/// The trajectory file's schema tag.
pub const TRAJECTORY_SCHEMA: &str = "reshift-trajectory/1";

/// The recorded frames and poses.
pub struct Recorder {
    dir: PathBuf,
    size: (u32, u32),
    frames: Vec<Vec<u8>>,
    poses: Vec<Pose>,
    vfov: f32,
    up: glam::Vec3,
}

/// `trajectory.toml`.
#[derive(Serialize)]
struct TrajectoryFile {
    schema: &'static str,
    vfov: f64,
    pose: Vec<PoseEntry>,
}

#[derive(Serialize)]
struct PoseEntry {
    eye: [f64; 3],
    target: [f64; 3],
    up: [f64; 3],
}

/// `v` as the f64 with the same shortest decimal form, so the file reads `0.1`, not
/// `0.10000000149011612`, and parses back to the same f32.
fn decimal(v: f32) -> f64 {
    v.to_string().parse().unwrap_or(f64::from(v))
}

fn decimals(v: glam::Vec3) -> [f64; 3] {
    v.to_array().map(decimal)
}

impl Recorder {
    /// A recorder into `dir` (created now, so a bad folder fails before the window opens) of
    /// `size` frames seen through a `vfov`-degree camera with `up`.
    pub fn new(
        dir: &Path,
        size: (u32, u32),
        vfov: f32,
        up: glam::Vec3,
    ) -> Result<Recorder, String> {
        std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        Ok(Recorder {
            dir: dir.to_path_buf(),
            size,
            frames: Vec::new(),
            poses: Vec::new(),
            vfov,
            up,
        })
    }

    /// Adds a displayed frame (RGB bytes of the recorder's size) seen from `pose`.
    pub fn push(&mut self, rgb: Vec<u8>, pose: Pose) {
        debug_assert_eq!(rgb.len(), 3 * self.size.0 as usize * self.size.1 as usize);
        self.frames.push(rgb);
        self.poses.push(pose);
    }

    /// The trajectory file's text.
    fn trajectory(&self) -> Result<String, String> {
        let file = TrajectoryFile {
            schema: TRAJECTORY_SCHEMA,
            vfov: decimal(self.vfov),
            pose: self
                .poses
                .iter()
                .map(|p| PoseEntry {
                    eye: decimals(p.eye),
                    target: decimals(p.target),
                    up: decimals(self.up),
                })
                .collect(),
        };
        let body = toml::to_string(&file).map_err(|e| format!("trajectory: {e}"))?;
        Ok(format!(
            "# reshift camera trajectory (recorded by reshift view)\n{body}"
        ))
    }

    /// Writes `view.png` and `trajectory.toml`; returns their paths (none without frames).
    pub fn finish(self) -> Result<Vec<PathBuf>, String> {
        if self.frames.is_empty() {
            return Ok(Vec::new());
        }
        let (video, trajectory) = (self.dir.join("view.png"), self.dir.join("trajectory.toml"));
        lab::report::video::write_apng(&video, &self.frames, self.size)
            .map_err(|e| e.to_string())?;
        std::fs::write(&trajectory, self.trajectory()?)
            .map_err(|e| format!("{}: {e}", trajectory.display()))?;
        Ok(vec![video, trajectory])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Vec3, vec3};

    #[test]
    fn frames_and_poses_are_written_as_an_apng_and_a_trajectory() {
        let dir = std::env::temp_dir().join(format!("reshift-view-record-{}", std::process::id()));
        let mut recorder = Recorder::new(&dir, (2, 1), 45.0, Vec3::Y).unwrap();
        for (i, x) in [0.1f32, 0.3].into_iter().enumerate() {
            let pose = Pose {
                eye: vec3(x, 1.0, 5.0),
                target: Vec3::ZERO,
            };
            recorder.push(vec![i as u8 * 100; 6], pose);
        }
        let written = recorder.finish().unwrap();
        assert_eq!(written.len(), 2);
        let text = std::fs::read_to_string(&written[1]).unwrap();
        assert!(text.starts_with("# reshift camera trajectory"), "{text}");
        let value: toml::Value = toml::from_str(&text).unwrap();
        assert_eq!(value["schema"].as_str(), Some(TRAJECTORY_SCHEMA));
        assert_eq!(value["vfov"].as_float(), Some(45.0));
        let poses = value["pose"].as_array().unwrap();
        assert_eq!(poses.len(), 2);
        assert_eq!(poses[0]["eye"][0].as_float(), Some(0.1));
        assert_eq!(poses[1]["up"][1].as_float(), Some(1.0));
        let decoder = png::Decoder::new(std::io::BufReader::new(
            std::fs::File::open(&written[0]).unwrap(),
        ));
        let reader = decoder.read_info().unwrap();
        assert_eq!(
            reader.info().animation_control().map(|a| a.num_frames),
            Some(2)
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
