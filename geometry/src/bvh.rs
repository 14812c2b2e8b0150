//! The scene's triangles and the ray queries over them (closest hit, occlusion, closest hit and
//! all hits on one object).
//!
//! One obvhs binary BVH (PLOC + reinsertion) is built over all objects' triangles and converted
//! twice: into obvhs's CWBVH (compressed 8-wide, Ylitie et al. 2017), exported as is for the
//! GPU twin (`glsl/bvh.glsl`), and into the CPU layout of `wide.rs` (uncompressed 8-wide
//! nodes, four-triangle packets), traversed by `traverse.rs` with the SIMD kernels of
//! `kernel/`. Scenes of several objects also get one such tree per object: the
//! object-restricted queries (the BSSRDF probe's) walk it, so it is their object filter and they
//! never visit another object's nodes. Triangles use the watertight test of Woop, Benthin & Wald 2013
//! (`watertight.rs`), so a ray through a shared edge or vertex of a closed mesh cannot slip
//! between triangles, and every kernel returns the same hits bit for bit.
//!
//! Box entry is clamped to the ray's `t_min`, inverse directions are exact down to 1e-20, and
//! box exits are pushed out by `2γ₃` of their magnitude (Ize 2013, *Robust BVH Ray Traversal*)
//! so rounding cannot cull a box the ray touches. (obvhs's own `CwBvhNode::intersect_ray` clamps
//! entry to an absolute 1e-4 and uses `±1/ε` for near-zero direction components.) Residual
//! limit: a ray with a zero direction component that runs exactly in a child box's face plane
//! can miss that box (a measure-zero grazing case).

use std::borrow::Borrow;
use std::mem::MaybeUninit;

use glam::{Vec2, Vec3};
use obvhs::{
    BvhBuildParams,
    bvh2::{Bvh2, reinsertion::ReinsertionOptimizer},
    cwbvh::{CwBvh, bvh2_to_cwbvh::bvh2_to_cwbvh},
    ploc::PlocBuilder,
    triangle::Triangle,
};

use super::kernel::KernelKind;
#[cfg(any(test, not(target_arch = "x86_64")))]
use super::kernel::Portable;
#[cfg(target_arch = "x86_64")]
use super::kernel::{Avx2, Sse2};
use super::mesh::TriangleMesh;
use super::query::{AllHits, Closest, Occluded, Query};
use super::ray::{Hit, Ray};
use super::watertight::PreparedRay;
use super::wide::WideBvh;

/// The scene's triangles: per-triangle data by global id, the device CWBVH and the CPU BVH.
///
/// Global triangle ids concatenate the objects' triangles in object order. Degenerate triangles
/// are kept (so ids match the input meshes) but never hit; drop them beforehand with
/// [`TriangleMesh::drop_degenerate`].
pub struct Geometry {
    /// The device export (obvhs CWBVH), not traversed on the CPU.
    bvh: CwBvh,
    /// Every object's triangles, for the unrestricted queries.
    wide: WideBvh,
    /// One tree per object for the object-restricted queries (the SSS probe's), which then
    /// never visit another object's nodes; empty when the scene has one object (`wide` serves).
    object_trees: Vec<WideBvh>,
    /// The box and triangle tests' instruction set (all give the same hits).
    kernel: KernelKind,
    vertices: Vec<[Vec3; 3]>,
    /// Per-vertex shading normals by global id (the geometric normal where a mesh has none).
    shading_normals: Vec<[Vec3; 3]>,
    objects: Vec<u32>,
    object_count: u32,
}

/// obvhs's medium preset with a full reinsertion pass (every node considered once) and the PLOC
/// search widened from depth 1: on the traversal benchmark's meshes this costs about three times
/// the build time (≈ 0.35 s for 100k triangles) and saves 5–20% of the traversal time of every
/// query (`docs/performance.md`).
fn build_params() -> BvhBuildParams {
    BvhBuildParams {
        reinsertion_batch_ratio: 1.0,
        search_depth_threshold: 1,
        ..BvhBuildParams::medium_build()
    }
}

