//! The kernels against the portable reference, bit for bit, on every node and packet of a test
//! scene.

use glam::Vec3A;

use super::*;
use crate::Geometry;
use crate::testing::{rays, scene};
use crate::watertight::intersect_triangle;
use crate::wide::WideBvh;

/// Lanes of a mask.
fn lanes_of(mask: u32) -> impl Iterator<Item = usize> {
    (0..32).filter(move |&i| mask & (1 << i) != 0)
}

fn solution_bits(hits: &PacketHits, lane: usize) -> [u32; 4] {
    let s = hits.solution(lane);
    [s.t, s.v, s.w, s.det].map(f32::to_bits)
}

/// Differences between kernel `K` on `test_ray` and the portable kernel on `ray` over every
/// node and every pair (and single) of packets: (box tests, hit lanes, differing results).
///
/// # Safety
/// `K`'s instruction set must be available.
unsafe fn differences<K: Kernel>(
    bvh: &WideBvh,
    ray: &PreparedRay,
    test_ray: &PreparedRay,
) -> (usize, usize, usize) {
    let (reference, tested) = unsafe { (Portable::ray(ray), K::ray(test_ray)) };
    let (mut boxes, mut hit_lanes, mut differing) = (0, 0, 0);
    for t_far in [ray.t_max, ray.t_min + 0.5] {
        for node in &bvh.nodes {
            let (mut e1, mut e2) = ([0.0f32; 8], [0.0f32; 8]);
            let m1 = unsafe { Portable::overlap(node, &reference, t_far, &mut e1) };
            let m2 = unsafe { K::overlap(node, &tested, t_far, &mut e2) };
            let (m1, m2) = (m1 & node.occupied, m2 & node.occupied);
            let same_entries = lanes_of(m1).all(|i| e1[i].to_bits() == e2[i].to_bits());
            differing += usize::from(m1 != m2 || !same_entries);
            boxes += m1.count_ones() as usize;
        }
        // Pairs, and single packets as the traversal passes them (repeated, no high lanes).
        for width in 1..=2 {
            for chunk in bvh.packets.chunks_exact(width) {
                let (a, b, lanes) = pair_of(&chunk[0], chunk.get(1));
                let h1 = unsafe { Portable::pair(a, b, &reference, lanes, t_far) };
                let h2 = unsafe { K::pair(a, b, &tested, lanes, t_far) };
                let same = h1.mask == h2.mask
                    && lanes_of(h1.mask).all(|l| solution_bits(&h1, l) == solution_bits(&h2, l));
                differing += usize::from(!same);
                hit_lanes += h1.mask.count_ones() as usize;
            }
        }
    }
    (boxes, hit_lanes, differing)
}

#[test]
fn simd_kernels_match_portable_bit_for_bit() {
    let geometry = Geometry::new(&scene());
    let bvh = geometry.wide();
    for kernel in KernelKind::available() {
        let differences = match kernel {
            KernelKind::Portable => continue,
            #[cfg(target_arch = "x86_64")]
            KernelKind::Sse2 => differences::<Sse2>,
            #[cfg(target_arch = "x86_64")]
            KernelKind::Avx2 => differences::<Avx2>,
        };
        let (mut boxes, mut hit_lanes, mut control) = (0, 0, 0);
        for ray in rays(200) {
            let Some(prepared) = PreparedRay::new(&ray) else {
                continue;
            };
            // SAFETY: `available` lists only kernels this machine runs.
            let (b, h, differing) = unsafe { differences(bvh, &prepared, &prepared) };
            assert_eq!(differing, 0, "{kernel:?}: {ray:?}");
            (boxes, hit_lanes) = (boxes + b, hit_lanes + h);
            // Negative control: the origin one ulp away must change some result bits.
            let nudged = PreparedRay {
                origin: prepared.origin + Vec3A::X * prepared.origin.x.abs().max(1.0) * 1.2e-7,
                ..PreparedRay::new(&ray).unwrap()
            };
            control += unsafe { differences(bvh, &prepared, &nudged) }.2;
        }
        assert!(
            boxes > 2_000 && hit_lanes > 500 && control > 200,
            "{kernel:?}: {boxes} boxes, {hit_lanes} hit lanes, control differs {control}"
        );
    }
}

/// `K::partition` of every node under every mask, as (inner, leaves) lists.
///
/// # Safety
/// `K`'s instruction set must be available.
unsafe fn partitions<K: Kernel>(bvh: &WideBvh) -> Vec<(Vec<ChildRef>, Vec<ChildRef>)> {
    let mut lists = Vec::new();
    for node in &bvh.nodes {
        for mask in 0..256 {
            let mask = mask & node.occupied;
            let mut inner = [MaybeUninit::uninit(); 8];
            let mut leaves = [MaybeUninit::uninit(); 8];
            let (n, l) = unsafe { K::partition(node, mask, &mut inner, &mut leaves) };
            // SAFETY: `partition` wrote the first `n` and `l` slots.
            let written = |s: &[MaybeUninit<ChildRef>], k: usize| {
                s[..k].iter().map(|c| unsafe { c.assume_init() }).collect()
            };
            lists.push((written(&inner, n), written(&leaves, l)));
        }
    }
    lists
}

#[test]
fn partitions_match_portable_for_every_mask() {
    let geometry = Geometry::new(&scene());
    let reference = unsafe { partitions::<Portable>(geometry.wide()) };
    let (inner, leaves) = reference
        .iter()
        .fold((0, 0), |(i, l), (a, b)| (i + a.len(), l + b.len()));
    assert!(
        inner > 1000 && leaves > 1000,
        "{inner} inner, {leaves} leaves"
    );
    for kernel in KernelKind::available() {
        let lists = match kernel {
            KernelKind::Portable => continue,
            // SAFETY (both): `available` lists only kernels this machine runs.
            #[cfg(target_arch = "x86_64")]
            KernelKind::Sse2 => unsafe { partitions::<Sse2>(geometry.wide()) },
            #[cfg(target_arch = "x86_64")]
            KernelKind::Avx2 => unsafe { partitions::<Avx2>(geometry.wide()) },
        };
        assert!(lists == reference, "{kernel:?}");
    }
}

#[test]
fn portable_packets_match_the_scalar_triangle_test() {
    let geometry = Geometry::new(&scene());
    let (mut hits, mut swapped) = (0, 0);
    for ray in rays(150) {
        let Some(prepared) = PreparedRay::new(&ray) else {
            continue;
        };
        let reference = unsafe { Portable::ray(&prepared) };
        for packet in &geometry.wide().packets {
            let result = unsafe { Portable::pair(packet, packet, &reference, 0xf, ray.t_max) };
            for lane in lanes_of(packet.occupied) {
                let tri = geometry.vertices(packet.prims[lane]);
                let scalar = intersect_triangle(&tri, &prepared, ray.t_max);
                let lane_hit = (result.mask & (1 << lane) != 0).then(|| {
                    let s = result.solution(lane);
                    (s.t, s.bary())
                });
                let bits = |h: Option<(f32, glam::Vec2)>| {
                    h.map(|(t, b)| [t.to_bits(), b.x.to_bits(), b.y.to_bits()])
                };
                assert_eq!(
                    bits(lane_hit),
                    bits(scalar),
                    "{ray:?}, prim {}",
                    packet.prims[lane]
                );
                hits += usize::from(scalar.is_some());
                // Negative control: the lane's barycentrics swapped would be detected.
                swapped += usize::from(scalar.is_some_and(|(_, b)| b.x != b.y));
            }
        }
    }
    assert!(hits > 100 && swapped > 100, "{hits} hits, {swapped}");
}
