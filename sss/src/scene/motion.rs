//! Objects that move (docs/scene-format.md, "Moving objects"): an object's keyframed rigid
//! motion along the frames, and the scene's geometry posed at one frame.
//!
//! A key holds a rotation about the object's pivot (the centre of the bounds where its
//! `transform` placed it) and then a translation, at one frame. Between two keys the translation
//! is interpolated linearly and the rotation spherically (slerp, along the shorter arc); before
//! the first key the object rests at the first, after the last at the last. The motion is rigid,
//! so a point named by its triangle and barycentric coordinates (a sample's x2) keeps its
//! surface area from frame to frame; what changes is where x2 sees the lights (the shifts'
//! `pose_jacobian`).
//!
//! Lights do not move: an emissive object may not have a motion (its triangles are lights,
//! placed once), and the scene's lights keep the bounds of frame 0.

use std::borrow::Borrow;
use std::collections::VecDeque;
use std::sync::{Arc, Mutex};

use geometry::{BvhBuildParams, Geometry, TriangleMesh};
use glam::{Affine3A, Quat, Vec3};

/// An object's pose at one key frame, relative to where its `transform` placed it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Key {
    pub frame: u32,
    /// Rotation about the pivot.
    pub rotation: Quat,
    /// Translation after the rotation.
    pub translation: Vec3,
}

/// An object's keyframed rigid motion: at least one key, frames strictly increasing.
#[derive(Clone, Debug, PartialEq)]
pub struct Keyframes {
    pivot: Vec3,
    keys: Vec<Key>,
}

impl Keyframes {
    /// The motion through `keys` (non-empty, frames strictly increasing: the loader checks)
    /// about `pivot`.
    pub fn new(pivot: Vec3, keys: Vec<Key>) -> Keyframes {
        debug_assert!(!keys.is_empty() && keys.windows(2).all(|k| k[0].frame < k[1].frame));
        Keyframes { pivot, keys }
    }

    /// The frames of the first and the last key.
    fn span(&self) -> (u32, u32) {
        (self.keys[0].frame, self.keys[self.keys.len() - 1].frame)
    }

    /// The rigid map from the placed object to its pose at `frame`:
    /// `x ↦ R(f)·(x − pivot) + pivot + t(f)`.
    pub fn at(&self, frame: u32) -> Affine3A {
        let (rotation, translation) = self.interpolated(frame);
        Affine3A::from_rotation_translation(
            rotation,
            self.pivot + translation - rotation * self.pivot,
        )
    }

    /// `R(f)` and `t(f)`: the keys' values, interpolated between two keys.
    fn interpolated(&self, frame: u32) -> (Quat, Vec3) {
        let after = self.keys.partition_point(|k| k.frame <= frame);
        let (a, b) = match (after.checked_sub(1), self.keys.get(after)) {
            (Some(i), Some(b)) => (&self.keys[i], b),
            (Some(i), None) => return (self.keys[i].rotation, self.keys[i].translation),
            (None, _) => return (self.keys[0].rotation, self.keys[0].translation),
        };
        let s = (frame - a.frame) as f32 / (b.frame - a.frame) as f32;
        (
            a.rotation.slerp(b.rotation, s),
            a.translation.lerp(b.translation, s),
        )
    }
}

/// How many posed geometries a [`Motion`] keeps: a stream needs two frames at once, and the
/// replicas of a bias test, run side by side, a few more.
const POSED_KEPT: usize = 4;

/// The moving objects of a scene: every object's placed mesh and, for those that move, their
/// keyframes; [`Motion::geometry_at`] poses them at a frame.
pub struct Motion {
    meshes: Vec<TriangleMesh>,
    /// By object id; `None` for an object at rest.
    keyframes: Vec<Option<Keyframes>>,
    /// The last [`POSED_KEPT`] geometries built, by frame (a geometry depends on its frame
    /// alone, so a kept one is the one a new build would give).
    posed: Mutex<VecDeque<(u32, Arc<Geometry>)>>,
}

