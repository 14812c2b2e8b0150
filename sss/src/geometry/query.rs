//! The ray queries as traversal plus visitor, generic over the [`Kernel`]: closest hit
//! (nearest-first traversal), occlusion and all hits (unordered traversal). They see every
//! triangle of the tree they walk; object-restricted queries walk their object's tree
//! ([`Geometry`](super::Geometry)).

use std::mem::MaybeUninit;

use super::kernel::{Kernel, PacketHits, pair_of};
use super::ray::Hit;
use super::traverse::{Entry, PairVisitor, Visitor};
use super::watertight::{PreparedRay, Solution};
use super::wide::{ChildRef, LANES, Packet, WideBvh};

/// A query the [`Geometry`](super::Geometry) runs with the kernel of the machine.
pub(super) trait Query {
    type Output;
    /// A slot of the traversal's storage.
    type Slot: Copy;
    /// Storage slots the traversal of `bvh` needs.
    fn slots(bvh: &WideBvh) -> usize;
    /// # Safety
    /// `K`'s instruction set must be available.
    unsafe fn run<K: Kernel>(
        self,
        bvh: &WideBvh,
        ray: &PreparedRay,
        slots: &mut [MaybeUninit<Self::Slot>],
    ) -> Self::Output;
}

/// The packet and lane of hit lane `bit` of the pair `(a, b)`.
#[inline(always)]
fn lane_of<'p>(a: &'p Packet, b: &'p Packet, bit: usize) -> (&'p Packet, usize) {
    if bit < LANES {
        (a, bit)
    } else {
        (b, bit - LANES)
    }
}

/// Each hit lane of `hits`, in lane order, with its packet and solution.
#[inline(always)]
fn for_each_hit(
    a: &Packet,
    b: &Packet,
    hits: &PacketHits,
    mut f: impl FnMut(&Packet, usize, Solution),
) {
    let mut mask = hits.mask;
    while mask != 0 {
        let bit = mask.trailing_zeros() as usize;
        mask &= mask - 1;
        let (packet, lane) = lane_of(a, b, bit);
        f(packet, lane, hits.solution(bit));
    }
}

/// Closest hit in `(t_min, t_max)`. Equal `t` goes to the lower triangle id, so the result does
/// not depend on traversal order.
pub(super) struct Closest;

struct ClosestVisitor<'a, K: Kernel> {
    ray: &'a K::Ray,
    /// The ray's own (exclusive) `t_max`.
    ray_t_max: f32,
    /// Solution, triangle id, object id.
    best: Option<(Solution, u32, u32)>,
}

impl<K: Kernel> Visitor for ClosestVisitor<'_, K> {
    #[inline(always)]
    unsafe fn leaf(&mut self, packets: &[Packet], t_max: &mut f32) {
        for two in packets.chunks(2) {
            let (a, b, lanes) = pair_of(&two[0], two.get(1));
            // Accept t equal to the best so far (a tie may go to a lower id); the ray's own
            // t_max stays exclusive.
            let limit = self.best.map_or(self.ray_t_max, |b| b.0.t.next_up());
            // SAFETY: forwarded from the caller.
            let hits = unsafe { K::pair(a, b, self.ray, lanes, limit) };
            let best = &mut self.best;
            for_each_hit(a, b, &hits, |packet, lane, s| {
                let prim = packet.prims[lane];
                if best.is_none_or(|b| s.t < b.0.t || (s.t == b.0.t && prim < b.1)) {
                    *best = Some((s, prim, packet.object));
                    *t_max = s.t;
                }
            });
        }
    }
}

impl Query for Closest {
    type Output = Option<Hit>;
    type Slot = Entry;

    fn slots(bvh: &WideBvh) -> usize {
        bvh.nearest_slots()
    }

