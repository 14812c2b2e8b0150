//! Pinhole camera on a linear 16-frame trajectory, or on a trajectory of one pose per frame
//! ([`Trajectory`], a recorded camera path), with per-frame sub-pixel jitter (DESIGN §4).
//!
//! Pixel coordinates are continuous: pixel `(px, py)` covers `[px, px+1) × [py, py+1)`, row 0 is
//! the top of the image, and its centre is `(px + 0.5, py + 0.5)`. Frame `f` renders through
//! `(px + 0.5, py + 0.5) + jitter(f)`; [`Camera::project`] is the unjittered projection, so the
//! hit point of [`Camera::ray`] projects back to the jittered sample position.

use std::sync::Arc;

use geometry::Ray;
use glam::{Vec2, Vec3, Vec3A};

use super::trajectory::{Pose, Trajectory};

/// Frames of the camera trajectory (paper 001 §6 records the temporal history over 16 frames).
pub const FRAMES: u32 = 16;

/// A pinhole camera whose eye and target move linearly from their start to their end positions
/// over frames `0..FRAMES`, or follow a trajectory's poses frame by frame; later frames stay at
/// the last pose (the jitter keeps cycling).
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    width: u32,
    height: u32,
    /// `tan(vfov / 2)`.
    tan_half_fov: f32,
    path: Path,
    jitter: bool,
}

/// Where the camera is at each frame.
#[derive(Clone, Debug, PartialEq)]
enum Path {
    /// Eye and target from their start `[0]` to their end `[1]` over frames `0..FRAMES`.
    Linear {
        eye: [Vec3; 2],
        target: [Vec3; 2],
        up: Vec3,
    },
    /// Pose `f` at frame `f`; the last pose after the end.
    Poses(Arc<[Pose]>),
    /// A camera moved live ([`Camera::moved_to`]): `previous` before frame `at`, `current` from
    /// it on.
    Moved {
        previous: Pose,
        current: Pose,
        at: u32,
    },
}

/// The camera's orthonormal basis at one frame.
#[derive(Clone, Copy, Debug)]
struct Basis {
    eye: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
}

impl Camera {
    /// A camera; the loader validates the inputs (non-zero resolution, `0 < vfov < 180`, eye ≠
    /// target and a view direction not parallel to `up` at both ends of the trajectory).
    pub fn new(
        resolution: [u32; 2],
        vfov_degrees: f32,
        eye: [Vec3; 2],
        target: [Vec3; 2],
        up: Vec3,
        jitter: bool,
    ) -> Camera {
        Camera {
            width: resolution[0],
            height: resolution[1],
            tan_half_fov: (0.5 * vfov_degrees.to_radians()).tan(),
            path: Path::Linear {
                eye,
                target,
                up: up.normalize(),
            },
            jitter,
        }
    }

    /// The same camera on `trajectory`'s poses (and its field of view, when it gives one); the
    /// resolution and jitter are kept. A trajectory of this camera's own poses
    /// ([`Trajectory::of_camera`]) renders the same bits.
    pub fn with_trajectory(&self, trajectory: &Trajectory) -> Camera {
        let poses: Vec<Pose> = trajectory
            .poses
            .iter()
            .map(|p| Pose {
                up: p.up.normalize(),
                ..*p
            })
            .collect();
        Camera {
            tan_half_fov: trajectory
                .vfov
                .map_or(self.tan_half_fov, |v| (0.5 * v.to_radians()).tan()),
            path: Path::Poses(poses.into()),
            ..self.clone()
        }
    }

    /// The pose at `frame`: eye, target and (unit) up.
    pub fn pose(&self, frame: u32) -> Pose {
        match &self.path {
            Path::Linear { eye, target, up } => {
                let t = Self::progress(frame);
                Pose {
                    eye: eye[0].lerp(eye[1], t),
                    target: target[0].lerp(target[1], t),
                    up: *up,
                }
            }
            Path::Poses(poses) => {
                let last = poses.len().saturating_sub(1);
                poses[(frame as usize).min(last)]
            }
            Path::Moved {
                previous,
                current,
                at,
            } => match frame < *at {
                true => *previous,
                false => *current,
            },
        }
    }