impl Motion {
    /// The motion of the objects with placed meshes `meshes` (by object id) and `keyframes`
    /// (same length; `None` at rest).
    pub fn new(meshes: Vec<TriangleMesh>, keyframes: Vec<Option<Keyframes>>) -> Motion {
        debug_assert_eq!(meshes.len(), keyframes.len());
        Motion {
            meshes,
            keyframes,
            posed: Mutex::new(VecDeque::with_capacity(POSED_KEPT)),
        }
    }

    /// The map from `object`'s placed mesh to its pose at `frame` (identity at rest).
    pub fn transform(&self, object: u32, frame: u32) -> Affine3A {
        match self.keyframes.get(object as usize) {
            Some(Some(keys)) => keys.at(frame),
            _ => Affine3A::IDENTITY,
        }
    }

    /// Whether `object` moves.
    pub fn moves(&self, object: u32) -> bool {
        matches!(self.keyframes.get(object as usize), Some(Some(_)))
    }

    /// The ids of the moving objects.
    pub fn moving_objects(&self) -> impl Iterator<Item = u32> + '_ {
        (0..self.keyframes.len() as u32).filter(|&o| self.moves(o))
    }

    /// The frame whose pose `frame` shows: `frame` clamped to the frames where some object is
    /// between its first and last key (before and after them every object holds a pose).
    pub fn settled(&self, frame: u32) -> u32 {
        let spans = self.keyframes.iter().flatten().map(Keyframes::span);
        let (first, last) = spans.fold((u32::MAX, 0), |(lo, hi), (a, b)| (lo.min(a), hi.max(b)));
        frame.clamp(first.min(last), last)
    }

    /// Point `p` of `object` at frame `from`, carried with the object to frame `to`.
    pub fn carry(&self, object: u32, from: u32, to: u32, p: Vec3) -> Vec3 {
        if !self.moves(object) {
            return p;
        }
        let placed = self.transform(object, from).inverse().transform_point3(p);
        self.transform(object, to).transform_point3(placed)
    }

    /// The scene's geometry at `frame`: each moving object posed, a new BVH built over all
    /// (obvhs's fast build; `docs/performance.md` has its cost per frame), or the one built last
    /// for the same pose ([`Motion::settled`]) where it is kept. Objects at rest keep their
    /// vertices bit for bit.
    pub fn geometry_at(&self, frame: u32) -> Arc<Geometry> {
        let frame = self.settled(frame);
        let kept = |posed: &VecDeque<(u32, Arc<Geometry>)>| {
            posed
                .iter()
                .find(|(f, _)| *f == frame)
                .map(|(_, g)| g.clone())
        };
        if let Some(geometry) = kept(&self.posed.lock().unwrap_or_else(|e| e.into_inner())) {
            return geometry;
        }
        let any = self
            .posed
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .front()
            .cloned();
        let geometry = Arc::new(self.build(frame, any.map(|(_, g)| g).as_deref()));
        let mut posed = self.posed.lock().unwrap_or_else(|e| e.into_inner());
        if posed.len() == POSED_KEPT {
            posed.pop_front();
        }
        posed.push_back((frame, geometry.clone()));
        geometry
    }

    /// A new BVH over the objects posed at `frame`; the trees of the objects at rest are
    /// `other`'s (a geometry of another frame) where there is one.
    fn build(&self, frame: u32, other: Option<&Geometry>) -> Geometry {
        let posed: Vec<Posed> = self
            .meshes
            .iter()
            .zip(&self.keyframes)
            .map(|(mesh, keys)| match keys {
                Some(keys) => Posed::Moved(mesh.transformed(&keys.at(frame))),
                None => Posed::Rest(mesh),
            })
            .collect();
        let params = BvhBuildParams::fast_build();
        match other {
            Some(other) => {
                let moved: Vec<bool> = self.keyframes.iter().map(Option::is_some).collect();
                other.reposed(&posed, &moved, params)
            }
            None => Geometry::with_build_params(&posed, params),
        }
    }
}