    #[inline(always)]
    unsafe fn run<K: Kernel>(
        self,
        bvh: &WideBvh,
        ray: &PreparedRay,
        entries: &mut [MaybeUninit<Entry>],
    ) -> Option<Hit> {
        // SAFETY (whole block): forwarded from the caller.
        unsafe {
            let lanes_ray = K::ray(ray);
            let mut visitor = ClosestVisitor::<K> {
                ray: &lanes_ray,
                ray_t_max: ray.t_max,
                best: None,
            };
            let mut t_max = ray.t_max;
            bvh.traverse_nearest::<K>(&lanes_ray, entries, &mut t_max, &mut visitor);
            visitor.best.map(|(s, prim, object)| Hit {
                t: s.t,
                prim,
                object,
                bary: s.bary(),
            })
        }
    }
}

/// Whether any triangle is hit in `(t_min, t_max)`.
pub(super) struct Occluded;

struct OccludedVisitor<'a, K: Kernel> {
    ray: &'a K::Ray,
    t_max: f32,
    occluded: bool,
}

impl<K: Kernel> PairVisitor for OccludedVisitor<'_, K> {
    /// A node's hit leaves are tested before any queued node: only a leaf can stop the query
    /// (measured +5–12% over queueing them).
    const LEAF_BATCH: usize = 1;

    #[inline(always)]
    unsafe fn pair(&mut self, a: &Packet, b: &Packet, lanes: u32) -> bool {
        // SAFETY: forwarded from the caller.
        self.occluded = unsafe { K::pair(a, b, self.ray, lanes, self.t_max) }.mask != 0;
        self.occluded
    }
}

impl Query for Occluded {
    type Output = bool;
    type Slot = ChildRef;

    fn slots(bvh: &WideBvh) -> usize {
        bvh.unordered_slots()
    }

    #[inline(always)]
    unsafe fn run<K: Kernel>(
        self,
        bvh: &WideBvh,
        ray: &PreparedRay,
        queue: &mut [MaybeUninit<ChildRef>],
    ) -> bool {
        // SAFETY (whole block): forwarded from the caller.
        unsafe {
            let lanes_ray = K::ray(ray);
            let mut visitor = OccludedVisitor::<K> {
                ray: &lanes_ray,
                t_max: ray.t_max,
                occluded: false,
            };
            bvh.traverse_unordered::<K, _>(&lanes_ray, queue, ray.t_max, &mut visitor);
            visitor.occluded
        }
    }
}

/// Every hit in `(t_min, t_max)`, appended to `out` in traversal order.
pub(super) struct AllHits<'a> {
    pub out: &'a mut Vec<Hit>,
}

struct AllHitsVisitor<'a, 'b, K: Kernel> {
    ray: &'a K::Ray,
    t_max: f32,
    out: &'b mut Vec<Hit>,
}

impl<K: Kernel> PairVisitor for AllHitsVisitor<'_, '_, K> {
    /// Every leaf is tested, so they wait for a batch whose packets pair up across leaves
    /// (8, 16 and 32 measured alike).
    const LEAF_BATCH: usize = 16;

    #[inline(always)]
    unsafe fn pair(&mut self, a: &Packet, b: &Packet, lanes: u32) -> bool {
        // SAFETY: forwarded from the caller.
        let hits = unsafe { K::pair(a, b, self.ray, lanes, self.t_max) };
        for_each_hit(a, b, &hits, |packet, lane, s| {
            self.out.push(Hit {
                t: s.t,
                prim: packet.prims[lane],
                object: packet.object,
                bary: s.bary(),
            });
        });
        false
    }
}

impl Query for AllHits<'_> {
    type Output = ();
    type Slot = ChildRef;

    fn slots(bvh: &WideBvh) -> usize {
        bvh.unordered_slots()
    }

    #[inline(always)]
    unsafe fn run<K: Kernel>(
        self,
        bvh: &WideBvh,
        ray: &PreparedRay,
        queue: &mut [MaybeUninit<ChildRef>],
    ) {
        // SAFETY (whole block): forwarded from the caller.
        unsafe {
            let lanes_ray = K::ray(ray);
            let mut visitor = AllHitsVisitor::<K> {
                ray: &lanes_ray,
                t_max: ray.t_max,
                out: self.out,
            };
            bvh.traverse_unordered::<K, _>(&lanes_ray, queue, ray.t_max, &mut visitor);
        }
    }
}
