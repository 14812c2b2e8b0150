//! The closed surface that bounds the walk: the [`Boundary`] query and analytic shapes.

use geometry::{Geometry, Ray};
use glam::Vec3;

/// Where a ray from inside the medium first meets the boundary.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoundaryHit {
    pub t: f32,
    /// Unit normal pointing out of the medium (`dir · normal ≥ 0` for the querying ray).
    pub normal: Vec3,
}

/// A closed surface seen from inside.
pub trait Boundary {
    /// The first crossing of `origin + t·dir` (unit `dir`, `origin` inside or on the surface)
    /// with `t < t_max`, ignoring the surface `origin` lies on when `dir` points inward.
    /// `None` when the boundary is not reached before `t_max`.
    fn intersect(&self, origin: Vec3, dir: Vec3, t_max: f32) -> Option<BoundaryHit>;
}

/// A semi-infinite medium: everything on the `−normal` side of the plane through `point`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HalfSpace {
    pub point: Vec3,
    /// Unit outward normal.
    pub normal: Vec3,
}

impl Boundary for HalfSpace {
    fn intersect(&self, origin: Vec3, dir: Vec3, t_max: f32) -> Option<BoundaryHit> {
        let toward = dir.dot(self.normal);
        if toward <= 0.0 {
            return None;
        }
        let t = ((self.point - origin).dot(self.normal) / toward).max(0.0);
        (t < t_max).then_some(BoundaryHit {
            t,
            normal: self.normal,
        })
    }
}

/// A solid sphere.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    pub center: Vec3,
    pub radius: f32,
}

impl Boundary for Sphere {
    /// The far root of `|o + t·d − c|² = r²`: from inside (or on the surface heading inward) it is
    /// the exit, so no self-intersection offset is needed.
    fn intersect(&self, origin: Vec3, dir: Vec3, t_max: f32) -> Option<BoundaryHit> {
        let oc = origin - self.center;
        let b = oc.dot(dir);
        let c = oc.length_squared() - self.radius * self.radius;
        let disc = b * b - c;
        if disc < 0.0 {
            return None;
        }
        let root = disc.sqrt();
        // Cancellation-free far root: −b + √disc, or c / (−b − √disc) when b > 0.
        let t = if b > 0.0 { -c / (b + root) } else { root - b }.max(0.0);
        if t >= t_max {
            return None;
        }
        let normal = (oc + t * dir).normalize();
        Some(BoundaryHit { t, normal })
    }
}

/// One closed, consistently wound object of the scene BVH.
///
/// A hit counts as the boundary only where the ray leaves the object (`dir · n > 0` for the
/// outward geometric normal `n`); hits where it would enter are skipped. That removes the
/// self-intersection problem without an offset: a walk on the surface heading inward ignores
/// the triangle it starts on, and a grazing reflection near an edge that crosses the
/// neighbouring triangle at `t ≈ 0` exits there, as it should.
#[derive(Clone, Copy)]
pub struct MeshBoundary<'a> {
    pub geometry: &'a Geometry,
    pub object: u32,
    /// Set when the object's triangles are wound clockwise seen from outside (negative
    /// [`TriangleMesh::signed_volume`](geometry::TriangleMesh::signed_volume)), so that the
    /// geometric normal points inward.
    pub inward_winding: bool,
}

