//! The tests of the CPU traversal, per instruction set: eight child boxes of a [`WideNode`]
//! against the ray, the triangles of two [`Packet`]s, and the split of a node's hit children
//! into inner nodes and leaves.
//!
//! Every kernel computes the same values in the same order, lane by lane: [`Portable`] is the
//! reference (plain Rust, the kernel on non-x86 targets), [`Sse2`] (the x86-64 baseline) and
//! [`Avx2`] (chosen at run time) must agree with it bit for bit; the tests check this. The
//! triangle test repeats [`watertight::intersect_triangle`](super::watertight) per lane, so hits
//! do not depend on the kernel. This file holds what they share (the [`Kernel`] trait, the hit
//! record, the choice of kernel); `portable.rs`, `x86/` (`sse2.rs`, `avx2.rs`) the kernels.
//!
//! Box test (Ize 2013, *Robust BVH Ray Traversal*): slab distances `(plane − o) · (1/d)`, entry
//! `max(near_x, near_y, near_z, t_min)`, exit `min(far_x, far_y, far_z)` pushed out by `2γ₃` of
//! its magnitude, then clipped to the culling distance `t_far` (the current `t_max`, pushed out
//! the same way, so a box whose entry rounds just past a hit at `t_max` is still visited). All
//! slab distances are finite (inverse directions are at most `1e20`), so `min`/`max` see no NaN
//! except `−∞ + ∞` in a widened exit, which only makes a box visited.

use std::mem::MaybeUninit;

use super::watertight::{PreparedRay, Solution};
use super::wide::{ChildRef, LANES, Packet, WideNode, is_leaf};

/// `2γ₃` with `γₙ = nε / (1 − nε)`, `ε = 2⁻²⁴` (Ize 2013).
const BOX_EXIT_MARGIN: f32 = 2.0 * (3.0 * f32::EPSILON * 0.5) / (1.0 - 3.0 * f32::EPSILON * 0.5);

/// `t + |t| · 2γ₃`: a box exit or culling distance made conservative.
#[inline(always)]
pub(super) fn widen(t: f32) -> f32 {
    t + t.abs() * BOX_EXIT_MARGIN
}

/// Lanes of a triangle test: two packets (one 8-lane test with AVX2).
const HIT_LANES: usize = 2 * LANES;

/// The triangles of two packets that the ray hits with `t_min < t < limit`: bit `4k + i` of
/// `mask` for lane `i` of packet `k`, and that lane's [`Solution`] fields.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct PacketHits {
    pub mask: u32,
    pub t: [f32; HIT_LANES],
    pub v: [f32; HIT_LANES],
    pub w: [f32; HIT_LANES],
    pub det: [f32; HIT_LANES],
}

impl PacketHits {
    pub fn solution(&self, lane: usize) -> Solution {
        Solution {
            t: self.t[lane],
            v: self.v[lane],
            w: self.w[lane],
            det: self.det[lane],
        }
    }
}

/// The arguments of [`Kernel::pair`] for packet `a` and the packet `b` after it, if any.
#[inline(always)]
pub(super) fn pair_of<'p>(a: &'p Packet, b: Option<&'p Packet>) -> (&'p Packet, &'p Packet, u32) {
    match b {
        Some(b) => (a, b, a.occupied | b.occupied << LANES),
        None => (a, a, a.occupied),
    }
}

/// One instruction set's box and triangle tests.
///
/// # Safety
/// The methods may use instructions of the kernel's instruction set: call them only where it
/// is available (checked once at [`Geometry`](super::Geometry) construction).
pub(super) trait Kernel {
    /// The ray in the kernel's registers (splatted).
    type Ray;
    unsafe fn ray(ray: &PreparedRay) -> Self::Ray;
    /// Bit `i` set when child slot `i`'s box overlaps `[t_min, t_far]`; the entry distances go
    /// to `entry`. Empty slots may be set (the caller masks them).
    unsafe fn overlap(node: &WideNode, ray: &Self::Ray, t_far: f32, entry: &mut [f32; 8]) -> u32;
    /// The lanes of `lanes` whose triangles the ray hits with `t_min < t < limit`: lanes 0..4
    /// of packet `a`, 4..8 of `b` (for one packet, pass it twice with no lanes above 4).
    unsafe fn pair(a: &Packet, b: &Packet, ray: &Self::Ray, lanes: u32, limit: f32) -> PacketHits;

    /// Writes the children of `node` in `mask`, in slot order, to the start of `inner` (inner
    /// nodes) and of `leaves`; returns how many went to each. Each slice must hold 8 slots
    /// (a kernel may write all 8).
    #[inline(always)]
    unsafe fn partition(
        node: &WideNode,
        mask: u32,
        inner: &mut [MaybeUninit<ChildRef>],
        leaves: &mut [MaybeUninit<ChildRef>],
    ) -> (usize, usize) {
        let (mut n, mut l) = (0, 0);
        let mut remaining = mask;
        while remaining != 0 {
            let child = node.children[remaining.trailing_zeros() as usize];
            remaining &= remaining - 1;
            if is_leaf(child) {
                leaves[l].write(child);
                l += 1;
            } else {
                inner[n].write(child);
                n += 1;
            }
        }
        (n, l)
    }
}

/// The kernels of this build.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum KernelKind {
    #[cfg(any(test, not(target_arch = "x86_64")))]
    Portable,
    #[cfg(target_arch = "x86_64")]
    Sse2,
    #[cfg(target_arch = "x86_64")]
    Avx2,
}

impl KernelKind {
    /// The fastest kernel this machine runs.
    pub fn detect() -> KernelKind {
        #[cfg(target_arch = "x86_64")]
        return if std::arch::is_x86_feature_detected!("avx2")
            && std::arch::is_x86_feature_detected!("popcnt")
        {
            KernelKind::Avx2
        } else {
            KernelKind::Sse2
        };
        #[cfg(not(target_arch = "x86_64"))]
        KernelKind::Portable
    }

    /// Every kernel this machine runs, the reference first.
    #[cfg(test)]
    pub fn available() -> Vec<KernelKind> {
        let mut kinds = vec![KernelKind::Portable];
        #[cfg(target_arch = "x86_64")]
        {
            kinds.push(KernelKind::Sse2);
            if KernelKind::detect() == KernelKind::Avx2 {
                kinds.push(KernelKind::Avx2);
            }
        }
        kinds
    }
}

/// Plane rows of the near and far planes per axis: `planes[2·axis]` holds minima.
fn plane_rows(ray: &PreparedRay) -> ([usize; 3], [usize; 3]) {
    let near = [0, 1, 2].map(|axis| 2 * axis + usize::from(ray.negative[axis]));
    (near, near.map(|row| row ^ 1))
}

#[cfg(any(test, not(target_arch = "x86_64")))]
mod portable;
#[cfg(any(test, not(target_arch = "x86_64")))]
pub(super) use portable::Portable;

#[cfg(target_arch = "x86_64")]
mod x86;
#[cfg(target_arch = "x86_64")]
pub(super) use x86::{Avx2, Sse2};

#[cfg(test)]
mod tests;
