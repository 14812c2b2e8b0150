//! The seeded emitter field (`[emitter_field]`): many small emissive rectangles of random size,
//! pose, colour and strength, for paper 001's many-lights scene on the Ajax bust (Fig. 7). Each
//! rectangle is an object (geometry: seen by the camera, occluding) whose two triangles are
//! lights.

use std::f32::consts::PI;

use geometry::{TriangleMesh, shapes};
use glam::{Affine3A, Quat, Vec3};
use restir::rng::{Stream, StreamKey};

use crate::material::Lambert;

/// `purpose` of the stream that draws rectangle `i` (`pixel = i`).
const EMITTER_FIELD_PURPOSE: u32 = 0x11A7_0002;

/// Draws of one rectangle before [`EmitterField::generate`] gives up on an exclusion box that
/// leaves too little room.
pub const MAX_DRAWS: u32 = 256;

/// The default colours: red, green, blue, yellow, magenta, cyan, white.
pub const DEFAULT_COLORS: [[f32; 3]; 7] = [
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
    [1.0, 1.0, 0.0],
    [1.0, 0.0, 1.0],
    [0.0, 1.0, 1.0],
    [1.0, 1.0, 1.0],
];

/// `count` rectangles: the 2 × 2 square `[−1, 1]²` of the xz-plane (normal +y) scaled per axis
/// by draws in `[scale_min, scale_max]`, rotated by a draw in [0, π) about an axis drawn in the
/// positive octant, centred uniformly in `[min, max]`, emitting `colors[k]` (k uniform) times a
/// strength uniform in [0, `strength`). A rectangle whose corners' bounding box reaches into the
/// box `exclude` is drawn again from its stream: an emitter that cuts through a translucent
/// object makes light sampling's variance infinite along the cut (the sampled contribution
/// grows as `1/‖x3 − x2‖²` there), which no number of replicas can measure.
#[derive(Clone, Debug, PartialEq)]
pub struct EmitterField {
    pub count: u32,
    pub seed: u64,
    pub min: Vec3,
    pub max: Vec3,
    pub scale_min: f32,
    pub scale_max: f32,
    pub strength: f32,
    pub colors: Vec<Vec3>,
    pub albedo: Vec3,
    pub two_sided: bool,
    /// `[min, max]` of the box no rectangle may reach into.
    pub exclude: Option<[Vec3; 2]>,
}

impl EmitterField {
    /// The rectangles in world space with their materials; rectangle `i` depends only on
    /// `(seed, i)`. `Err(i)`: rectangle `i` reached into the exclusion box in all of its
    /// [`MAX_DRAWS`] draws. Inputs must be validated (non-empty colours, ordered ranges).
    pub fn generate(&self) -> Result<Vec<(TriangleMesh, Lambert)>, u32> {
        let square = shapes::quad(2.0, 2.0);
        (0..self.count)
            .map(|i| {
                let mut rng = StreamKey::new(i, 0, 0, EMITTER_FIELD_PURPOSE).stream(self.seed);
                (0..MAX_DRAWS)
                    .map(|_| self.draw(&square, &mut rng))
                    .find(|(mesh, _)| !self.excluded(mesh))
                    .ok_or(i)
            })
            .collect()
    }

    /// One rectangle and its material from `rng`.
    fn draw(&self, square: &TriangleMesh, rng: &mut Stream) -> (TriangleMesh, Lambert) {
        let mut draw3 = || Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
        let scale = self.scale_min + draw3() * (self.scale_max - self.scale_min);
        let center = self.min + draw3() * (self.max - self.min);
        // An axis of the positive octant; a zero draw keeps the square unrotated.
        let axis = draw3().try_normalize().unwrap_or(Vec3::Y);
        let angle = rng.next_f32() * PI;
        let k = (rng.next_f32() * self.colors.len() as f32) as usize;
        let color = self.colors[k.min(self.colors.len() - 1)];
        let strength = rng.next_f32() * self.strength;
        let xf = Affine3A::from_scale_rotation_translation(
            scale,
            Quat::from_axis_angle(axis, angle),
            center,
        );
        let material = Lambert {
            albedo: self.albedo,
            emission: color * strength,
            two_sided: self.two_sided,
        };
        (square.transformed(&xf), material)
    }

