//! The SSE2 kernel, the x86-64 baseline.

use super::{F4, HalfNode, Simd, X86Ray, boxes, triangles, x86_ray};
use crate::kernel::{Kernel, PacketHits};
use crate::watertight::PreparedRay;
use crate::wide::{LANES, Packet, WideNode};

/// SSE2 (the x86_64 baseline): boxes in two 4-lane halves, packets one at a time.
pub struct Sse2;

impl Kernel for Sse2 {
    type Ray = X86Ray;

    #[inline(always)]
    unsafe fn ray(ray: &PreparedRay) -> X86Ray {
        x86_ray(ray)
    }

    #[inline(always)]
    unsafe fn overlap(node: &WideNode, r: &X86Ray, t_far: f32, entry: &mut [f32; 8]) -> u32 {
        // SAFETY (whole block): SSE2 is baseline.
        unsafe {
            let (low, low_hits) = boxes::<F4>(&HalfNode(node, 0), r, t_far);
            let (high, high_hits) = boxes::<F4>(&HalfNode(node, 1), r, t_far);
            low.store(&mut entry[..4]);
            high.store(&mut entry[4..]);
            low_hits | high_hits << 4
        }
    }

    #[inline(always)]
    unsafe fn pair(a: &Packet, b: &Packet, r: &X86Ray, lanes: u32, limit: f32) -> PacketHits {
        let mut hits = PacketHits::default();
        // SAFETY (whole block): SSE2 is baseline.
        unsafe {
            triangles::<F4>(a, r, lanes & 0xf, limit, &mut hits, 0);
            if lanes >> LANES != 0 {
                triangles::<F4>(b, r, lanes >> LANES, limit, &mut hits, LANES);
            }
        }
        hits
    }
}
