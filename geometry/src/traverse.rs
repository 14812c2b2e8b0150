//! The traversal loops over a [`WideBvh`], generic over the [`Kernel`] and what the query
//! does with the triangle packets of the leaves it reaches:
//!
//! - [`WideBvh::traverse_nearest`]: children nearest first (box entry distance), and pending
//!   boxes entered beyond the shrinking `t_max` skipped: closest-hit queries ([`Visitor`]).
//!   Every hit child's node or packets is prefetched as soon as its box test passes.
//! - [`WideBvh::traverse_unordered`]: no order and no pruning, for queries that visit every
//!   overlapped leaf (all hits) or stop at the first hit (occlusion) ([`HitVisitor`]). Inner
//!   nodes wait in a first-in first-out queue, so the next node's address is known long before
//!   its turn and consecutive box tests overlap in the pipeline; a node's hit children are
//!   split into inner nodes and leaves by [`Kernel::partition`] (no branch per child); the
//!   leaves' packets are tested two at a time, across leaves, in batches.
//!
//! Measured on the benchmark meshes (`traversal-bench`, 1 thread, against the pending-entry
//! traversal with per-child pushes and prefetches it replaced): all hits along SSS probes
//! +22–25% (bumpy) and +10–25% (scanned-like), occlusion +4–20%. Prefetching the queued inner
//! nodes cost 10–12% (the queue already exposes their addresses early); prefetching a batch's
//! packets before testing them gains 8–10% on the larger mesh.

use std::mem::MaybeUninit;

use super::kernel::{Kernel, PacketHits, pair_of, widen};
use super::wide::{ChildRef, MAX_LEAF_PACKETS, Packet, WideBvh, WideNode, is_leaf, leaf_packets};

/// A deferred child and its box entry distance.
#[derive(Clone, Copy)]
pub(super) struct Entry {
    child: ChildRef,
    entry: f32,
}

/// Traversal storage slots held on the call stack; deeper trees use a heap buffer.
pub(super) const INLINE_SLOTS: usize = 256;
/// Cache lines of a node and of a packet.
const NODE_LINES: usize = size_of::<WideNode>() / 64;
const PACKET_LINES: usize = size_of::<Packet>() / 64;
/// Queued inner nodes taken oldest first while at most this many wait; beyond it the newest
/// (depth first), which bounds the queue.
const BREADTH_WINDOW: usize = 64;
/// Slots a [`Kernel::partition`] may write past the end of a list.
const PARTITION_SLACK: usize = 8;
/// Most leaves a [`HitVisitor`] may ask to collect before their packets are tested.
const MAX_LEAF_BATCH: usize = 16;

/// What a closest-hit query does at a leaf.
pub(super) trait Visitor {
    /// Tests the leaf's packets; may shrink `t_max` (which prunes boxes in nearest-first
    /// traversal).
    ///
    /// # Safety
    /// The visitor's kernel instruction set must be available.
    unsafe fn leaf(&mut self, packets: &[Packet], t_max: &mut f32);
}

/// What an unordered query does with the triangles its ray hits.
pub(super) trait HitVisitor {
    /// Hit leaves collected before their packets are tested (at most [`MAX_LEAF_BATCH`]): 1 to
    /// test each node's hit leaves at once, for a query that stops at its first hit; more to
    /// pair more packets of different leaves in one test.
    const LEAF_BATCH: usize;

    /// Takes the hits (a non-empty mask) of the pair test of packets `a` and `b`
    /// ([`Kernel::pair`]). Returns `true` to stop the traversal.
    fn hits(&mut self, a: &Packet, b: &Packet, hits: &PacketHits) -> bool;
}

impl WideBvh {
    /// Pending entries of [`WideBvh::traverse_nearest`].
    pub(super) fn nearest_slots(&self) -> usize {
        self.stack_depth
    }

    /// Queue slots of [`WideBvh::traverse_unordered`]: at most `BREADTH_WINDOW` queued nodes
    /// before a depth-first run, which adds at most `stack_depth`, and a partition's overshoot.
    pub(super) fn unordered_slots(&self) -> usize {
        BREADTH_WINDOW + self.stack_depth + 2 * PARTITION_SLACK
    }

