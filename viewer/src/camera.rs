//! The viewer's camera controls: a [`Pose`] (eye, target) moved by orbiting round the target or
//! flying (moving eye and target together, turning the view about the eye), and the scene
//! [`Camera`] at rest at that pose which every displayed frame renders.

use glam::Vec3;
use sss::scene::Camera;

/// Radians of turn per unit of orbit or look input (a pixel of mouse drag, a tenth of an arrow
/// key's step).
const RADIANS_PER_UNIT: f32 = 0.01;

/// The steepest the view may look along the up axis, in radians from it: at the pole the
/// camera's basis (`forward × up`) would be degenerate.
const MIN_POLAR: f32 = 0.05;

/// Where the camera is and what it looks at.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    pub eye: Vec3,
    pub target: Vec3,
}

/// How input moves the camera.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// Input turns the eye round the target at a fixed distance; the wheel dollies.
    Orbit,
    /// Input turns the view about the eye; moves carry eye and target together.
    Fly,
}

impl Mode {
    pub fn name(self) -> &'static str {
        match self {
            Mode::Orbit => "orbit",
            Mode::Fly => "fly",
        }
    }
}

/// The pose and the fixed parts of the scene's camera (resolution, field of view, up, jitter).
#[derive(Clone, Debug)]
pub struct Controls {
    pub pose: Pose,
    pub mode: Mode,
    /// The scene camera at its trajectory's end pose; [`Controls::camera`] keeps all of it but
    /// the pose.
    base: Camera,
    /// The scene camera's up vector: orbits turn about it.
    up: Vec3,
}

impl Controls {
    /// Controls starting at the end pose of `camera`'s trajectory (the frame `compare` and
    /// `render` show last).
    pub fn new(camera: &Camera) -> Controls {
        let last = camera.pose(sss::scene::FRAMES - 1);
        Controls {
            pose: Pose {
                eye: last.eye,
                target: last.target,
            },
            mode: Mode::Orbit,
            base: camera.at_rest(),
            up: last.up,
        }
    }

    /// The up vector orbits turn about.
    pub fn up(&self) -> Vec3 {
        self.up
    }

    /// The vertical field of view in degrees.
    pub fn vfov_degrees(&self) -> f32 {
        2.0 * self.base.tan_half_fov().atan().to_degrees()
    }

    /// The scene camera at rest at the current pose: every frame of a run renders it.
    pub fn camera(&self) -> Camera {
        Camera::new(
            [self.base.width(), self.base.height()],
            self.vfov_degrees(),
            [self.pose.eye; 2],
            [self.pose.target; 2],
            self.up,
            self.base.jittered(),
        )
    }

    /// Turns by `dx` (about up) and `dy` (towards or away from up) input units: round the
    /// target in [`Mode::Orbit`], about the eye in [`Mode::Fly`].
    pub fn turn(&mut self, dx: f32, dy: f32) {
        let (pivot, moving) = match self.mode {
            Mode::Orbit => (self.pose.target, self.pose.eye),
            Mode::Fly => (self.pose.eye, self.pose.target),
        };
        let offset = moving - pivot;
        let radius = offset.length();
        if radius <= 0.0 || !radius.is_finite() {
            return;
        }
        // Spherical coordinates about `up`: polar angle from up, azimuth round it.
        let (u, dir) = (self.up, offset / radius);
        let polar = dir.dot(u).clamp(-1.0, 1.0).acos();
        let sign = match self.mode {
            Mode::Orbit => 1.0,
            Mode::Fly => -1.0,
        };
        let polar = (polar + sign * dy * RADIANS_PER_UNIT)
            .clamp(MIN_POLAR, std::f32::consts::PI - MIN_POLAR);
        let across = dir - u * dir.dot(u);
        let across = if across.length_squared() > 0.0 {
            across.normalize()
        } else {
            u.any_orthonormal_vector()
        };
        let azimuth = -sign * dx * RADIANS_PER_UNIT;
        let across = glam::Quat::from_axis_angle(u, azimuth) * across;
        let moved = pivot + radius * (u * polar.cos() + across * polar.sin());
        match self.mode {
            Mode::Orbit => self.pose.eye = moved,
            Mode::Fly => self.pose.target = moved,
        }
    }

