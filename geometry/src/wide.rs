//! The CPU traversal layout: an uncompressed 8-wide BVH whose leaves are packets of four
//! triangles stored lane by lane, collapsed from obvhs's binary BVH (the same one the device
//! CWBVH is converted from). Child boxes are exact `f32` boxes in SoA order, so one 8-lane box
//! test (two 4-lane halves without AVX2) tests all children; packets are tested four or eight
//! triangles at a time with the watertight test.
//!
//! Collapse (after Wald et al. 2008, *Getting rid of packets*, and Ylitie et al. 2017 §3): a
//! wide node starts from a binary node's two children and opens its largest-area child of more
//! than two packets of triangles until it has eight children. A child of at most
//! [`MAX_LEAF_TRIANGLES`] triangles that stays unopened becomes a leaf; a larger one becomes a
//! wide node. Measured on the benchmark meshes (`traversal-bench`), this beats leaves of one or
//! two packets at most, a surface-area leaf cost, opening by area × triangle count, and leaves of
//! up to six or eight packets, on every query.

use glam::{Vec3, Vec3A};
use obvhs::{aabb::Aabb, bvh2::Bvh2};

/// Triangles per packet (the lanes of one 4-lane triangle test).
pub(super) const LANES: usize = 4;
/// Children of more triangles than this (two packets: one AVX2 triangle test) are opened while a
/// wide node has free slots; smaller ones stay leaves (measured 2–7% faster on every query of the
/// benchmark meshes than opening children of more than one packet).
const OPEN_ABOVE: u32 = 2 * LANES as u32;
/// Largest leaf: four packets.
const MAX_LEAF_TRIANGLES: u32 = 16;

/// A child reference: an inner node index, or a leaf (bit 31) with its packet count − 1 in bits
/// 28..31 and its first packet index below.
pub(super) type ChildRef = u32;
const LEAF_BIT: u32 = 1 << 31;
const COUNT_SHIFT: u32 = 28;
const INDEX_MASK: u32 = (1 << COUNT_SHIFT) - 1;
/// Most packets a leaf reference holds (a leaf of several objects has a run per object).
pub(super) const MAX_LEAF_PACKETS: usize = 1 << (31 - COUNT_SHIFT);

pub(super) fn is_leaf(child: ChildRef) -> bool {
    child & LEAF_BIT != 0
}

/// `(first packet, packet count)` of a leaf reference.
pub(super) fn leaf_packets(child: ChildRef) -> (usize, usize) {
    (
        (child & INDEX_MASK) as usize,
        (((child & !LEAF_BIT) >> COUNT_SHIFT) + 1) as usize,
    )
}

fn leaf_ref(first: usize, count: usize) -> ChildRef {
    assert!(first <= INDEX_MASK as usize, "too many triangle packets");
    assert!(
        (1..=MAX_LEAF_PACKETS).contains(&count),
        "{count} packets in a leaf"
    );
    LEAF_BIT | (((count - 1) as u32) << COUNT_SHIFT) | first as u32
}

/// Eight child boxes in SoA order and the child references (256 bytes, four cache lines).
#[repr(C, align(64))]
#[derive(Clone, Copy, Debug)]
pub(super) struct WideNode {
    /// `planes[2·axis]` = box minima, `planes[2·axis + 1]` = maxima, one lane per child.
    pub planes: [[f32; 8]; 6],
    pub children: [ChildRef; 8],
    /// Bit `i` set when slot `i` holds a child (empty slots have zero boxes and are masked).
    pub occupied: u32,
}

/// Up to four triangles of one object, lane by lane; empty lanes repeat lane 0's vertices.
#[repr(C, align(64))]
#[derive(Clone, Copy, Debug)]
pub(super) struct Packet {
    /// `vertices[vertex][axis][lane]`.
    pub vertices: [[[f32; LANES]; 3]; 3],
    /// Global triangle id per lane.
    pub prims: [u32; LANES],
    /// The object of every lane (a packet holds one object's triangles).
    pub object: u32,
    /// Bit `i` set when lane `i` holds a triangle.
    pub occupied: u32,
}

pub(super) const EMPTY_LANE: u32 = u32::MAX;

/// The CPU BVH: wide nodes, triangle packets, the root reference, and the traversal stack depth
/// the tree can need.
#[derive(Clone, Default)]
pub(super) struct WideBvh {
    pub nodes: Vec<WideNode>,
    pub packets: Vec<Packet>,
    /// `None` for an empty scene.
    pub root: Option<ChildRef>,
    /// Largest number of stack entries a traversal can hold at once.
    pub stack_depth: usize,
}

