//! Test fixtures shared by the geometry modules: an overlapping three-object scene, random rays
//! with axis-aligned and `±0.0` directions, and the brute-force reference for every query.

use glam::{Affine3A, Quat, Vec3, Vec3A};
use restir::rng::{Stream, StreamKey};

use super::Geometry;
use super::mesh::TriangleMesh;
use super::ray::{Hit, Ray};
use super::shapes;
use super::watertight::{PreparedRay, intersect_triangle};

const SEED: u64 = 0x6E0;

pub fn unit_vector(rng: &mut Stream) -> Vec3A {
    let z = 1.0 - 2.0 * rng.next_f32();
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = std::f32::consts::TAU * rng.next_f32();
    Vec3A::new(r * phi.cos(), r * phi.sin(), z)
}

/// Three objects that overlap in space: a bumpy sphere, a torus knot through it, and a box
/// with a quad (flat faces, so axis-aligned rays graze edges and hit faces head-on).
pub fn scene() -> Vec<TriangleMesh> {
    let mut boxes = shapes::cuboid(Vec3::new(0.4, 0.3, 0.5));
    let quad =
        shapes::quad(3.0, 3.0).transformed(&Affine3A::from_translation(Vec3::new(0.0, -1.2, 0.0)));
    let base = boxes.positions.len() as u32;
    boxes.positions.extend(&quad.positions);
    boxes
        .indices
        .extend(quad.indices.iter().map(|t| t.map(|i| i + base)));
    vec![
        shapes::bumpy_sphere(1.0, 0.1, 3.0, 5, 3),
        shapes::torus_knot(2, 3, 1.2, 0.15, 96, 8).transformed(
            &Affine3A::from_rotation_translation(
                Quat::from_rotation_y(0.4),
                Vec3::new(0.2, 0.1, 0.0),
            ),
        ),
        boxes.transformed(&Affine3A::from_translation(Vec3::new(0.5, 0.2, 0.3))),
    ]
}

/// Random rays through the scene bounds, then the same rays with axis-aligned directions and
/// with `±0.0` direction components (each sign of zero in each slot).
pub fn rays(count: usize) -> Vec<Ray> {
    let (lo, hi) = (Vec3A::splat(-2.0), Vec3A::splat(2.0));
    let mut rng = StreamKey::new(0, 0, 0, 0xB0B).stream(SEED);
    let mut rays = Vec::new();
    let axes = [Vec3A::X, Vec3A::Y, Vec3A::Z];
    for i in 0..count {
        let origin = lo + (hi - lo) * Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
        let dir = unit_vector(&mut rng);
        let t_min = if i % 3 == 0 {
            0.0
        } else {
            0.5 * rng.next_f32()
        };
        let t_max = if i % 2 == 0 {
            f32::INFINITY
        } else {
            t_min + 3.0 * rng.next_f32()
        };
        let signed_zero = |x: f32, keep: bool| {
            if keep {
                x
            } else {
                if x < 0.0 { -0.0 } else { 0.0 }
            }
        };
        let axis = axes[i % 3] * if rng.next_f32() < 0.5 { -1.0 } else { 1.0 };
        let (zx, zy) = (i % 4 < 2, i % 2 == 0);
        let zeroed = Vec3A::new(signed_zero(dir.x, zx), signed_zero(dir.y, zy), dir.z);
        for d in [dir, axis, -axis * 0.5, zeroed, -zeroed] {
            // Raw struct (not Ray::new) so that −0.0 reaches the queries uncanonicalised.
            rays.push(Ray {
                origin,
                dir: d,
                t_min,
                t_max,
            });
        }
    }
    assert!(rays.iter().any(|r| {
        r.dir
            .to_array()
            .iter()
            .any(|x| x.to_bits() == (-0.0f32).to_bits())
    }));
    rays
}

/// Every hit of `ray` over all triangles, sorted by (t, prim): the reference for all queries.
pub fn brute_force(geometry: &Geometry, ray: &Ray) -> Vec<Hit> {
    let Some(prepared) = PreparedRay::new(ray) else {
        return Vec::new();
    };
    let mut hits: Vec<Hit> = (0..geometry.triangle_count())
        .filter_map(|prim| {
            let tri = geometry.vertices(prim);
            intersect_triangle(&tri, &prepared, prepared.t_max).map(|(t, bary)| Hit {
                t,
                prim,
                object: geometry.object_of(prim),
                bary,
            })
        })
        .collect();
    hits.sort_by(|a, b| a.t.total_cmp(&b.t).then(a.prim.cmp(&b.prim)));
    hits
}

/// The bits of a hit, so comparisons tell `−0.0` from `+0.0`.
pub fn hit_bits(hit: &Hit) -> [u32; 5] {
    [
        hit.t.to_bits(),
        hit.prim,
        hit.object,
        hit.bary.x.to_bits(),
        hit.bary.y.to_bits(),
    ]
}