    /// Moves `forward` and `right` distances along the view (fly) or, in orbit mode, dollies
    /// the eye towards the target by `forward` (keeping a tenth of the distance at least).
    pub fn advance(&mut self, forward: f32, right: f32) {
        let view = self.pose.target - self.pose.eye;
        let distance = view.length();
        if distance <= 0.0 || !distance.is_finite() {
            return;
        }
        let ahead = view / distance;
        match self.mode {
            Mode::Orbit => {
                let kept = (distance - forward).max(0.1 * distance);
                self.pose.eye = self.pose.target - ahead * kept;
            }
            Mode::Fly => {
                let side = ahead.cross(self.up).normalize_or_zero();
                let step = ahead * forward + side * right;
                self.pose.eye += step;
                self.pose.target += step;
            }
        }
    }

    /// The distance from eye to target: the scale of one move step.
    pub fn distance(&self) -> f32 {
        self.pose.eye.distance(self.pose.target)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::vec3;

    fn controls() -> Controls {
        let camera = Camera::new(
            [8, 6],
            40.0,
            [vec3(0.0, 1.0, 4.0), vec3(0.0, 1.0, 5.0)],
            [Vec3::ZERO; 2],
            Vec3::Y,
            true,
        );
        Controls::new(&camera)
    }

    #[test]
    fn starts_at_the_end_pose_with_the_scene_camera_otherwise() {
        let c = controls();
        assert_eq!(c.pose.eye, vec3(0.0, 1.0, 5.0));
        assert_eq!(c.pose.target, Vec3::ZERO);
        let camera = c.camera();
        assert_eq!((camera.width(), camera.height()), (8, 6));
        assert!(camera.jittered());
        assert!((c.vfov_degrees() - 40.0).abs() < 1e-4);
        // At rest: every frame at the pose.
        for frame in [0, 7, 40] {
            assert_eq!(camera.eye(frame), c.pose.eye);
        }
    }

    #[test]
    fn orbiting_keeps_the_target_and_distance_and_moves_the_eye() {
        let mut c = controls();
        let (target, distance) = (c.pose.target, c.distance());
        c.turn(50.0, 20.0);
        assert_eq!(c.pose.target, target);
        assert!((c.distance() - distance).abs() < 1e-4 * distance);
        assert!(c.pose.eye.distance(vec3(0.0, 1.0, 5.0)) > 0.1);
        // Turning back returns (up to rounding).
        c.turn(-50.0, -20.0);
        assert!(c.pose.eye.distance(vec3(0.0, 1.0, 5.0)) < 1e-4);
    }

    #[test]
    fn the_view_never_reaches_the_pole() {
        let mut c = controls();
        c.turn(0.0, -1e4);
        let dir = (c.pose.eye - c.pose.target).normalize();
        assert!(dir.dot(Vec3::Y).acos() >= MIN_POLAR - 1e-5);
        assert!(c.camera().forward(0).is_finite());
    }

    #[test]
    fn flying_moves_eye_and_target_together() {
        let mut c = controls();
        c.mode = Mode::Fly;
        let before = c.pose;
        c.advance(1.0, 0.5);
        let step = c.pose.eye - before.eye;
        assert!((c.pose.target - before.target - step).length() < 1e-6);
        assert!((step.length() - 1.25f32.sqrt()).abs() < 1e-5);
        let eye = c.pose.eye;
        c.turn(30.0, 0.0);
        assert_eq!(c.pose.eye, eye);
    }

    #[test]
    fn dollying_never_passes_the_target() {
        let mut c = controls();
        let distance = c.distance();
        c.advance(100.0 * distance, 0.0);
        assert!((c.distance() - 0.1 * distance).abs() < 1e-4);
    }
}