/// obvhs's binary BVH as `build_cwbvh_from_tris` builds it without spatial splits: PLOC, then
/// reinsertion.
fn build_bvh2(triangles: &[Triangle], params: &BvhBuildParams) -> Bvh2 {
    let mut bvh2 = PlocBuilder::with_capacity(triangles.len()).build(
        params.ploc_search_distance,
        triangles,
        (0..triangles.len() as u32).collect(),
        params.sort_precision,
        params.search_depth_threshold,
    );
    ReinsertionOptimizer::default().run(&mut bvh2, params.reinsertion_batch_ratio, None);
    bvh2
}

impl Geometry {
    /// Builds the BVH over all objects; object id = index in `objects`.
    ///
    /// Panics if a mesh indexes past its positions or has non-finite vertices (the loaders and
    /// shapes never produce such meshes; this is a programming error, not bad input).
    pub fn new<M: Borrow<TriangleMesh>>(objects: &[M]) -> Geometry {
        Geometry::with_build_params(objects, build_params())
    }

    /// [`Geometry::new`] with explicit obvhs build parameters (quality vs build time).
    /// `pre_split` is ignored: with spatial splits a triangle can sit in several leaves, and
    /// all-hits queries would report it more than once.
    pub fn with_build_params<M: Borrow<TriangleMesh>>(
        objects: &[M],
        params: BvhBuildParams,
    ) -> Geometry {
        Geometry::build(objects, params, |_| None)
    }

    /// [`Geometry::with_build_params`] for `objects` that equal the objects this geometry was
    /// built from, triangle for triangle, except those marked in `moved` (a moving object's
    /// pose at another frame): the trees of the objects at rest are this geometry's, cloned;
    /// the scene's trees and the moved objects' are built anew. The same geometry as a full
    /// build with `params` where this one was built with them.
    pub fn reposed<M: Borrow<TriangleMesh>>(
        &self,
        objects: &[M],
        moved: &[bool],
        params: BvhBuildParams,
    ) -> Geometry {
        Geometry::build(objects, params, |object| {
            let kept = !moved.get(object).copied().unwrap_or(true);
            kept.then(|| self.object_trees.get(object).cloned())
                .flatten()
        })
    }