impl Boundary for MeshBoundary<'_> {
    fn intersect(&self, origin: Vec3, dir: Vec3, t_max: f32) -> Option<BoundaryHit> {
        let mut t_min = 0.0;
        loop {
            let ray = Ray::new(origin.into(), dir.into(), t_min, t_max);
            let hit = self.geometry.closest_hit_on_object(&ray, self.object)?;
            let normal = self.geometry.geometric_normal(hit.prim);
            let normal = if self.inward_winding { -normal } else { normal };
            if normal.dot(dir) > 0.0 {
                return Some(BoundaryHit { t: hit.t, normal });
            }
            // Entering hit: continue past it (`t_min < t` is open, so the loop advances).
            t_min = hit.t;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use geometry::shapes::cuboid;

    #[test]
    fn half_space_exits_only_upward() {
        let plane = HalfSpace {
            point: Vec3::ZERO,
            normal: Vec3::Z,
        };
        let origin = Vec3::new(1.0, 2.0, -3.0);
        let hit = plane
            .intersect(origin, Vec3::new(0.0, 0.6, 0.8), 10.0)
            .unwrap();
        assert!((hit.t - 3.75).abs() < 1e-6);
        assert_eq!(hit.normal, Vec3::Z);
        assert!(
            plane
                .intersect(origin, Vec3::new(0.0, 0.6, 0.8), 3.7)
                .is_none()
        );
        assert!(plane.intersect(origin, -Vec3::Z, f32::INFINITY).is_none());
        assert!(
            plane
                .intersect(Vec3::ZERO, Vec3::new(0.0, 0.6, -0.8), f32::INFINITY)
                .is_none()
        );
    }

    #[test]
    fn sphere_exit_from_inside_and_from_its_surface() {
        let s = Sphere {
            center: Vec3::new(1.0, 0.0, 0.0),
            radius: 2.0,
        };
        let hit = s.intersect(Vec3::new(1.0, 0.0, 0.0), Vec3::Y, 5.0).unwrap();
        assert!((hit.t - 2.0).abs() < 1e-6 && (hit.normal - Vec3::Y).length() < 1e-6);
        // From the north pole straight down: the chord (4), not the pole itself.
        let hit = s
            .intersect(Vec3::new(1.0, 0.0, 2.0), -Vec3::Z, 5.0)
            .unwrap();
        assert!((hit.t - 4.0).abs() < 1e-5 && (hit.normal + Vec3::Z).length() < 1e-5);
        // From the pole heading out: t = 0, outward normal.
        let hit = s.intersect(Vec3::new(1.0, 0.0, 2.0), Vec3::Z, 5.0).unwrap();
        assert!(hit.t < 1e-6 && hit.normal.dot(Vec3::Z) > 0.999);
        assert!(
            s.intersect(Vec3::new(1.0, 0.0, 0.0), Vec3::Y, 1.5)
                .is_none()
        );
    }

    #[test]
    fn mesh_boundary_exits_a_closed_cube_with_outward_normals() {
        let geometry = Geometry::new(&[cuboid(Vec3::splat(1.0))]);
        let cube = MeshBoundary {
            geometry: &geometry,
            object: 0,
            inward_winding: false,
        };
        let dir = Vec3::new(0.6, 0.0, 0.8);
        let hit = cube.intersect(Vec3::new(0.2, 0.3, 0.0), dir, 10.0).unwrap();
        assert!((hit.t - 1.25).abs() < 1e-5 && (hit.normal - Vec3::Z).length() < 1e-6);
        // From a face point heading inward: the opposite face, not the start face.
        let hit = cube
            .intersect(Vec3::new(0.1, 0.2, 1.0), -Vec3::Z, 10.0)
            .unwrap();
        assert!((hit.t - 2.0).abs() < 1e-5 && (hit.normal + Vec3::Z).length() < 1e-6);
        assert!(cube.intersect(Vec3::ZERO, dir, 1.2).is_none());
        // The same cube wound inside out, declared so: same answers.
        let mut inverted = cuboid(Vec3::splat(1.0));
        inverted.indices.iter_mut().for_each(|tri| tri.swap(1, 2));
        assert!(inverted.signed_volume() < 0.0);
        let geometry = Geometry::new(&[inverted]);
        let cube = MeshBoundary {
            geometry: &geometry,
            object: 0,
            inward_winding: true,
        };
        let hit = cube
            .intersect(Vec3::new(0.1, 0.2, 1.0), -Vec3::Z, 10.0)
            .unwrap();
        assert!((hit.t - 2.0).abs() < 1e-5 && (hit.normal + Vec3::Z).length() < 1e-6);
    }
}