    /// Runs `query` with `len` uninitialised slots of traversal storage.
    #[inline(always)]
    pub(super) fn with_slots<T: Copy, R>(
        len: usize,
        query: impl FnOnce(&mut [MaybeUninit<T>]) -> R,
    ) -> R {
        if len <= INLINE_SLOTS {
            query(&mut [MaybeUninit::uninit(); INLINE_SLOTS][..len])
        } else {
            query(&mut vec![MaybeUninit::uninit(); len])
        }
    }

    /// Asks the cache for a child's node or leaf packets while the traversal works on other
    /// pending children.
    #[inline(always)]
    fn prefetch(&self, child: ChildRef) {
        if is_leaf(child) {
            let (first, count) = leaf_packets(child);
            prefetch_lines(
                self.packets.as_ptr().wrapping_add(first),
                count * PACKET_LINES,
            );
        } else {
            prefetch_lines(self.nodes.as_ptr().wrapping_add(child as usize), NODE_LINES);
        }
    }

    /// The children of `node` whose boxes the ray overlaps within `[t_min, t_max]` (prefetched),
    /// with their entry distances.
    ///
    /// # Safety
    /// `K`'s instruction set must be available.
    #[inline(always)]
    unsafe fn hit_children<K: Kernel>(
        &self,
        node: &WideNode,
        ray: &K::Ray,
        t_max: f32,
        entry: &mut [f32; 8],
    ) -> u32 {
        // SAFETY: forwarded from the caller.
        let mask = unsafe { K::overlap(node, ray, widen(t_max), entry) } & node.occupied;
        let mut remaining = mask;
        while remaining != 0 {
            let i = remaining.trailing_zeros() as usize;
            remaining &= remaining - 1;
            self.prefetch(node.children[i]);
        }
        mask
    }

    /// Nearest-first traversal for closest-hit queries. `entries` must hold
    /// [`WideBvh::nearest_slots`].
    ///
    /// # Safety
    /// `K`'s instruction set must be available.
    #[inline(always)]
    pub(super) unsafe fn traverse_nearest<K: Kernel>(
        &self,
        ray: &K::Ray,
        entries: &mut [MaybeUninit<Entry>],
        t_max: &mut f32,
        visitor: &mut impl Visitor,
    ) {
        let Some(mut current) = self.root else {
            return;
        };
        let mut len = 0;
        loop {
            if !is_leaf(current) {
                let node = &self.nodes[current as usize];
                let mut entry = [0.0f32; 8];
                // SAFETY: forwarded from the caller.
                let mut mask = unsafe { self.hit_children::<K>(node, ray, *t_max, &mut entry) };
                if mask != 0 {
                    let first = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    if mask == 0 {
                        current = node.children[first];
                        continue;
                    }
                    // Push all, sorted by decreasing entry distance (insertion sort of at most
                    // eight), then take the nearest from the top.
                    let base = len;
                    let mut push = |i: usize| {
                        let e = Entry {
                            child: node.children[i],
                            entry: entry[i],
                        };
                        let mut j = len;
                        // SAFETY: entries in base..len were written below.
                        while j > base && unsafe { entries[j - 1].assume_init() }.entry < e.entry {
                            entries[j] = entries[j - 1];
                            j -= 1;
                        }
                        // Indexing panics rather than overflows; `stack_depth` bounds `len`.
                        entries[j].write(e);
                        len += 1;
                    };
                    push(first);
                    while mask != 0 {
                        let i = mask.trailing_zeros() as usize;
                        mask &= mask - 1;
                        push(i);
                    }
                    len -= 1;
                    // SAFETY: written by `push`.
                    current = unsafe { entries[len].assume_init() }.child;
                    continue;
                }
            } else {
                let (first, count) = leaf_packets(current);
                // SAFETY: forwarded from the caller.
                unsafe { visitor.leaf(&self.packets[first..first + count], t_max) };
            }
            // The nearest pending box not entered beyond the (possibly shrunk) t_max.
            loop {
                if len == 0 {
                    return;
                }
                len -= 1;
                // SAFETY: entries below `len + 1` were written by `push`.
                let next = unsafe { entries[len].assume_init() };
                if next.entry <= widen(*t_max) {
                    current = next.child;
                    break;
                }
            }
        }
    }

