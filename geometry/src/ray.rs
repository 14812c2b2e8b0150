//! Rays and hit records.

use glam::{Vec2, Vec3A};

/// A ray segment: points `origin + t·dir` for `t_min < t < t_max` (both ends open).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    pub origin: Vec3A,
    pub dir: Vec3A,
    pub t_min: f32,
    pub t_max: f32,
}

impl Ray {
    /// A ray with `−0.0` direction components replaced by `+0.0` (`dir + 0`), so that the sign
    /// of a zero component cannot disagree between octant selection and slab tests.
    pub fn new(origin: Vec3A, dir: Vec3A, t_min: f32, t_max: f32) -> Ray {
        Ray {
            origin,
            dir: dir + Vec3A::ZERO,
            t_min,
            t_max,
        }
    }

    /// The segment from `from` to `to` (exclusive at both ends), with `dir = to − from`, so
    /// `t` runs over (0, 1).
    pub fn segment(from: Vec3A, to: Vec3A) -> Ray {
        Ray::new(from, to - from, 0.0, 1.0)
    }

    pub fn at(&self, t: f32) -> Vec3A {
        self.origin + t * self.dir
    }
}

/// A ray–triangle intersection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: f32,
    /// Global triangle id (objects' triangles concatenated in object order).
    pub prim: u32,
    pub object: u32,
    /// Barycentrics `(u, v)` of vertices 1 and 2; vertex 0 has weight `1 − u − v`.
    pub bary: Vec2,
}
