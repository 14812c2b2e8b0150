//! `reshift view --record DIR`: what was seen, written when the viewer closes. Every rendered
//! frame (as displayed: tonemapped, or the false-colour error) goes into `DIR/view.png`, an
//! animated PNG by the lab's own writer ([`lab::report::video::write_apng`]), and its pose into
//! `DIR/trajectory.toml`, a camera trajectory (`reshift-trajectory/1`, one `[[pose]]` per frame)
//! that `compare --trajectory` replays, so what a researcher saw can be measured, and per frame
//! what it was and cost into `DIR/frames.tsv` ([`FRAMES_HEADER`]): the method, the live
//! stream's frame index and mean confidence (empty for a frame rendered at rest), the non-finite
//! count, the wall time and each pass's time on the backend's clock. A flight recorded with one
//! ReSTIR method from its first frame is one live stream: `compare --trajectory` with the same
//! method and seed renders its frames again, bit for bit on the CPU.

use std::path::{Path, PathBuf};

use sss::scene::Trajectory;

use crate::camera::Pose;
use crate::session::Frame;

/// The columns of `frames.tsv`, tab-separated; `passes` is `label=milliseconds` per pass,
/// space-separated.
pub const FRAMES_HEADER: &str =
    "frame\tmethod\tstream_frame\tconfidence\tnonfinite\twall_ms\tpasses";

/// The recorded frames and poses.
pub struct Recorder {
    dir: PathBuf,
    size: (u32, u32),
    frames: Vec<Vec<u8>>,
    poses: Vec<Pose>,
    /// One line of `frames.tsv` per frame.
    rows: Vec<String>,
    vfov: f32,
    up: glam::Vec3,
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
            rows: Vec::new(),
            vfov,
            up,
        })
    }

    /// Adds a displayed frame as shown (RGB bytes of the recorder's size) and what `method`
    /// rendered for it.
    pub fn push(&mut self, rgb: Vec<u8>, frame: &Frame, method: &str) {
        debug_assert_eq!(rgb.len(), 3 * self.size.0 as usize * self.size.1 as usize);
        let (index, confidence) = frame.live.map_or((String::new(), String::new()), |l| {
            (l.index.to_string(), l.confidence.to_string())
        });
        let passes: Vec<String> = (frame.timings.iter())
            .map(|(label, seconds)| format!("{label}={:.4}", 1e3 * seconds))
            .collect();
        self.rows.push(format!(
            "{}\t{method}\t{index}\t{confidence}\t{}\t{:.4}\t{}",
            self.frames.len(),
            frame.nonfinite,
            1e3 * frame.wall_seconds,
            passes.join(" ")
        ));
        self.frames.push(rgb);
        self.poses.push(frame.pose);
    }

    /// The trajectory of the recorded poses, checked as a file's would be (errors name `path`).
    fn trajectory(&self, path: &Path) -> Result<Trajectory, String> {
        let poses = self
            .poses
            .iter()
            .map(|p| sss::scene::Pose {
                eye: p.eye,
                target: p.target,
                up: self.up,
            })
            .collect();
        Trajectory::new(Some(self.vfov), poses, path).map_err(|e| e.to_string())
    }

    /// Writes `view.png`, `trajectory.toml` and `frames.tsv`; returns their paths (none
    /// without frames).
    pub fn finish(self) -> Result<Vec<PathBuf>, String> {
        if self.frames.is_empty() {
            return Ok(Vec::new());
        }
        let (video, trajectory) = (self.dir.join("view.png"), self.dir.join("trajectory.toml"));
        lab::report::video::write_apng(&video, &self.frames, self.size)
            .map_err(|e| e.to_string())?;
        let text = self.trajectory(&trajectory)?.to_toml();
        let write = |path: &Path, text: String| {
            std::fs::write(path, text).map_err(|e| format!("{}: {e}", path.display()))
        };
        write(&trajectory, text)?;
        let table = self.dir.join("frames.tsv");
        write(
            &table,
            format!("{FRAMES_HEADER}\n{}\n", self.rows.join("\n")),
        )?;
        Ok(vec![video, trajectory, table])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::session::Live;
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
            let frame = Frame {
                image: engine::Image {
                    width: 2,
                    height: 1,
                    pixels: vec![glam::Vec3::ZERO; 2],
                },
                pose,
                timings: vec![("shade".into(), 0.002)],
                wall_seconds: 0.01,
                window: 1,
                nonfinite: 0,
                live: Some(Live {
                    index: i as u32,
                    confidence: 1.5,
                }),
            };
            recorder.push(vec![i as u8 * 100; 6], &frame, "restir:hybrid");
        }
        let written = recorder.finish().unwrap();
        assert_eq!(written.len(), 3);
        let table = std::fs::read_to_string(&written[2]).unwrap();
        let lines: Vec<&str> = table.lines().collect();
        assert_eq!(lines[0], FRAMES_HEADER);
        assert_eq!(
            lines[2],
            "1\trestir:hybrid\t1\t1.5\t0\t10.0000\tshade=2.0000"
        );
        let read = Trajectory::load(&written[1]).unwrap();
        assert_eq!(read.vfov, Some(45.0));
        assert_eq!(read.poses.len(), 2);
        assert_eq!(read.poses[0].eye, vec3(0.1, 1.0, 5.0));
        assert_eq!(read.poses[1].up, Vec3::Y);
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