    /// The same camera moved to `pose` at `frame`, as a viewer moves it: from `frame` on it is
    /// at `pose`, before it at this camera's pose of frame `frame − 1` (the frame that temporal
    /// reuse reprojects into; `pose` too when `frame` is 0). Moving a camera frame after frame
    /// this way renders the bits of a trajectory of the same poses ([`Camera::with_trajectory`]),
    /// whose frame `f` is at pose `f` and frame `f − 1` at pose `f − 1`; the field of view,
    /// resolution and jitter are kept.
    pub fn moved_to(&self, frame: u32, pose: Pose) -> Camera {
        let current = Pose {
            up: pose.up.normalize(),
            ..pose
        };
        let previous = frame.checked_sub(1).map_or(current, |f| self.pose(f));
        Camera {
            path: Path::Moved {
                previous,
                current,
                at: frame,
            },
            ..self.clone()
        }
    }

    /// The same camera at another resolution (a CLI override); the field of view is kept.
    pub fn with_resolution(&self, width: u32, height: u32) -> Camera {
        Camera {
            width,
            height,
            ..self.clone()
        }
    }

    /// The same camera at rest at its trajectory's end pose for every frame (the pose of frame
    /// `FRAMES − 1`, so that frame renders as before); the jitter is kept.
    pub fn at_rest(&self) -> Camera {
        let end = self.pose(FRAMES - 1);
        Camera {
            path: Path::Linear {
                eye: [end.eye; 2],
                target: [end.target; 2],
                up: end.up,
            },
            ..self.clone()
        }
    }

    /// The same camera with jitter on or off.
    pub fn with_jitter(&self, jitter: bool) -> Camera {
        Camera {
            jitter,
            ..self.clone()
        }
    }

    pub fn width(&self) -> u32 {
        self.width
    }

    /// `tan(vfov / 2)`, for the GPU twin of [`Camera::ray`].
    pub fn tan_half_fov(&self) -> f32 {
        self.tan_half_fov
    }

    pub fn height(&self) -> u32 {
        self.height
    }

    /// Whether frames are jittered.
    pub fn jittered(&self) -> bool {
        self.jitter
    }

    /// Trajectory parameter of `frame` in [0, 1].
    fn progress(frame: u32) -> f32 {
        frame.min(FRAMES - 1) as f32 / (FRAMES - 1) as f32
    }

    fn basis(&self, frame: u32) -> Basis {
        let Pose { eye, target, up } = self.pose(frame);
        let forward = (target - eye).normalize();
        let right = forward.cross(up).normalize();
        let up = right.cross(forward);
        Basis {
            eye,
            forward,
            right,
            up,
        }
    }

    /// Eye position at `frame`.
    pub fn eye(&self, frame: u32) -> Vec3 {
        self.basis(frame).eye
    }

    /// Unit view direction at `frame`.
    pub fn forward(&self, frame: u32) -> Vec3 {
        self.basis(frame).forward
    }

    /// Unit right and up vectors of the image plane at `frame` (image x grows along right, image
    /// y grows along −up).
    pub fn right_up(&self, frame: u32) -> (Vec3, Vec3) {
        let b = self.basis(frame);
        (b.right, b.up)
    }

    /// Sub-pixel offset of `frame` in pixels, in [−0.5, 0.5)²: the Halton (2, 3) point of index
    /// `frame + 1` minus ½ (index 0 would be the corner). Zero when jitter is off.
    pub fn jitter(&self, frame: u32) -> Vec2 {
        if !self.jitter {
            return Vec2::ZERO;
        }
        let i = frame as u64 + 1;
        Vec2::new(radical_inverse(i, 2) - 0.5, radical_inverse(i, 3) - 0.5)
    }