    /// Whether `mesh`'s bounding box overlaps the exclusion box.
    fn excluded(&self, mesh: &TriangleMesh) -> bool {
        let Some([lo, hi]) = self.exclude else {
            return false;
        };
        let (a, b) = mesh.bounds();
        a.cmple(hi).all() && b.cmpge(lo).all()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn field(seed: u64) -> EmitterField {
        EmitterField {
            count: 64,
            seed,
            min: Vec3::splat(-20.0),
            max: Vec3::splat(20.0),
            scale_min: 0.05,
            scale_max: 1.0,
            strength: 48.0,
            colors: DEFAULT_COLORS.map(Vec3::from_array).to_vec(),
            albedo: Vec3::ONE,
            two_sided: true,
            exclude: None,
        }
    }

    /// Rectangles lie in the box (centres inside it, corners within the largest half-diagonal),
    /// have the drawn sizes, emit a listed colour times a strength below the cap, depend on the
    /// seed, and rectangle `i` does not depend on the count.
    #[test]
    fn rectangles_are_seeded_and_within_their_ranges() {
        let a = field(0).generate().unwrap();
        assert_eq!(a.len(), 64);
        let reach = 2f32.sqrt();
        for (mesh, lambert) in &a {
            assert_eq!((mesh.positions.len(), mesh.indices.len()), (4, 2));
            let centre = mesh.positions.iter().sum::<Vec3>() / 4.0;
            assert!(centre.abs().max_element() <= 20.0, "{centre}");
            for p in &mesh.positions {
                assert!(p.distance(centre) <= reach + 1e-4, "{p} vs {centre}");
            }
            let area = mesh.area();
            assert!(
                (4.0 * 0.05f64.powi(2) - 1e-6..=4.0 + 1e-5).contains(&area),
                "{area}"
            );
            let strength = lambert.emission.max_element();
            assert!((0.0..48.0).contains(&strength), "{strength}");
            let color = lambert.emission / strength;
            assert!(
                DEFAULT_COLORS
                    .iter()
                    .any(|&c| (Vec3::from_array(c) - color).abs().max_element() < 1e-6),
                "{color}"
            );
            assert!(lambert.two_sided && lambert.albedo == Vec3::ONE);
        }
        assert_ne!(a, field(1).generate().unwrap());
        let fewer = EmitterField {
            count: 10,
            ..field(0)
        };
        assert_eq!(fewer.generate().unwrap()[..], a[..10]);
        let colours: std::collections::HashSet<[u32; 3]> = a
            .iter()
            .map(|(_, l)| {
                (l.emission / l.emission.max_element())
                    .to_array()
                    .map(f32::to_bits)
            })
            .collect();
        assert!(colours.len() >= 5, "{colours:?}");
    }

    /// With an exclusion box every rectangle stays out of it (its corners' box does not reach
    /// in), the rectangles that did not reach in are unchanged, and a box that covers the whole
    /// region leaves no room: the rectangle that could not be placed is named.
    #[test]
    fn the_exclusion_box_keeps_rectangles_out() {
        let free = field(3).generate().unwrap();
        let excluded = EmitterField {
            exclude: Some([Vec3::new(-8.0, -12.0, -6.0), Vec3::new(8.0, 12.0, 6.0)]),
            ..field(3)
        };
        let kept = excluded.generate().unwrap();
        let mut unchanged = 0;
        for ((mesh, _), (before, _)) in kept.iter().zip(&free) {
            assert!(!excluded.excluded(mesh));
            unchanged += usize::from(mesh == before);
        }
        let reaching = free.iter().filter(|(m, _)| excluded.excluded(m)).count();
        assert!(reaching > 0, "the box is in the way of some first draws");
        assert_eq!(unchanged, free.len() - reaching);
        let everywhere = EmitterField {
            exclude: Some([Vec3::splat(-30.0), Vec3::splat(30.0)]),
            ..field(3)
        };
        assert_eq!(everywhere.generate(), Err(0));
    }
}
