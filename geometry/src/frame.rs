//! Orthonormal frames around a normal.

use glam::Vec3;

/// A right-handed orthonormal basis `(t, b, n)` with `t × b = n`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    pub t: Vec3,
    pub b: Vec3,
    pub n: Vec3,
}

impl Frame {
    /// The branchless basis of Duff et al. 2017 (*Building an Orthonormal Basis, Revisited*,
    /// Listing 3) around the unit normal `n`. The sign is `n.z ≥ 0 ? 1 : −1` (so `−0.0` counts as
    /// positive), written as a select to mirror GLSL exactly (GLSL `sign(0) = 0` must not be used).
    pub fn from_normal(n: Vec3) -> Frame {
        let sign = if n.z >= 0.0 { 1.0 } else { -1.0 };
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        Frame {
            t: Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
            b: Vec3::new(b, sign + n.y * n.y * a, -n.y),
            n,
        }
    }

    /// Coordinates of the world vector `v` in this frame.
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.t), v.dot(self.b), v.dot(self.n))
    }

    /// The world vector with coordinates `v` in this frame.
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        v.x * self.t + v.y * self.b + v.z * self.n
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use restir::rng::StreamKey;

    fn unit_vector(u1: f32, u2: f32) -> Vec3 {
        let z = 1.0 - 2.0 * u1;
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = std::f32::consts::TAU * u2;
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    }

    /// Max deviation from orthonormality / right-handedness, over random and edge-case normals.
    fn worst_error(make: impl Fn(Vec3) -> Frame) -> f32 {
        let mut rng = StreamKey::new(0, 0, 0, 0xF0A3).stream(7);
        let mut normals: Vec<Vec3> = (0..10_000)
            .map(|_| unit_vector(rng.next_f32(), rng.next_f32()))
            .collect();
        normals.extend([
            Vec3::Z,
            -Vec3::Z,
            Vec3::X,
            -Vec3::Y,
            Vec3::new(0.6, 0.8, -0.0),
        ]);
        normals
            .into_iter()
            .map(|n| {
                let f = make(n);
                [
                    (f.t.length() - 1.0).abs(),
                    (f.b.length() - 1.0).abs(),
                    f.t.dot(f.b).abs(),
                    f.t.dot(n).abs(),
                    f.b.dot(n).abs(),
                    (f.t.cross(f.b) - n).length(),
                    (f.to_world(f.to_local(n * 0.3 + f.t)) - (n * 0.3 + f.t)).length(),
                ]
                .into_iter()
                .fold(0.0f32, f32::max)
            })
            .fold(0.0, f32::max)
    }

    #[test]
    fn frame_is_orthonormal_and_right_handed() {
        let err = worst_error(Frame::from_normal);
        assert!(
            err < 1e-5,
            "worst orthonormality error {err} over 10005 normals"
        );
        // Negative control: swapping t and b makes the frame left-handed; the same check catches it.
        let swapped = worst_error(|n| {
            let f = Frame::from_normal(n);
            Frame { t: f.b, b: f.t, n }
        });
        assert!(swapped > 1.0, "negative control not detected: {swapped}");
    }
}