    /// Pixels per world unit on the image plane at view depth `z` (square pixels).
    fn pixels_per_unit(&self, z: f32) -> f32 {
        self.height as f32 / (2.0 * self.tan_half_fov * z)
    }

    /// The primary ray (unit direction, `t ∈ (0, ∞)`) through the jittered centre of pixel
    /// `(px, py)` at `frame`.
    pub fn ray(&self, frame: u32, px: u32, py: u32) -> Ray {
        let b = self.basis(frame);
        let pixel = Vec2::new(px as f32 + 0.5, py as f32 + 0.5) + self.jitter(frame);
        let (w, h) = (self.width as f32, self.height as f32);
        // Image-plane coordinates at unit depth.
        let sx = (2.0 * pixel.x - w) / h * self.tan_half_fov;
        let sy = (h - 2.0 * pixel.y) / h * self.tan_half_fov;
        let dir = (b.forward + sx * b.right + sy * b.up).normalize();
        Ray::new(Vec3A::from(b.eye), Vec3A::from(dir), 0.0, f32::INFINITY)
    }

    /// Continuous pixel coordinates of the world point `p` seen at `frame` (no jitter), or `None`
    /// when `p` is behind the eye or projects outside `[0, width) × [0, height)`. Reprojection for
    /// temporal reuse: the pixel of `p` in the previous frame is `floor(project(frame − 1, p))`.
    pub fn project(&self, frame: u32, p: Vec3) -> Option<Vec2> {
        let b = self.basis(frame);
        let d = p - b.eye;
        let z = d.dot(b.forward);
        if !z.is_finite() || z <= 0.0 {
            return None;
        }
        let k = self.pixels_per_unit(z);
        let (w, h) = (self.width as f32, self.height as f32);
        let c = Vec2::new(0.5 * w + d.dot(b.right) * k, 0.5 * h - d.dot(b.up) * k);
        (c.x >= 0.0 && c.x < w && c.y >= 0.0 && c.y < h).then_some(c)
    }

    /// Spatial reuse radius in pixels (DESIGN §9): the screen length of a world offset of
    /// `2·max_d` at `x1` along the camera's right and up axes, clamped to [5, 30]. An offset in
    /// the image plane keeps the view depth, so both axes give `2·max_d · pixels_per_unit(z)`.
    /// Points behind the eye get the lower bound.
    pub fn spatial_radius_px(&self, frame: u32, x1: Vec3, max_d: f32) -> f32 {
        self.projected_radius_px(frame, x1, max_d)
            .map_or(5.0, |r| r.clamp(5.0, 30.0))
    }

    /// The unclamped projection behind [`Self::spatial_radius_px`]: the screen length of `2·max_d`
    /// at `x1`, or `None` when `x1` is behind the eye or the length is not finite.
    pub fn projected_radius_px(&self, frame: u32, x1: Vec3, max_d: f32) -> Option<f32> {
        let b = self.basis(frame);
        let z = (x1 - b.eye).dot(b.forward);
        let r = 2.0 * max_d * self.pixels_per_unit(z);
        (z > 0.0 && r.is_finite()).then_some(r)
    }
}