    /// Unordered traversal (all hits, occlusion) for triangles hit with `t_min < t < t_max`:
    /// inner nodes queued first in first out while at most `BREADTH_WINDOW` wait, else last in
    /// first out; hit leaves tested by [`WideBvh::test_leaves`] every `V::LEAF_BATCH` and at the
    /// end. `queue` must hold [`WideBvh::unordered_slots`].
    ///
    /// The live queue stays below `unordered_slots − PARTITION_SLACK`: a first-in take happens
    /// with at most `BREADTH_WINDOW` waiting, and the depth-first run that follows adds at most
    /// `stack_depth` before the count drops back; the queue is moved to its start when its end
    /// comes within `PARTITION_SLACK` of the storage's.
    ///
    /// # Safety
    /// `K`'s instruction set must be available.
    #[inline(always)]
    pub(super) unsafe fn traverse_unordered<K: Kernel, V: HitVisitor>(
        &self,
        ray: &K::Ray,
        queue: &mut [MaybeUninit<ChildRef>],
        t_max: f32,
        visitor: &mut V,
    ) {
        const { assert!(V::LEAF_BATCH >= 1 && V::LEAF_BATCH <= MAX_LEAF_BATCH) };
        let Some(root) = self.root else {
            return;
        };
        let mut leaves = [MaybeUninit::uninit(); MAX_LEAF_BATCH + PARTITION_SLACK];
        if is_leaf(root) {
            leaves[0].write(root);
            // SAFETY: forwarded from the caller; slot 0 was written.
            unsafe { self.test_leaves::<K>(&leaves[..1], ray, t_max, visitor) };
            return;
        }
        let far = widen(t_max);
        let end = queue.len() - PARTITION_SLACK;
        queue[0].write(root);
        let (mut head, mut tail, mut batch) = (0, 1, 0);
        while head < tail {
            let current = if tail - head <= BREADTH_WINDOW {
                head += 1;
                queue[head - 1]
            } else {
                tail -= 1;
                queue[tail]
            };
            // SAFETY: slots head..tail were written by `partition` (or hold the root).
            let node = &self.nodes[unsafe { current.assume_init() } as usize];
            let mut entry = [0.0f32; 8];
            // SAFETY (whole block): forwarded from the caller.
            unsafe {
                let mask = K::overlap(node, ray, far, &mut entry) & node.occupied;
                let (inner, hit_leaves) =
                    K::partition(node, mask, &mut queue[tail..], &mut leaves[batch..]);
                tail += inner;
                batch += hit_leaves;
                if batch >= V::LEAF_BATCH {
                    if self.test_leaves::<K>(&leaves[..batch], ray, t_max, visitor) {
                        return;
                    }
                    batch = 0;
                }
            }
            if tail > end {
                queue.copy_within(head..tail, 0);
                (head, tail) = (0, tail - head);
            }
        }
        // SAFETY: forwarded from the caller.
        unsafe { self.test_leaves::<K>(&leaves[..batch], ray, t_max, visitor) };
    }

