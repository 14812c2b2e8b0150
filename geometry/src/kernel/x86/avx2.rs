//! The AVX2 kernel, chosen at run time where the CPU has AVX2 and POPCNT.

use std::arch::x86_64::*;
use std::mem::MaybeUninit;

use super::{F8, PacketPair, Simd, X86Ray, boxes, triangles, x86_ray};
use crate::kernel::{Kernel, PacketHits};
use crate::watertight::PreparedRay;
use crate::wide::{ChildRef, Packet, WideNode};

/// AVX2: boxes in one 8-lane test, two packets in one 8-lane triangle test.
pub struct Avx2;

impl Kernel for Avx2 {
    type Ray = X86Ray;

    #[inline(always)]
    unsafe fn ray(ray: &PreparedRay) -> X86Ray {
        x86_ray(ray)
    }

    #[inline(always)]
    unsafe fn overlap(node: &WideNode, r: &X86Ray, t_far: f32, entry: &mut [f32; 8]) -> u32 {
        // SAFETY: the caller checked AVX2.
        unsafe {
            let (near, hit) = boxes::<F8>(node, r, t_far);
            near.store(entry);
            hit
        }
    }

    #[inline(always)]
    unsafe fn pair(a: &Packet, b: &Packet, r: &X86Ray, lanes: u32, limit: f32) -> PacketHits {
        let mut hits = PacketHits::default();
        // SAFETY: the caller checked AVX2.
        unsafe { triangles::<F8>(&PacketPair(a, b), r, lanes, limit, &mut hits, 0) };
        hits
    }

    /// Both lists at once by a lane permutation ([`COMPRESS`]), without a branch per child.
    #[inline(always)]
    unsafe fn partition(
        node: &WideNode,
        mask: u32,
        inner: &mut [MaybeUninit<ChildRef>],
        leaves: &mut [MaybeUninit<ChildRef>],
    ) -> (usize, usize) {
        assert!(inner.len() >= 8 && leaves.len() >= 8);
        // SAFETY (whole block): the caller checked AVX2; each store writes 8 slots of a
        // slice that holds them.
        unsafe {
            let children = _mm256_loadu_si256(node.children.as_ptr().cast());
            // The leaf bit is bit 31, the sign of each lane.
            let leaf = _mm256_movemask_ps(_mm256_castsi256_ps(children)) as u32;
            let (inner_mask, leaf_mask) = (mask & !leaf, mask & leaf);
            let inner_lanes = compress(children, inner_mask);
            let leaf_lanes = compress(children, leaf_mask);
            _mm256_storeu_si256(inner.as_mut_ptr().cast(), inner_lanes);
            _mm256_storeu_si256(leaves.as_mut_ptr().cast(), leaf_lanes);
            (
                inner_mask.count_ones() as usize,
                leaf_mask.count_ones() as usize,
            )
        }
    }
}

/// The lanes of `mask` packed to the front (the rest undefined).
///
/// # Safety
/// AVX2 must be available.
#[inline(always)]
unsafe fn compress(lanes: __m256i, mask: u32) -> __m256i {
    unsafe {
        let order = _mm256_set1_epi32(COMPRESS[mask as usize] as i32);
        let nibbles = _mm256_setr_epi32(0, 4, 8, 12, 16, 20, 24, 28);
        // `vpermd` reads the low three bits of each index.
        _mm256_permutevar8x32_epi32(lanes, _mm256_srlv_epi32(order, nibbles))
    }
}

/// For each 8-bit mask, its set slots in increasing order, one per nibble from the lowest:
/// the lane permutation that packs the masked lanes to the front.
static COMPRESS: [u32; 256] = {
    let mut table = [0u32; 256];
    let mut mask = 0;
    while mask < 256 {
        let (mut packed, mut slot, mut order) = (0, 0, 0u32);
        while slot < 8 {
            if mask & (1 << slot) != 0 {
                order |= (slot as u32) << (4 * packed);
                packed += 1;
            }
            slot += 1;
        }
        table[mask] = order;
        mask += 1;
    }
    table
};