/// Van der Corput radical inverse of `i` in `base`, in [0, 1).
fn radical_inverse(mut i: u64, base: u64) -> f32 {
    let inv_base = 1.0 / base as f64;
    let (mut value, mut scale) = (0.0f64, inv_base);
    while i > 0 {
        value += (i % base) as f64 * scale;
        i /= base;
        scale *= inv_base;
    }
    value as f32
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::vec3;

    fn moving_camera() -> Camera {
        Camera::new(
            [64, 48],
            40.0,
            [vec3(0.0, 1.0, 4.0), vec3(0.6, 1.3, 3.6)],
            [vec3(0.0, 0.4, 0.0), vec3(0.1, 0.4, 0.0)],
            Vec3::Y,
            true,
        )
    }

    /// Intersect a camera ray with the plane `z = z0` (stands in for a scene hit).
    fn hit_plane(ray: &Ray, z0: f32) -> Vec3 {
        let t = (z0 - ray.origin.z) / ray.dir.z;
        Vec3::from(ray.at(t))
    }

    /// At rest, every frame has the moving camera's last pose (the last frame's rays are the
    /// same bits) and jitter is kept; without jitter the rays go through pixel centres.
    /// Control: the moving camera's first frame differs from its last.
    #[test]
    fn a_camera_at_rest_keeps_the_last_pose_and_jitter_toggles() {
        let cam = moving_camera();
        let rest = cam.at_rest();
        let last = FRAMES - 1;
        for frame in [0, 7, last] {
            assert_eq!(rest.eye(frame), cam.eye(last));
            assert_eq!(rest.forward(frame), cam.forward(last));
            assert_eq!(rest.jitter(frame), cam.jitter(frame));
        }
        assert_eq!(rest.ray(last, 5, 9), cam.ray(last, 5, 9));
        assert_ne!(cam.eye(0), cam.eye(last), "control: the camera moves");
        let still = cam.with_jitter(false);
        assert!(!still.jittered() && cam.with_jitter(true).jittered());
        assert_eq!(still.jitter(3), Vec2::ZERO);
        assert_ne!(still.ray(3, 5, 9), cam.ray(3, 5, 9));
    }

    /// A camera moved pose by pose gives, at each frame and the frame before it, the rays of
    /// a trajectory of the same poses; before the first move every frame is at the first pose.
    /// Control: moved to another pose, its rays differ.
    #[test]
    fn a_camera_moved_frame_by_frame_is_the_trajectory_of_its_poses() {
        let cam = moving_camera();
        let poses: Vec<Pose> = (0..5).map(|f| cam.pose(3 * f)).collect();
        let trajectory = Trajectory {
            vfov: None,
            poses: poses.clone(),
        };
        let replay = cam.with_trajectory(&trajectory);
        let mut live = cam.at_rest();
        for (f, pose) in poses.iter().enumerate() {
            let f = f as u32;
            live = live.moved_to(f, *pose);
            for frame in f.saturating_sub(1)..=f {
                assert_eq!(
                    live.ray(frame, 7, 3),
                    replay.ray(frame, 7, 3),
                    "{f}, {frame}"
                );
                assert_eq!(live.pose(frame), replay.pose(frame));
            }
        }
        let first = cam.at_rest().moved_to(0, poses[2]);
        assert_eq!(first.pose(0), poses[2]);
        let other = live.moved_to(5, poses[0]);
        assert_ne!(other.ray(5, 7, 3), live.ray(5, 7, 3), "control");
        assert_eq!(other.pose(4), poses[4]);
    }

    #[test]
    fn jitter_is_halton_in_half_open_square_and_off_when_disabled() {
        let cam = moving_camera();
        assert_eq!(cam.jitter(0), Vec2::new(0.0, 1.0 / 3.0 - 0.5));
        assert_eq!(cam.jitter(1), Vec2::new(-0.25, 2.0 / 3.0 - 0.5));
        for f in 0..64 {
            let j = cam.jitter(f);
            assert!(
                j.cmpge(Vec2::splat(-0.5)).all() && j.cmplt(Vec2::splat(0.5)).all(),
                "{j}"
            );
        }
        let distinct: std::collections::HashSet<_> = (0..FRAMES)
            .map(|f| cam.jitter(f).to_array().map(f32::to_bits))
            .collect();
        assert_eq!(distinct.len(), FRAMES as usize);
        let still = Camera {
            jitter: false,
            ..cam
        };
        assert_eq!(still.jitter(5), Vec2::ZERO);
    }

    /// `project(hit of ray(f, px, py)) = (px + 0.5, py + 0.5) + jitter(f)` for every frame and
    /// a grid of pixels; the negative control drops the jitter and must miss by the jitter.
    #[test]
    fn project_inverts_ray_through_jittered_pixel_centre() {
        let cam = moving_camera();
        let mut worst = 0.0f32;
        let mut worst_unjittered = f32::INFINITY;
        for f in 0..FRAMES {
            for (px, py) in [(0, 0), (63, 47), (10, 30), (40, 5), (32, 24)] {
                let p = hit_plane(&cam.ray(f, px, py), -1.5);
                let c = cam.project(f, p).expect("visible");
                let centre = Vec2::new(px as f32 + 0.5, py as f32 + 0.5);
                worst = worst.max((c - (centre + cam.jitter(f))).abs().max_element());
                worst_unjittered = worst_unjittered.min((c - centre).length());
            }
        }
        assert!(worst < 2e-3, "worst reprojection error {worst} px");
        assert!(
            worst_unjittered > 0.1,
            "negative control: without jitter the error is {worst_unjittered}"
        );
    }

    /// A static world point moves between frames exactly as the analytic pinhole predicts:
    /// reprojecting into frame f−1 and casting that frame's ray through the result finds the
    /// point again; and frames of a moving camera do project it to different pixels.
    #[test]
    fn reprojection_of_static_point_between_frames() {
        let cam = moving_camera();
        let p = vec3(0.2, 0.5, -0.3);
        for f in 1..FRAMES {
            let now = cam.project(f, p).unwrap();
            let before = cam.project(f - 1, p).unwrap();
            assert!((now - before).length() > 0.05, "camera moves: frame {f}");
            let b = cam.basis(f - 1);
            let (w, h) = (cam.width as f32, cam.height as f32);
            let sx = (2.0 * before.x - w) / h * cam.tan_half_fov;
            let sy = (h - 2.0 * before.y) / h * cam.tan_half_fov;
            let dir = (b.forward + sx * b.right + sy * b.up).normalize();
            let to_p = (p - b.eye).normalize();
            assert!(
                dir.angle_between(to_p) < 1e-5,
                "frame {f}: {}",
                dir.angle_between(to_p)
            );
        }
        assert_eq!(
            cam.eye(FRAMES + 3),
            cam.eye(FRAMES - 1),
            "frames past the end stay put"
        );
        let doubled = cam.with_resolution(128, 96);
        let (a, b) = (cam.project(7, p).unwrap(), doubled.project(7, p).unwrap());
        assert!(
            (2.0 * a - b).length() < 1e-3,
            "a resolution override keeps the view: {a} {b}"
        );
        assert!(
            cam.project(0, cam.eye(0) - cam.forward(0)).is_none(),
            "behind the eye"
        );
    }

    #[test]
    fn spatial_radius_matches_projected_offset_and_clamps() {
        let cam = moving_camera();
        let (right, up) = cam.right_up(3);
        let x1 = vec3(0.0, 0.4, 0.0);
        let max_d = 0.4;
        let c = cam.project(3, x1).unwrap();
        let along_right = (cam.project(3, x1 + 2.0 * max_d * right).unwrap() - c).length();
        let along_up = (cam.project(3, x1 + 2.0 * max_d * up).unwrap() - c).length();
        let r = cam.spatial_radius_px(3, x1, max_d);
        assert!(
            (5.0..30.0).contains(&r),
            "test wants the unclamped range, got {r}"
        );
        assert!(
            (r - along_right).abs() < 1e-3 * r && (r - along_up).abs() < 1e-3 * r,
            "{r} {along_right} {along_up}"
        );
        assert_eq!(cam.projected_radius_px(3, x1, max_d), Some(r));
        assert_eq!(cam.spatial_radius_px(3, x1, 1e-4), 5.0);
        assert_eq!(cam.spatial_radius_px(3, x1, 10.0), 30.0);
        let small = cam.projected_radius_px(3, x1, 1e-4).unwrap();
        let large = cam.projected_radius_px(3, x1, 10.0).unwrap();
        assert!(small < 5.0 && large > 30.0, "{small} {large}");
        let behind = cam.eye(3) - cam.forward(3);
        assert_eq!(cam.spatial_radius_px(3, behind, 0.1), 5.0);
        assert_eq!(cam.projected_radius_px(3, behind, 0.1), None);
    }
}
