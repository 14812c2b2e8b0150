//! The ray queries as traversal plus visitor, generic over the [`Kernel`]: closest hit
//! (nearest-first traversal), occlusion and all hits (unordered traversal). They see every
//! triangle of the tree they walk; object-restricted queries walk their object's tree
//! ([`Geometry`](super::Geometry)).

use std::mem::MaybeUninit;

use super::kernel::{Kernel, PacketHits, pair_of};
use super::ray::Hit;
use super::traverse::{Entry, HitVisitor, Visitor};
use super::watertight::PreparedRay;
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

/// Each hit lane of `hits` of the pair `(a, b)`, in lane order, as a [`Hit`].
#[inline(always)]
fn for_each_hit(a: &Packet, b: &Packet, hits: &PacketHits, mut f: impl FnMut(Hit)) {
    let mut mask = hits.mask;
    while mask != 0 {
        let bit = mask.trailing_zeros() as usize;
        mask &= mask - 1;
        let (packet, lane) = if bit < LANES {
            (a, bit)
        } else {
            (b, bit - LANES)
        };
        let s = hits.solution(bit);
        f(Hit {
            t: s.t,
            prim: packet.prims[lane],
            object: packet.object,
            bary: s.bary(),
        });
    }
}

/// Closest hit in `(t_min, t_max)`. Equal `t` goes to the lower triangle id, so the result does
/// not depend on traversal order.
pub(super) struct Closest;

struct ClosestVisitor<'a, K: Kernel> {
    ray: &'a K::Ray,
    /// The ray's own (exclusive) `t_max`.
    ray_t_max: f32,
    best: Option<Hit>,
}

impl<K: Kernel> Visitor for ClosestVisitor<'_, K> {
    #[inline(always)]
    unsafe fn leaf(&mut self, packets: &[Packet], t_max: &mut f32) {
        for two in packets.chunks(2) {
            let (a, b, lanes) = pair_of(&two[0], two.get(1));
            // Accept t equal to the best so far (a tie may go to a lower id); the ray's own
            // t_max stays exclusive.
            let limit = self.best.map_or(self.ray_t_max, |b| b.t.next_up());
            // SAFETY: forwarded from the caller.
            let hits = unsafe { K::pair(a, b, self.ray, lanes, limit) };
            let best = &mut self.best;
            for_each_hit(a, b, &hits, |hit| {
                if best.is_none_or(|b| hit.t < b.t || (hit.t == b.t && hit.prim < b.prim)) {
                    *best = Some(hit);
                    *t_max = hit.t;
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
            visitor.best
        }
    }
}

/// Whether any triangle is hit in `(t_min, t_max)`.
pub(super) struct Occluded;

impl HitVisitor for bool {
    /// A node's hit leaves are tested before any queued node: only a leaf can stop the query
    /// (measured +5–12% over queueing them).
    const LEAF_BATCH: usize = 1;

    /// The occlusion query's visitor: set on the first hit, which ends the traversal.
    #[inline(always)]
    fn hits(&mut self, _: &Packet, _: &Packet, _: &PacketHits) -> bool {
        *self = true;
        true
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
        let mut occluded = false;
        // SAFETY: forwarded from the caller.
        unsafe {
            bvh.traverse_unordered::<K, _>(&K::ray(ray), queue, ray.t_max, &mut occluded);
        }
        occluded
    }
}

/// Every hit in `(t_min, t_max)`, appended to `out` in traversal order.
pub(super) struct AllHits<'a> {
    pub out: &'a mut Vec<Hit>,
}

impl HitVisitor for Vec<Hit> {
    /// Every leaf is tested, so they wait for a batch whose packets pair up across leaves
    /// (8, 16 and 32 measured alike).
    const LEAF_BATCH: usize = 16;

    /// The all-hits query's visitor: every hit appended.
    #[inline(always)]
    fn hits(&mut self, a: &Packet, b: &Packet, hits: &PacketHits) -> bool {
        for_each_hit(a, b, hits, |hit| self.push(hit));
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
        // SAFETY: forwarded from the caller.
        unsafe { bvh.traverse_unordered::<K, _>(&K::ray(ray), queue, ray.t_max, self.out) };
    }
}