    /// The build of [`Geometry::with_build_params`] that takes object `i`'s own tree from
    /// `kept(i)` where it gives one.
    fn build<M: Borrow<TriangleMesh>>(
        objects: &[M],
        params: BvhBuildParams,
        kept: impl Fn(usize) -> Option<WideBvh>,
    ) -> Geometry {
        let mut vertices = Vec::new();
        let mut shading_normals = Vec::new();
        let mut object_of = Vec::new();
        for (object, mesh) in objects.iter().map(Borrow::borrow).enumerate() {
            for (i, &[a, b, c]) in mesh.indices.iter().enumerate() {
                let tri = [a, b, c].map(|v| {
                    let p = *mesh.positions.get(v as usize).unwrap_or_else(|| {
                        panic!("object {object} triangle {i}: vertex index {v} out of range")
                    });
                    assert!(
                        p.is_finite(),
                        "object {object} triangle {i}: non-finite vertex {p}"
                    );
                    p
                });
                let geometric = (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalize_or_zero();
                let normals = match &mesh.normals {
                    Some(normals) => [a, b, c].map(|v| normals[v as usize]),
                    None => [geometric; 3],
                };
                vertices.push(tri);
                shading_normals.push(normals);
                object_of.push(object as u32);
            }
        }
        let triangles: Vec<Triangle> = vertices
            .iter()
            .map(|&[v0, v1, v2]| Triangle {
                v0: v0.into(),
                v1: v1.into(),
                v2: v2.into(),
            })
            .collect();
        let (bvh, wide) = if triangles.is_empty() {
            (CwBvh::default(), WideBvh::default())
        } else {
            let bvh2 = build_bvh2(&triangles, &params);
            (
                bvh2_to_cwbvh(&bvh2, params.max_prims_per_leaf.clamp(1, 3), true, false),
                WideBvh::from_bvh2(&bvh2, &vertices, &object_of),
            )
        };
        let mut object_trees = Vec::new();
        if objects.len() > 1 {
            let mut first = 0;
            for (object, mesh) in objects.iter().map(Borrow::borrow).enumerate() {
                let own = &triangles[first..first + mesh.indices.len()];
                let tree = if let Some(tree) = kept(object) {
                    tree
                } else if own.is_empty() {
                    WideBvh::default()
                } else {
                    let mut bvh2 = build_bvh2(own, &params);
                    // Local triangle indices to global ids (objects are contiguous).
                    bvh2.primitive_indices
                        .iter_mut()
                        .for_each(|prim| *prim += first as u32);
                    WideBvh::from_bvh2(&bvh2, &vertices, &object_of)
                };
                object_trees.push(tree);
                first += mesh.indices.len();
            }
        }
        Geometry {
            bvh,
            wide,
            object_trees,
            kernel: KernelKind::detect(),
            vertices,
            shading_normals,
            objects: object_of,
            object_count: objects.len() as u32,
        }
    }

    /// The tree of `object`'s triangles alone (`object` < `object_count`): its own, or with a
    /// single object the scene's.
    fn tree_of(&self, object: u32) -> &WideBvh {
        self.object_trees.get(object as usize).unwrap_or(&self.wide)
    }

    /// Runs `query` on `bvh` with this geometry's kernel.
    #[inline(always)]
    fn run<Q: Query>(&self, bvh: &WideBvh, query: Q, ray: &PreparedRay) -> Q::Output {
        WideBvh::with_slots(Q::slots(bvh), |slots| match self.kernel {
            // SAFETY: `KernelKind::detect` found AVX2 and POPCNT on this machine.
            #[cfg(target_arch = "x86_64")]
            KernelKind::Avx2 => unsafe { run_avx2(query, bvh, ray, slots) },
            // SAFETY: SSE2 is part of the x86-64 baseline.
            #[cfg(target_arch = "x86_64")]
            KernelKind::Sse2 => unsafe { query.run::<Sse2>(bvh, ray, slots) },
            // SAFETY: plain Rust.
            #[cfg(any(test, not(target_arch = "x86_64")))]
            KernelKind::Portable => unsafe { query.run::<Portable>(bvh, ray, slots) },
        })
    }

    /// The closest hit with `t_min < t < t_max`; ties in `t` go to the lower triangle id.
    pub fn closest_hit(&self, ray: &Ray) -> Option<Hit> {
        self.run(&self.wide, Closest, &PreparedRay::new(ray)?)
    }

    /// The closest hit on triangles of `object` only (none for an object id out of range).
    pub fn closest_hit_on_object(&self, ray: &Ray, object: u32) -> Option<Hit> {
        if object >= self.object_count {
            return None;
        }
        self.run(self.tree_of(object), Closest, &PreparedRay::new(ray)?)
    }

    /// Whether any triangle is hit with `t_min < t < t_max` (shadow rays).
    pub fn occluded(&self, ray: &Ray) -> bool {
        PreparedRay::new(ray).is_some_and(|ray| self.run(&self.wide, Occluded, &ray))
    }

    /// Clears `out` and fills it with every hit on `object` in `(t_min, t_max)` (none for an
    /// object id out of range), sorted by `t`, ties broken by triangle id: the rank of a hit in
    /// `out` is the BSSRDF probe's intersection index [001 §2.1] and must not depend on
    /// traversal order.
    pub fn all_hits_on_object(&self, ray: &Ray, object: u32, out: &mut Vec<Hit>) {
        out.clear();
        if object >= self.object_count {
            return;
        }
        if let Some(ray) = PreparedRay::new(ray) {
            self.run(self.tree_of(object), AllHits { out }, &ray);
            out.sort_unstable_by(|a, b| a.t.total_cmp(&b.t).then(a.prim.cmp(&b.prim)));
        }
    }

    pub fn object_of(&self, prim: u32) -> u32 {
        self.objects[prim as usize]
    }

    pub fn vertices(&self, prim: u32) -> [Vec3; 3] {
        self.vertices[prim as usize]
    }

    /// `(1 − u − v)·v0 + u·v1 + v·v2`.
    pub fn position(&self, prim: u32, bary: Vec2) -> Vec3 {
        let [v0, v1, v2] = self.vertices(prim);
        v0 + bary.x * (v1 - v0) + bary.y * (v2 - v0)
    }

    /// Unit `(v1 − v0) × (v2 − v0)`; zero for a degenerate triangle.
    pub fn geometric_normal(&self, prim: u32) -> Vec3 {
        let [v0, v1, v2] = self.vertices(prim);
        (v1 - v0).cross(v2 - v0).normalize_or_zero()
    }

    /// The per-vertex shading normals of `prim` as stored (the geometric normal where the mesh
    /// has none), for the GPU twin of [`Geometry::shading_normal`].
    pub fn vertex_normals(&self, prim: u32) -> [Vec3; 3] {
        self.shading_normals[prim as usize]
    }

    /// Interpolated per-vertex normal, renormalised; the geometric normal where the mesh has no
    /// normals or the interpolated one vanishes.
    pub fn shading_normal(&self, prim: u32, bary: Vec2) -> Vec3 {
        let [n0, n1, n2] = self.shading_normals[prim as usize];
        let n = (1.0 - bary.x - bary.y) * n0 + bary.x * n1 + bary.y * n2;
        n.try_normalize()
            .unwrap_or_else(|| self.geometric_normal(prim))
    }

    pub fn triangle_area(&self, prim: u32) -> f32 {
        let [v0, v1, v2] = self.vertices(prim);
        0.5 * (v1 - v0).cross(v2 - v0).length()
    }

    pub fn object_count(&self) -> u32 {
        self.object_count
    }

    pub fn triangle_count(&self) -> u32 {
        self.vertices.len() as u32
    }

    /// The CPU BVH, for the kernel and layout tests.
    #[cfg(test)]
    pub(super) fn wide(&self) -> &WideBvh {
        &self.wide
    }

    /// The CWBVH (nodes and leaf-slot → triangle id map), for upload to the GPU.
    pub fn bvh(&self) -> &CwBvh {
        &self.bvh
    }
}

/// [`Query::run`] compiled for AVX2 (and POPCNT, which every AVX2 machine has: the child
/// counts of [`Kernel::partition`](super::kernel::Kernel::partition)).
///
/// # Safety
/// AVX2 and POPCNT must be available.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,popcnt")]
unsafe fn run_avx2<Q: Query>(
    query: Q,
    bvh: &WideBvh,
    ray: &PreparedRay,
    slots: &mut [MaybeUninit<Q::Slot>],
) -> Q::Output {
    // SAFETY: forwarded from the caller.
    unsafe { query.run::<Avx2>(bvh, ray, slots) }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes;
    use crate::testing::{brute_force, hit_bits, rays, scene, unit_vector};
    use crate::traverse::INLINE_SLOTS;
    use crate::watertight::intersect_triangle;
    use glam::{Affine3A, Vec3, Vec3A};
    use obvhs::ray::RayHit;
    use restir::rng::StreamKey;

    const SEED: u64 = 0x6E0;

    /// Stock obvhs 0.4 closest hit (its own node test and ±0.0 handling), same triangle test.
    fn stock_obvhs_closest(geometry: &Geometry, ray: &Ray) -> Option<(u32, f32)> {
        let prepared = PreparedRay::new(ray)?;
        let stock = obvhs::ray::Ray::new(ray.origin, ray.dir, ray.t_min, ray.t_max);
        let mut hit = RayHit::none();
        geometry.bvh.ray_traverse(stock, &mut hit, |r, slot| {
            let tri = geometry.vertices(geometry.bvh.primitive_indices[slot]);
            intersect_triangle(&tri, &prepared, r.tmax).map_or(f32::INFINITY, |h| h.0)
        });
        (hit.t < ray.t_max).then(|| {
            (
                geometry.bvh.primitive_indices[hit.primitive_id as usize],
                hit.t,
            )
        })
    }

    /// Every query with every kernel of this machine against brute force, bit for bit;
    /// returns (hits, chords with two or more hits on one object) to show what was exercised.
    fn assert_matches_brute_force(geometry: &mut Geometry, rays: &[Ray]) -> (usize, usize) {
        let bits = |hits: &[Hit]| hits.iter().map(hit_bits).collect::<Vec<_>>();
        let (mut hits_total, mut multi) = (0, 0);
        let mut out = Vec::new();
        for kernel in KernelKind::available() {
            geometry.kernel = kernel;
            for ray in rays {
                let reference = brute_force(geometry, ray);
                let closest = reference.first().copied();
                assert_eq!(
                    bits(geometry.closest_hit(ray).as_slice()),
                    bits(closest.as_slice()),
                    "{kernel:?}: closest hit, {ray:?}"
                );
                assert_eq!(
                    geometry.occluded(ray),
                    closest.is_some(),
                    "{kernel:?}: occluded, {ray:?}"
                );
                for object in 0..geometry.object_count() {
                    let on_object: Vec<Hit> = reference
                        .iter()
                        .copied()
                        .filter(|h| h.object == object)
                        .collect();
                    geometry.all_hits_on_object(ray, object, &mut out);
                    assert_eq!(
                        bits(&out),
                        bits(&on_object),
                        "{kernel:?}: all hits on object {object}, {ray:?}"
                    );
                    assert_eq!(
                        bits(geometry.closest_hit_on_object(ray, object).as_slice()),
                        bits(&on_object[..on_object.len().min(1)]),
                        "{kernel:?}: closest hit on object {object}, {ray:?}"
                    );
                    multi += usize::from(on_object.len() >= 2);
                }
                hits_total += reference.len();
            }
        }
        (hits_total, multi)
    }

    #[test]
    fn queries_match_brute_force() {
        let rays = rays(400);
        let (hits, multi) = assert_matches_brute_force(&mut Geometry::new(&scene()), &rays);
        // The comparison must exercise something: many hits, and many multi-hit chords.
        let kernels = KernelKind::available().len();
        assert!(
            hits > kernels * rays.len() / 4 && multi > kernels * rays.len() / 10,
            "{hits} hits, {multi} multi-hit"
        );
    }

    #[test]
    fn deep_trees_use_a_heap_stack() {
        // Nested triangles shrinking geometrically toward a point: the binary tree is a chain,
        // deeper than the inline traversal storage, so queries run on the heap stack.
        let mesh = TriangleMesh {
            positions: (0..1500)
                .flat_map(|i| {
                    let s = 0.95f32.powi(i);
                    [
                        Vec3::new(s, 0.0, 0.0),
                        Vec3::new(s, s, 0.0),
                        Vec3::new(s, 0.0, s),
                    ]
                })
                .collect(),
            indices: (0..1500).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect(),
            normals: None,
        };
        let mut geometry = Geometry::new(&[mesh]);
        assert!(
            geometry.wide.nearest_slots() > INLINE_SLOTS
                && geometry.wide.unordered_slots() > INLINE_SLOTS,
            "stack depth {}",
            geometry.wide.stack_depth
        );
        let mut rng = StreamKey::new(0, 0, 0, 0xDEE9).stream(SEED);
        let rays: Vec<Ray> = (0..300)
            .map(|_| {
                let target = Vec3A::new(0.3, 0.05, 0.05) * rng.next_f32();
                let origin = Vec3A::new(-1.0, 0.02, 0.02) + 0.01 * unit_vector(&mut rng);
                Ray::new(origin, target - origin, 0.0, f32::INFINITY)
            })
            .collect();
        let (hits, multi) = assert_matches_brute_force(&mut geometry, &rays);
        assert!(hits > 1000 && multi > 100, "{hits} hits, {multi} multi-hit");
    }

    #[test]
    fn device_export_is_the_obvhs_cwbvh() {
        // The GPU traverses `Geometry::bvh()`: it must stay exactly what obvhs builds.
        let meshes = scene();
        let triangles: Vec<Triangle> = meshes
            .iter()
            .flat_map(|m| (0..m.triangle_count()).map(|i| m.triangle(i)))
            .map(|[v0, v1, v2]| Triangle {
                v0: v0.into(),
                v1: v1.into(),
                v2: v2.into(),
            })
            .collect();
        let stock = obvhs::cwbvh::builder::build_cwbvh_from_tris(
            &triangles,
            build_params(),
            &mut std::time::Duration::default(),
        );
        assert!(Geometry::new(&meshes).bvh() == &stock);
        // Negative control: another build preset gives another tree.
        let other = obvhs::cwbvh::builder::build_cwbvh_from_tris(
            &triangles,
            BvhBuildParams::fast_build(),
            &mut std::time::Duration::default(),
        );
        assert!(Geometry::new(&meshes).bvh() != &other);
    }

    #[test]
    fn negative_zero_directions_break_stock_obvhs_but_not_ours() {
        // Negative control for the test above: stock obvhs traversal with uncanonicalised −0.0
        // components disagrees with brute force on some rays; ours (same rays) never does.
        let geometry = Geometry::new(&scene());
        let rays: Vec<Ray> = rays(400)
            .into_iter()
            .filter(|r| {
                r.dir
                    .to_array()
                    .iter()
                    .any(|x| x.to_bits() == (-0.0f32).to_bits())
            })
            .collect();
        let reference = |ray: &Ray| brute_force(&geometry, ray).first().map(|h| (h.prim, h.t));
        let stock_misses = rays
            .iter()
            .filter(|r| stock_obvhs_closest(&geometry, r) != reference(r))
            .count();
        let ours = rays
            .iter()
            .filter(|r| geometry.closest_hit(r).map(|h| (h.prim, h.t)) != reference(r))
            .count();
        assert!(
            stock_misses > 0,
            "stock obvhs agreed on all {} −0.0 rays",
            rays.len()
        );
        assert_eq!(ours, 0, "of {} −0.0 rays", rays.len());
    }

    #[test]
    fn hits_closer_than_obvhs_epsilon_are_found() {
        // obvhs 0.4 clamps box entry to 1e-4: a hit at t = 5e-5 is lost by the stock traversal.
        let geometry = Geometry::new(&[shapes::quad(1.0, 1.0)]);
        for (height, stock_finds) in [(5e-5f32, false), (2e-4, true)] {
            let ray = Ray::new(
                Vec3A::new(0.1, height, 0.2),
                Vec3A::NEG_Y,
                0.0,
                f32::INFINITY,
            );
            let hit = geometry.closest_hit(&ray).expect("hit below the quad");
            assert!(
                (hit.t - height).abs() <= 1e-6 * height.max(1.0),
                "t = {} for height {height}",
                hit.t
            );
            assert!(geometry.occluded(&ray));
            assert_eq!(
                stock_obvhs_closest(&geometry, &ray).is_some(),
                stock_finds,
                "stock obvhs at {height}"
            );
            // t_min excludes the hit.
            assert!(
                geometry
                    .closest_hit(&Ray {
                        t_min: height * 1.01,
                        ..ray
                    })
                    .is_none()
            );
        }
    }

    #[test]
    fn interval_is_open_at_both_ends() {
        let geometry = Geometry::new(&[shapes::quad(1.0, 1.0)]);
        let down = |t_min, t_max| Ray::new(Vec3A::new(0.1, 1.0, 0.2), Vec3A::NEG_Y, t_min, t_max);
        assert!(geometry.occluded(&down(0.0, 1.5)));
        assert!(!geometry.occluded(&down(0.0, 1.0)), "t_max is exclusive");
        assert!(!geometry.occluded(&down(1.0, 2.0)), "t_min is exclusive");
        assert!(geometry.closest_hit(&down(0.0, 0.0)).is_none());
        assert!(
            geometry
                .closest_hit(&Ray::new(Vec3A::ZERO, Vec3A::ZERO, 0.0, 1.0))
                .is_none(),
            "zero direction"
        );
    }

    #[test]
    fn hit_attributes_are_consistent() {
        let meshes = scene();
        let geometry = Geometry::new(&meshes);
        assert_eq!(geometry.object_count(), 3);
        let total: usize = meshes.iter().map(TriangleMesh::triangle_count).sum();
        assert_eq!(geometry.triangle_count() as usize, total);
        let area: f64 = (0..geometry.triangle_count())
            .map(|p| geometry.triangle_area(p) as f64)
            .sum();
        let expected: f64 = meshes.iter().map(TriangleMesh::area).sum();
        assert!(
            (area - expected).abs() < 1e-5 * expected,
            "{area} vs {expected}"
        );
        let mut checked = 0;
        for ray in rays(200) {
            let Some(hit) = geometry.closest_hit(&ray) else {
                continue;
            };
            let p = geometry.position(hit.prim, hit.bary);
            let scale = 1.0 + ray.origin.length() + hit.t * ray.dir.length();
            assert!(
                (Vec3A::from(p) - ray.at(hit.t)).length() < 1e-5 * scale,
                "position vs ray.at(t)"
            );
            let [v0, v1, v2] = geometry.vertices(hit.prim);
            let n = geometry.geometric_normal(hit.prim);
            assert!((n - (v1 - v0).cross(v2 - v0).normalize()).length() < 1e-6);
            let s = geometry.shading_normal(hit.prim, hit.bary);
            assert!(
                (s.length() - 1.0).abs() < 1e-5 && s.dot(n) > 0.0,
                "shading {s} vs geometric {n}"
            );
            if hit.object == 2 {
                assert_eq!(s, n, "flat meshes shade with the geometric normal");
            }
            checked += 1;
        }
        assert!(checked > 100, "{checked} hits checked");
    }

    #[test]
    fn triangle_test_matches_double_precision_reference() {
        // Reference: Möller–Trumbore in f64 on rays aimed at interior points of random triangles.
        let mut rng = StreamKey::new(0, 0, 0, 0x7E57).stream(SEED);
        let (mut worst, mut swapped) = ((0.0f64, 0.0f64), 0.0f64);
        for _ in 0..2000 {
            let tri = [0; 3]
                .map(|_| Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - 1.0);
            let (b1, b2) = (0.05 + 0.45 * rng.next_f32(), 0.05 + 0.45 * rng.next_f32());
            let target = Vec3A::from(tri[0] + b1 * (tri[1] - tri[0]) + b2 * (tri[2] - tri[0]));
            let origin = target + 3.0 * unit_vector(&mut rng);
            let ray = Ray::new(origin, (target - origin).normalize(), 0.0, f32::INFINITY);
            let prepared = PreparedRay::new(&ray).unwrap();
            let d = |v: Vec3A| v.as_dvec3();
            let (e1, e2) = ((tri[1] - tri[0]).as_dvec3(), (tri[2] - tri[0]).as_dvec3());
            let p = d(ray.dir).cross(e2);
            let det = e1.dot(p);
            if det.abs() < 1e-3 {
                continue;
            }
            let s = d(ray.origin) - tri[0].as_dvec3();
            let (u, q) = (s.dot(p) / det, s.cross(e1));
            let (v, t) = (d(ray.dir).dot(q) / det, e2.dot(q) / det);
            let (t32, bary) =
                intersect_triangle(&tri, &prepared, f32::INFINITY).expect("aimed ray hits");
            worst.0 = worst.0.max((t32 as f64 - t).abs());
            worst.1 = worst
                .1
                .max((bary.x as f64 - u).abs().max((bary.y as f64 - v).abs()));
            swapped = swapped.max((bary.y as f64 - u).abs().max((bary.x as f64 - v).abs()));
        }
        assert!(
            worst.0 < 1e-4 && worst.1 < 1e-3,
            "worst |Δt| {}, |Δbary| {}",
            worst.0,
            worst.1
        );
        // Negative control: the same comparison rejects barycentrics given in the wrong order.
        assert!(
            swapped > 1e-3,
            "swapped barycentrics not detected: {swapped}"
        );
    }

    #[test]
    fn rays_through_shared_edges_and_vertices_never_slip_through() {
        // Rays from outside aimed at vertices and edge midpoints of a closed sphere far from the
        // origin (large coordinates, so rounding is coarse) must hit it. Negative control: a
        // cracked variant that rejects hits within 10⁻³ (barycentric) of an edge misses some.
        let centre = Vec3::new(300.3, -200.2, 100.1);
        let sphere =
            shapes::uv_sphere(1.0, 37, 19).transformed(&Affine3A::from_translation(centre));
        let geometry = Geometry::new(std::slice::from_ref(&sphere));
        let mut rng = StreamKey::new(0, 0, 0, 0xED6E).stream(SEED);
        let (mut missed, mut cracked_missed, mut count) = (0, 0, 0);
        for &[a, b, c] in &sphere.indices {
            let [pa, pb, pc] = [a, b, c].map(|i| Vec3A::from(sphere.positions[i as usize]));
            for target in [pa, 0.5 * (pa + pb), 0.5 * (pb + pc), 0.5 * (pc + pa)] {
                // Within 60° of the outward normal, so the ray crosses the surface at the
                // target (a grazing ray may rightly pass beside a silhouette edge).
                let outward = (target - Vec3A::from(centre)).normalize();
                let mut offset = unit_vector(&mut rng);
                while offset.dot(outward) < 0.5 {
                    offset = unit_vector(&mut rng);
                }
                let origin = target + 3.0 * offset;
                let ray = Ray::new(origin, target - origin, 0.0, f32::INFINITY);
                let hits = brute_force(&geometry, &ray);
                missed += usize::from(geometry.closest_hit(&ray).is_none() || hits.is_empty());
                // The target is at t = 1; the far side of the sphere is at t > 1.3.
                let near = |h: &Hit| (h.t - 1.0).abs() < 1e-3;
                missed += usize::from(!hits.iter().any(near));
                let interior =
                    |h: &Hit| h.bary.x.min(h.bary.y).min(1.0 - h.bary.x - h.bary.y) >= 1e-3;
                cracked_missed += usize::from(!hits.iter().any(|h| near(h) && interior(h)));
                count += 1;
            }
        }
        assert_eq!(missed, 0, "of {count} rays");
        assert!(
            cracked_missed > count / 10,
            "negative control: cracked test missed {cracked_missed} of {count}"
        );
    }

    #[test]
    fn degenerate_inputs() {
        let empty = Geometry::new::<TriangleMesh>(&[]);
        let ray = Ray::new(Vec3A::ZERO, Vec3A::X, 0.0, f32::INFINITY);
        assert!(empty.closest_hit(&ray).is_none() && !empty.occluded(&ray));
        let single = Geometry::new(&[TriangleMesh {
            positions: vec![
                Vec3::new(1.0, -1.0, -1.0),
                Vec3::new(1.0, 1.0, -1.0),
                Vec3::new(1.0, 0.0, 1.0),
            ],
            indices: vec![[0, 1, 2]],
            normals: None,
        }]);
        let hit = single.closest_hit(&ray).expect("single triangle");
        assert_eq!((hit.prim, hit.object, hit.t), (0, 0, 1.0));
        assert!((single.position(0, hit.bary) - Vec3::X).length() < 1e-6);
    }

    /// A geometry reposed from another frame's (the sphere moved, the floor at rest) hits what a
    /// full build of the new pose hits, for scene and per-object queries, along a fan of rays.
    /// Control: claiming the sphere did not move keeps its old tree, and its hits differ.
    #[test]
    fn a_reposed_geometry_hits_what_a_full_build_hits() {
        let params = BvhBuildParams::fast_build();
        let (sphere, floor) = (shapes::icosphere(0.5, 3), shapes::quad(4.0, 4.0));
        let before = Geometry::with_build_params(&[sphere.clone(), floor.clone()], params);
        let moved = sphere.transformed(&Affine3A::from_translation(Vec3::new(0.3, 0.6, 0.0)));
        let now = [moved, floor];
        let full = Geometry::with_build_params(&now, params);
        let reposed = before.reposed(&now, &[true, false], params);
        let stale = before.reposed(&now, &[false, false], params);
        let (mut hits, mut stale_differs) = (0, 0);
        for i in 0..400 {
            let (a, b) = ((i % 20) as f32 / 20.0 - 0.5, (i / 20) as f32 / 20.0 - 0.5);
            let dir = Vec3A::new(a, -1.0, b).normalize();
            let ray = Ray::new(Vec3A::new(0.2, 3.0, 0.0), dir, 0.0, 1e3);
            assert_eq!(reposed.closest_hit(&ray), full.closest_hit(&ray), "ray {i}");
            for object in 0..2 {
                let want = full.closest_hit_on_object(&ray, object);
                assert_eq!(reposed.closest_hit_on_object(&ray, object), want, "ray {i}");
                hits += want.is_some() as u32;
            }
            stale_differs += (stale.closest_hit_on_object(&ray, 0)
                != full.closest_hit_on_object(&ray, 0)) as u32;
        }
        assert!(hits > 400, "{hits} hits");
        assert!(stale_differs > 20, "control: {stale_differs} rays");
    }
}