/// An object's mesh at one frame.
enum Posed<'a> {
    Rest(&'a TriangleMesh),
    Moved(TriangleMesh),
}

impl Borrow<TriangleMesh> for Posed<'_> {
    fn borrow(&self) -> &TriangleMesh {
        match self {
            Posed::Rest(mesh) => mesh,
            Posed::Moved(mesh) => mesh,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key(frame: u32, degrees: f32, translation: Vec3) -> Key {
        Key {
            frame,
            rotation: Quat::from_rotation_y(degrees.to_radians()),
            translation,
        }
    }

    /// Keys hold before the first and after the last; between two keys translation is linear
    /// and rotation turns about the pivot, which it leaves in place.
    #[test]
    fn keyframes_interpolate_between_their_keys_and_hold_outside() {
        let pivot = Vec3::new(1.0, 0.5, 0.0);
        let motion = Keyframes::new(
            pivot,
            vec![
                key(2, 0.0, Vec3::ZERO),
                key(6, 90.0, Vec3::new(4.0, 0.0, 0.0)),
            ],
        );
        assert_eq!(motion.at(0), motion.at(2));
        assert_eq!(motion.at(6), motion.at(100));
        assert_eq!(motion.span(), (2, 6));
        let halfway = motion.at(4);
        assert!(
            (halfway.transform_point3(pivot) - (pivot + Vec3::new(2.0, 0.0, 0.0))).length() < 1e-6
        );
        // 45° about y at frame 4: a point one unit along +x of the pivot turns toward −z.
        let p = halfway.transform_point3(pivot + Vec3::X) - halfway.transform_point3(pivot);
        let expected = Vec3::new(0.5f32.sqrt(), 0.0, -(0.5f32.sqrt()));
        assert!((p - expected).length() < 1e-6, "{p}");
        // Control: at the first key nothing has moved.
        assert!(
            (motion.at(2).transform_point3(Vec3::splat(3.0)) - Vec3::splat(3.0)).length() < 1e-6
        );
    }

    /// Carrying a point to another frame and back returns it, and an object at rest keeps its
    /// vertices bit for bit in every frame's geometry.
    #[test]
    fn carried_points_return_and_objects_at_rest_stay_put() {
        let cube = geometry::shapes::cuboid(Vec3::ONE);
        let floor = geometry::shapes::quad(4.0, 4.0);
        let keys = Keyframes::new(
            Vec3::ZERO,
            vec![
                key(0, 0.0, Vec3::ZERO),
                key(15, 120.0, Vec3::new(0.0, 0.0, 2.0)),
            ],
        );
        let motion = Motion::new(vec![cube, floor.clone()], vec![Some(keys), None]);
        let p = Vec3::new(0.5, 0.2, -0.3);
        let there = motion.carry(0, 3, 11, p);
        assert!((there - p).length() > 0.1, "the object moves");
        assert!((motion.carry(0, 11, 3, there) - p).length() < 1e-5);
        assert_eq!(motion.carry(1, 3, 11, p), p);
        // Past the last key the pose is the last key's: one geometry serves them all.
        assert_eq!((motion.settled(15), motion.settled(40)), (15, 15));
        assert!(Arc::ptr_eq(
            &motion.geometry_at(15),
            &motion.geometry_at(40)
        ));
        assert!(!Arc::ptr_eq(
            &motion.geometry_at(14),
            &motion.geometry_at(15)
        ));
        let g = motion.geometry_at(9);
        let first_floor = g.triangle_count() - floor.triangle_count() as u32;
        for (i, &[a, b, c]) in floor.indices.iter().enumerate() {
            let v = [a, b, c].map(|v| floor.positions[v as usize]);
            assert_eq!(g.vertices(first_floor + i as u32), v);
        }
        assert!(motion.moves(0) && !motion.moves(1));
    }
}
