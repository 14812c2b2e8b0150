//! The ray queries as traversal plus leaf visitor, generic over the [`Kernel`]: closest hit,
//! occlusion, and all hits. They see every triangle of the tree they walk; object-restricted
//! queries walk their object's tree ([`Geometry`](super::Geometry)).

use std::mem::MaybeUninit;

use super::kernel::{Kernel, PACKETS_AT_ONCE};
use super::ray::Hit;
use super::traverse::{Entry, Visitor};
use super::watertight::{PreparedRay, Solution};
use super::wide::{LANES, Packet, WideBvh};

/// A query the [`Geometry`](super::Geometry) runs with the kernel of the machine.
pub(super) trait Query {
    type Output;
    /// # Safety
    /// `K`'s instruction set must be available.
    unsafe fn run<K: Kernel>(
        self,
        bvh: &WideBvh,
        ray: &PreparedRay,
        entries: &mut [MaybeUninit<Entry>],
    ) -> Self::Output;
}

/// The lanes holding a triangle in one or two packets, lane `4k + i` for lane `i` of packet `k`.
#[inline(always)]
fn chunk_lanes(chunk: &[Packet]) -> u32 {
    chunk
        .iter()
        .enumerate()
        .fold(0, |mask, (k, packet)| mask | packet.occupied << (k * LANES))
}

/// The packet and lane of hit lane `bit` of a chunk.
#[inline(always)]
fn lane_of(chunk: &[Packet], bit: usize) -> (&Packet, usize) {
    (&chunk[bit / LANES], bit % LANES)
}

/// Each hit lane of `mask`, in lane order.
#[inline(always)]
fn for_each_lane(mut mask: u32, mut f: impl FnMut(usize)) {
    while mask != 0 {
        let lane = mask.trailing_zeros() as usize;
        mask &= mask - 1;
        f(lane);
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
    unsafe fn leaf(&mut self, packets: &[Packet], t_max: &mut f32) -> bool {
        for chunk in packets.chunks(PACKETS_AT_ONCE) {
            // Accept t equal to the best so far (a tie may go to a lower id); the ray's own
            // t_max stays exclusive.
            let limit = self.best.map_or(self.ray_t_max, |b| b.0.t.next_up());
            // SAFETY: forwarded from the caller.
            let hits = unsafe { K::packets(chunk, self.ray, chunk_lanes(chunk), limit) };
            let best = &mut self.best;
            for_each_lane(hits.mask, |bit| {
                let (packet, lane) = lane_of(chunk, bit);
                let (s, prim) = (hits.solution(bit), packet.prims[lane]);
                if best.is_none_or(|b| s.t < b.0.t || (s.t == b.0.t && prim < b.1)) {
                    *best = Some((s, prim, packet.object));
                    *t_max = s.t;
                }
            });
        }
        false
    }
}

impl Query for Closest {
    type Output = Option<Hit>;

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
    occluded: bool,
}

impl<K: Kernel> Visitor for OccludedVisitor<'_, K> {
    const EAGER_LEAVES: bool = true;

    #[inline(always)]
    unsafe fn leaf(&mut self, packets: &[Packet], t_max: &mut f32) -> bool {
        for chunk in packets.chunks(PACKETS_AT_ONCE) {
            // SAFETY: forwarded from the caller.
            let hits = unsafe { K::packets(chunk, self.ray, chunk_lanes(chunk), *t_max) };
            if hits.mask != 0 {
                self.occluded = true;
                return true;
            }
        }
        false
    }
}

impl Query for Occluded {
    type Output = bool;

    #[inline(always)]
    unsafe fn run<K: Kernel>(
        self,
        bvh: &WideBvh,
        ray: &PreparedRay,
        entries: &mut [MaybeUninit<Entry>],
    ) -> bool {
        // SAFETY (whole block): forwarded from the caller.
        unsafe {
            let lanes_ray = K::ray(ray);
            let mut visitor = OccludedVisitor::<K> {
                ray: &lanes_ray,
                occluded: false,
            };
            let mut t_max = ray.t_max;
            bvh.traverse_any::<K, _, true>(&lanes_ray, entries, &mut t_max, &mut visitor);
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
    out: &'b mut Vec<Hit>,
}

impl<K: Kernel> Visitor for AllHitsVisitor<'_, '_, K> {
    #[inline(always)]
    unsafe fn leaf(&mut self, packets: &[Packet], t_max: &mut f32) -> bool {
        for chunk in packets.chunks(PACKETS_AT_ONCE) {
            // SAFETY: forwarded from the caller.
            let hits = unsafe { K::packets(chunk, self.ray, chunk_lanes(chunk), *t_max) };
            for_each_lane(hits.mask, |bit| {
                let (packet, lane) = lane_of(chunk, bit);
                let s = hits.solution(bit);
                self.out.push(Hit {
                    t: s.t,
                    prim: packet.prims[lane],
                    object: packet.object,
                    bary: s.bary(),
                });
            });
        }
        false
    }
}

impl Query for AllHits<'_> {
    type Output = ();

    #[inline(always)]
    unsafe fn run<K: Kernel>(
        self,
        bvh: &WideBvh,
        ray: &PreparedRay,
        entries: &mut [MaybeUninit<Entry>],
    ) {
        // SAFETY (whole block): forwarded from the caller.
        unsafe {
            let lanes_ray = K::ray(ray);
            let mut visitor = AllHitsVisitor::<K> {
                ray: &lanes_ray,
                out: self.out,
            };
            let mut t_max = ray.t_max;
            bvh.traverse_any::<K, _, true>(&lanes_ray, entries, &mut t_max, &mut visitor);
        }
    }
}