    /// Prefetches the packets of `leaves` (written slots), then tests them two at a time
    /// (consecutive packets, across leaves) and hands the hits to `visitor`. Returns `true` if
    /// the visitor stopped.
    ///
    /// # Safety
    /// `K`'s instruction set must be available.
    #[inline(always)]
    unsafe fn test_leaves<K: Kernel>(
        &self,
        leaves: &[MaybeUninit<ChildRef>],
        ray: &K::Ray,
        t_max: f32,
        visitor: &mut impl HitVisitor,
    ) -> bool {
        // Packet indices of every leaf in a row: four written per leaf without a branch on its
        // count (a leaf of one object has at most four packets), `count` of them kept.
        let mut written =
            [MaybeUninit::<u32>::uninit(); MAX_LEAF_PACKETS * (MAX_LEAF_BATCH + PARTITION_SLACK)];
        let mut n = 0;
        for leaf in leaves {
            // SAFETY: the caller passes written slots.
            let (first, count) = leaf_packets(unsafe { leaf.assume_init() });
            for k in 0..count.max(4) {
                written[n + k].write((first + k) as u32);
            }
            n += count;
        }
        // SAFETY: slots below `n` were written (each leaf writes at least its count).
        let packets = unsafe { &*(&raw const written[..n] as *const [u32]) };
        for &p in packets {
            prefetch_lines(self.packets.as_ptr().wrapping_add(p as usize), PACKET_LINES);
        }
        for two in packets.chunks(2) {
            let (a, b, lanes) = pair_of(
                &self.packets[two[0] as usize],
                two.get(1).map(|&p| &self.packets[p as usize]),
            );
            // SAFETY: forwarded from the caller.
            let hits = unsafe { K::pair(a, b, ray, lanes, t_max) };
            if hits.mask != 0 && visitor.hits(a, b, &hits) {
                return true;
            }
        }
        false
    }
}

/// Asks the cache for `lines` cache lines from `start`.
#[inline(always)]
fn prefetch_lines<T>(start: *const T, lines: usize) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        let start: *const i8 = start.cast();
        for i in 0..lines {
            // SAFETY: prefetching is a hint and never faults.
            unsafe { _mm_prefetch::<_MM_HINT_T0>(start.wrapping_add(64 * i)) };
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (start, lines);
}

#[cfg(test)]
mod tests {
    use glam::{Vec3, Vec3A};

    use super::*;
    use crate::{Geometry, Ray, TriangleMesh};

    /// Inner nodes per depth of `bvh`.
    fn inner_levels(bvh: &WideBvh) -> Vec<usize> {
        let mut levels = Vec::new();
        let mut level: Vec<ChildRef> = bvh.root.into_iter().filter(|&c| !is_leaf(c)).collect();
        while !level.is_empty() {
            levels.push(level.len());
            level = level
                .iter()
                .flat_map(|&c| {
                    let node = &bvh.nodes[c as usize];
                    (0..8)
                        .filter(move |&i| node.occupied & (1 << i) != 0)
                        .map(move |i| node.children[i])
                })
                .filter(|&c| !is_leaf(c))
                .collect();
        }
        levels
    }

    #[test]
    fn a_ray_through_every_leaf_cycles_the_queue_and_turns_depth_first() {
        // A stack of triangles across the z axis: a ray along it enters every box.
        let n = 24_000u32;
        let mesh = TriangleMesh {
            positions: (0..n)
                .flat_map(|i| {
                    let z = i as f32 * 1e-3;
                    [
                        Vec3::new(-1.0, -1.0, z),
                        Vec3::new(1.0, -1.0, z),
                        Vec3::new(0.0, 1.0, z),
                    ]
                })
                .collect(),
            indices: (0..n).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect(),
            normals: None,
        };
        let geometry = Geometry::new(&[mesh]);
        let bvh = geometry.wide();
        // The traversal must queue more nodes than its storage holds (the queue moves to its
        // start) and hold more than BREADTH_WINDOW at once (it turns depth first).
        let levels = inner_levels(bvh);
        assert!(
            levels.iter().sum::<usize>() > bvh.unordered_slots()
                && levels.iter().any(|&w| w > BREADTH_WINDOW),
            "inner nodes per level {levels:?}, {} slots",
            bvh.unordered_slots()
        );
        let mut hits = Vec::new();
        for (x, y) in [(0.0, 0.0), (0.2, -0.3), (-0.1, 0.25)] {
            let ray = Ray::new(Vec3A::new(x, y, -1.0), Vec3A::Z, 0.0, f32::INFINITY);
            geometry.all_hits_on_object(&ray, 0, &mut hits);
            let mut prims: Vec<u32> = hits.iter().map(|h| h.prim).collect();
            prims.dedup();
            assert_eq!(prims, (0..n).collect::<Vec<_>>(), "{ray:?}");
            assert!(geometry.occluded(&ray));
        }
    }
}