fn area(aabb: &Aabb) -> f32 {
    aabb.half_area()
}

/// Triangles under every binary node.
fn subtree_counts(bvh2: &Bvh2) -> Vec<u32> {
    let mut count = vec![0u32; bvh2.nodes.len()];
    // Pre-order without recursion, then reversed: children before parents.
    let mut order = Vec::with_capacity(bvh2.nodes.len());
    let mut stack = vec![0usize];
    while let Some(i) = stack.pop() {
        order.push(i);
        let node = &bvh2.nodes[i];
        if !node.is_leaf() {
            stack.push(node.first_index as usize);
            stack.push(node.first_index as usize + 1);
        }
    }
    for &i in order.iter().rev() {
        let node = &bvh2.nodes[i];
        count[i] = if node.is_leaf() {
            node.prim_count
        } else {
            count[node.first_index as usize] + count[node.first_index as usize + 1]
        };
    }
    count
}

impl WideBvh {
    /// Collapses `bvh2` (over `triangles`, global ids, with `objects` per triangle).
    pub fn from_bvh2(bvh2: &Bvh2, triangles: &[[Vec3; 3]], objects: &[u32]) -> WideBvh {
        if bvh2.nodes.is_empty() {
            return WideBvh::default();
        }
        let counts = subtree_counts(bvh2);
        let mut builder = Builder {
            bvh2,
            counts: &counts,
            triangles,
            objects,
            out: WideBvh::default(),
        };
        let (root, depth) = builder.emit(0);
        builder.out.root = Some(root);
        builder.out.stack_depth = depth + 1;
        builder.out
    }
}

struct Builder<'a> {
    bvh2: &'a Bvh2,
    counts: &'a [u32],
    triangles: &'a [[Vec3; 3]],
    objects: &'a [u32],
    out: WideBvh,
}

