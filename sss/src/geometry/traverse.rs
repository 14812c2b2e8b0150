//! The traversal loops over a [`WideBvh`], generic over the [`Kernel`] and the leaf
//! [`Visitor`] of the query:
//!
//! - [`WideBvh::traverse_nearest`]: children nearest first (box entry distance), and pending
//!   boxes entered beyond the shrinking `t_max` skipped: closest-hit queries.
//! - [`WideBvh::traverse_any`]: no order and no pruning, for queries that visit every
//!   overlapped leaf (all hits) or stop at the first hit (occlusion). With `BREADTH` the oldest
//!   pending child is taken first, so the prefetches of all pending children overlap (incoherent
//!   rays are bound by memory latency); otherwise the newest (depth first).
//!
//! Every hit child's node or packets is prefetched as soon as its box test passes.

use std::mem::MaybeUninit;

use super::kernel::{Kernel, widen};
use super::wide::{ChildRef, Packet, WideBvh, WideNode, is_leaf, leaf_packets};

/// A deferred child and its box entry distance.
#[derive(Clone, Copy)]
pub(super) struct Entry {
    child: ChildRef,
    entry: f32,
}

/// Entries held on the call stack (1 KiB); deeper trees use a heap buffer.
pub(super) const INLINE_ENTRIES: usize = 128;
/// Cache lines of a node and of a packet.
const NODE_LINES: usize = size_of::<WideNode>() / 64;
const PACKET_LINES: usize = size_of::<Packet>() / 64;
/// Pending children taken in breadth-first order before the traversal turns depth first.
const BREADTH_WINDOW: usize = 64;

/// What a query does at a leaf.
pub(super) trait Visitor {
    /// Whether [`WideBvh::traverse_any`] tests a node's hit leaves at once, before the pending
    /// children: worth it for a query that stops at its first hit, which only a leaf can give
    /// (measured +5–12% on occlusion, and nothing gained for all hits, whose leaves are better
    /// queued behind their prefetch).
    const EAGER_LEAVES: bool = false;

    /// Tests the leaf's packets; may shrink `t_max` (which prunes boxes in nearest-first
    /// traversal); returns `true` to stop.
    ///
    /// # Safety
    /// The visitor's kernel instruction set must be available.
    unsafe fn leaf(&mut self, packets: &[Packet], t_max: &mut f32) -> bool;
}

impl WideBvh {
    /// Pending-entry storage for this tree: a power of two, at least `stack_depth` for
    /// nearest-first traversal and `stack_depth + BREADTH_WINDOW` for breadth-first.
    pub(super) fn entries_needed(&self) -> usize {
        (self.stack_depth + BREADTH_WINDOW).next_power_of_two()
    }

    /// Runs `query` with uninitialised entry storage of [`WideBvh::entries_needed`] length.
    #[inline(always)]
    pub(super) fn with_entries<R>(&self, query: impl FnOnce(&mut [MaybeUninit<Entry>]) -> R) -> R {
        let needed = self.entries_needed();
        if needed <= INLINE_ENTRIES {
            query(&mut [MaybeUninit::uninit(); INLINE_ENTRIES][..needed])
        } else {
            query(&mut vec![MaybeUninit::uninit(); needed])
        }
    }

    /// Asks the cache for a child's node or leaf packets while the traversal works on other
    /// pending children.
    #[inline(always)]
    fn prefetch(&self, child: ChildRef) {
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
            // SAFETY (whole block): prefetching is a hint and never faults.
            let line = |start: *const i8, i: usize| unsafe {
                _mm_prefetch::<_MM_HINT_T0>(start.wrapping_add(64 * i))
            };
            if is_leaf(child) {
                let (first, count) = leaf_packets(child);
                let start: *const i8 = self.packets.as_ptr().wrapping_add(first).cast();
                (0..count * PACKET_LINES).for_each(|i| line(start, i));
            } else {
                let start: *const i8 = self.nodes.as_ptr().wrapping_add(child as usize).cast();
                (0..NODE_LINES).for_each(|i| line(start, i));
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        let _ = child;
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

    /// Nearest-first traversal for closest-hit queries. `entries` must hold `stack_depth`.
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
                if unsafe { visitor.leaf(&self.packets[first..first + count], t_max) } {
                    return;
                }
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

    /// Unordered traversal (all hits, occlusion): breadth first while fewer than
    /// `entries.len() − stack_depth` children are pending, else depth first. `entries.len()`
    /// must be a power of two of at least `stack_depth + 8`.
    ///
    /// Pending entries stay below `entries.len()`: a breadth-first take happens only with at
    /// most `len − stack_depth` pending, and the depth-first run that follows it adds at most
    /// `stack_depth` before the count drops back.
    ///
    /// # Safety
    /// `K`'s instruction set must be available.
    #[inline(always)]
    pub(super) unsafe fn traverse_any<K: Kernel, V: Visitor, const BREADTH: bool>(
        &self,
        ray: &K::Ray,
        entries: &mut [MaybeUninit<Entry>],
        t_max: &mut f32,
        visitor: &mut V,
    ) {
        let Some(mut current) = self.root else {
            return;
        };
        debug_assert!(entries.len().is_power_of_two());
        let ring = entries.len() - 1;
        let breadth_limit = entries.len().saturating_sub(self.stack_depth);
        let (mut head, mut len) = (0, 0);
        loop {
            if !is_leaf(current) {
                let node = &self.nodes[current as usize];
                let mut entry = [0.0f32; 8];
                // SAFETY: forwarded from the caller.
                let mut mask = unsafe { self.hit_children::<K>(node, ray, *t_max, &mut entry) };
                if V::EAGER_LEAVES {
                    let mut leaves = mask;
                    while leaves != 0 {
                        let i = leaves.trailing_zeros() as usize;
                        leaves &= leaves - 1;
                        if is_leaf(node.children[i]) {
                            mask &= !(1 << i);
                            let (first, count) = leaf_packets(node.children[i]);
                            // SAFETY: forwarded from the caller.
                            if unsafe { visitor.leaf(&self.packets[first..first + count], t_max) } {
                                return;
                            }
                        }
                    }
                }
                while mask != 0 {
                    let i = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    entries[(head + len) & ring].write(Entry {
                        child: node.children[i],
                        entry: 0.0,
                    });
                    len += 1;
                }
            } else {
                let (first, count) = leaf_packets(current);
                // SAFETY: forwarded from the caller.
                if unsafe { visitor.leaf(&self.packets[first..first + count], t_max) } {
                    return;
                }
            }
            if len == 0 {
                return;
            }
            let slot = if BREADTH && len <= breadth_limit {
                let oldest = head;
                head = (head + 1) & ring;
                oldest
            } else {
                (head + len - 1) & ring
            };
            len -= 1;
            // SAFETY: the ring holds `len + 1` written entries from `head` before this take.
            current = unsafe { entries[slot].assume_init() }.child;
        }
    }
}