impl Builder<'_> {
    /// Emits binary node `i` as a wide node or a leaf; returns its reference and the stack
    /// depth its traversal can need.
    fn emit(&mut self, i: usize) -> (ChildRef, usize) {
        let nodes = &self.bvh2.nodes;
        if nodes[i].is_leaf() || self.counts[i] <= MAX_LEAF_TRIANGLES {
            return (self.emit_leaf(i), 0);
        }
        let mut slots = vec![
            nodes[i].first_index as usize,
            nodes[i].first_index as usize + 1,
        ];
        while slots.len() < 8 {
            let widest = slots
                .iter()
                .enumerate()
                .filter(|&(_, &s)| !nodes[s].is_leaf() && self.counts[s] > OPEN_ABOVE)
                .max_by(|a, b| area(nodes[*a.1].aabb()).total_cmp(&area(nodes[*b.1].aabb())))
                .map(|(k, _)| k);
            let Some(k) = widest else { break };
            let opened = slots.swap_remove(k);
            slots.push(nodes[opened].first_index as usize);
            slots.push(nodes[opened].first_index as usize + 1);
        }
        let index = self.out.nodes.len();
        self.out.nodes.push(WideNode {
            planes: [[0.0; 8]; 6],
            children: [0; 8],
            occupied: 0,
        });
        let mut node = self.out.nodes[index];
        let mut deepest = 0;
        for (slot, &child) in slots.iter().enumerate() {
            let aabb = nodes[child].aabb();
            for axis in 0..3 {
                node.planes[2 * axis][slot] = aabb.min[axis];
                node.planes[2 * axis + 1][slot] = aabb.max[axis];
            }
            let (reference, depth) = self.emit(child);
            node.children[slot] = reference;
            node.occupied |= 1 << slot;
            deepest = deepest.max(depth);
        }
        self.out.nodes[index] = node;
        (index as ChildRef, deepest + slots.len() - 1)
    }

    /// The triangles under binary node `i`, in tree order, as one run of packets.
    fn emit_leaf(&mut self, i: usize) -> ChildRef {
        let mut prims = Vec::with_capacity(self.counts[i] as usize);
        let mut stack = vec![i];
        while let Some(j) = stack.pop() {
            let node = &self.bvh2.nodes[j];
            if node.is_leaf() {
                let first = node.first_index as usize;
                prims.extend(&self.bvh2.primitive_indices[first..first + node.prim_count as usize]);
            } else {
                stack.push(node.first_index as usize + 1);
                stack.push(node.first_index as usize);
            }
        }
        // A packet holds one object's triangles (its `object` is every hit's): group by
        // object (stable, so tree order is kept within an object).
        prims.sort_by_key(|&prim| self.objects[prim as usize]);
        let first = self.out.packets.len();
        for run in prims.chunk_by(|a, b| self.objects[*a as usize] == self.objects[*b as usize]) {
            for chunk in run.chunks(LANES) {
                let mut packet = Packet {
                    vertices: [[[0.0; LANES]; 3]; 3],
                    prims: [EMPTY_LANE; LANES],
                    object: self.objects[chunk[0] as usize],
                    occupied: 0,
                };
                for lane in 0..LANES {
                    let prim = chunk.get(lane).copied();
                    let tri = self.triangles[prim.unwrap_or(chunk[0]) as usize];
                    for (vertex, p) in tri.iter().enumerate() {
                        for axis in 0..3 {
                            packet.vertices[vertex][axis][lane] = Vec3A::from(*p)[axis];
                        }
                    }
                    if let Some(prim) = prim {
                        packet.prims[lane] = prim;
                        packet.occupied |= 1 << lane;
                    }
                }
                self.out.packets.push(packet);
            }
        }
        leaf_ref(first, self.out.packets.len() - first)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Geometry;
    use crate::testing::scene;

    /// The triangles under a child reference, and the deepest pending-entry count a traversal
    /// of it can reach.
    fn subtree(bvh: &WideBvh, child: ChildRef, prims: &mut Vec<(u32, usize)>) -> usize {
        if is_leaf(child) {
            let (first, count) = leaf_packets(child);
            for (k, packet) in bvh.packets[first..first + count].iter().enumerate() {
                for lane in 0..LANES {
                    if packet.occupied & (1 << lane) != 0 {
                        prims.push((packet.prims[lane], first + k));
                    }
                }
            }
            return 0;
        }
        let node = &bvh.nodes[child as usize];
        let k = node.occupied.count_ones() as usize;
        let mut deepest = 0;
        for slot in 0..8 {
            if node.occupied & (1 << slot) != 0 {
                deepest = deepest.max(subtree(bvh, node.children[slot], prims));
            }
        }
        // All k hit children pending, then k − 1 while one of them is traversed.
        k.max(k - 1 + deepest)
    }

    #[test]
    fn collapse_keeps_every_triangle_once_inside_its_boxes() {
        let meshes = scene();
        let geometry = Geometry::new(&meshes);
        let bvh = geometry.wide();
        let mut root_prims = Vec::new();
        let deepest = subtree(bvh, bvh.root.unwrap(), &mut root_prims);
        let mut ids: Vec<u32> = root_prims.iter().map(|p| p.0).collect();
        ids.sort_unstable();
        assert_eq!(ids, (0..geometry.triangle_count()).collect::<Vec<_>>());
        assert!(
            deepest <= bvh.stack_depth,
            "{deepest} > {}",
            bvh.stack_depth
        );
        let (mut children, mut leaves) = (0, 0);
        for node in &bvh.nodes {
            for slot in 0..8 {
                if node.occupied & (1 << slot) == 0 {
                    continue;
                }
                children += 1;
                let mut prims = Vec::new();
                subtree(bvh, node.children[slot], &mut prims);
                leaves += usize::from(is_leaf(node.children[slot]));
                if is_leaf(node.children[slot]) {
                    assert!(prims.len() <= MAX_LEAF_TRIANGLES as usize);
                }
                for &(prim, packet) in &prims {
                    assert_eq!(bvh.packets[packet].object, geometry.object_of(prim));
                    for v in geometry.vertices(prim) {
                        for axis in 0..3 {
                            let (lo, hi) =
                                (node.planes[2 * axis][slot], node.planes[2 * axis + 1][slot]);
                            assert!(lo <= v[axis] && v[axis] <= hi, "prim {prim} outside");
                        }
                    }
                }
            }
        }
        // Wide: most slots used, and far fewer nodes than leaves.
        assert!(
            children as f64 > 4.5 * bvh.nodes.len() as f64 && leaves > 2 * bvh.nodes.len(),
            "{children} children, {leaves} leaves, {} nodes",
            bvh.nodes.len()
        );
    }
}
