//! The tests of the CPU traversal, per instruction set: eight child boxes of a [`WideNode`]
//! against the ray, the triangles of two [`Packet`]s, and the split of a node's hit children
//! into inner nodes and leaves.
//!
//! Every kernel computes the same values in the same order, lane by lane: [`Portable`] is the
//! reference (plain Rust, the kernel on non-x86 targets), [`Sse2`] (the x86-64 baseline) and
//! [`Avx2`] (chosen at run time) must agree with it bit for bit; the tests check this. The
//! triangle test repeats [`watertight::intersect_triangle`](super::watertight) per lane, so hits
//! do not depend on the kernel.
//!
//! Box test (Ize 2013, *Robust BVH Ray Traversal*): slab distances `(plane − o) · (1/d)`, entry
//! `max(near_x, near_y, near_z, t_min)`, exit `min(far_x, far_y, far_z)` pushed out by `2γ₃` of
//! its magnitude, then clipped to the culling distance `t_far` (the current `t_max`, pushed out
//! the same way, so a box whose entry rounds just past a hit at `t_max` is still visited). All
//! slab distances are finite (inverse directions are at most `1e20`), so `min`/`max` see no NaN
//! except `−∞ + ∞` in a widened exit, which only makes a box visited.

#[cfg(any(test, not(target_arch = "x86_64")))]
use glam::Vec3A;

#[cfg(any(test, not(target_arch = "x86_64")))]
use super::watertight::solve;
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

/// Plain Rust: the reference for the SIMD kernels and the kernel of non-x86 targets.
#[cfg(any(test, not(target_arch = "x86_64")))]
pub(super) struct Portable;

#[cfg(any(test, not(target_arch = "x86_64")))]
pub(super) struct PortableRay {
    origin: Vec3A,
    inv: Vec3A,
    shear: glam::Mat3A,
    t_min: f32,
    near: [usize; 3],
    far: [usize; 3],
}

/// `maxps`/`minps` semantics (the second operand when unordered), so that the portable and
/// SIMD kernels agree even on the NaN of a widened `−∞` exit.
#[cfg(any(test, not(target_arch = "x86_64")))]
fn max_ps(a: f32, b: f32) -> f32 {
    if a > b { a } else { b }
}

#[cfg(any(test, not(target_arch = "x86_64")))]
fn min_ps(a: f32, b: f32) -> f32 {
    if a < b { a } else { b }
}

#[cfg(any(test, not(target_arch = "x86_64")))]
impl Kernel for Portable {
    type Ray = PortableRay;

    unsafe fn ray(ray: &PreparedRay) -> PortableRay {
        let (near, far) = plane_rows(ray);
        PortableRay {
            origin: ray.origin,
            inv: ray.inv_dir,
            shear: ray.shear,
            t_min: ray.t_min,
            near,
            far,
        }
    }

    unsafe fn overlap(node: &WideNode, r: &PortableRay, t_far: f32, entry: &mut [f32; 8]) -> u32 {
        let (o, inv) = (r.origin, r.inv);
        let mut mask = 0;
        for lane in 0..8 {
            let t = |row: usize, axis: usize| (node.planes[row][lane] - o[axis]) * inv[axis];
            let near = max_ps(
                max_ps(max_ps(t(r.near[0], 0), t(r.near[1], 1)), t(r.near[2], 2)),
                r.t_min,
            );
            let far = min_ps(min_ps(t(r.far[0], 0), t(r.far[1], 1)), t(r.far[2], 2));
            let far = min_ps(widen(far), t_far);
            entry[lane] = near;
            mask |= u32::from(near <= far) << lane;
        }
        mask
    }

    unsafe fn pair(a: &Packet, b: &Packet, r: &PortableRay, lanes: u32, limit: f32) -> PacketHits {
        let mut hits = PacketHits::default();
        for (k, packet) in [a, b].into_iter().enumerate() {
            for lane in 0..LANES {
                let bit = k * LANES + lane;
                if lanes & (1 << bit) == 0 {
                    continue;
                }
                let vertex = |i: usize| {
                    let v = packet.vertices[i];
                    r.shear * (Vec3A::new(v[0][lane], v[1][lane], v[2][lane]) - r.origin)
                };
                let Some(s) = solve(vertex(0), vertex(1), vertex(2)) else {
                    continue;
                };
                if s.t > r.t_min && s.t < limit {
                    hits.mask |= 1 << bit;
                    (hits.t[bit], hits.v[bit], hits.w[bit], hits.det[bit]) = (s.t, s.v, s.w, s.det);
                }
            }
        }
        hits
    }
}

#[cfg(target_arch = "x86_64")]
pub(super) use x86::{Avx2, Sse2};

#[cfg(target_arch = "x86_64")]
mod x86 {
    use std::arch::x86_64::*;

    use glam::Vec3A;

    use super::{BOX_EXIT_MARGIN, HIT_LANES, Kernel, PacketHits, plane_rows};
    use crate::watertight::{PreparedRay, edge_functions};
    use std::mem::MaybeUninit;

    use crate::wide::{ChildRef, LANES, Packet, WideNode};

    /// Lane-wise `f32` operations on 4 (SSE) or 8 (AVX) lanes: the box and triangle tests are
    /// written once over this. Comparisons return all-ones lanes; `max`/`min` return the second
    /// operand when unordered (`maxps`/`minps`).
    ///
    /// # Safety
    /// The methods use their instruction set (SSE2 is baseline; AVX must be available).
    trait Simd: Copy {
        unsafe fn splat(x: f32) -> Self;
        unsafe fn add(self, b: Self) -> Self;
        unsafe fn sub(self, b: Self) -> Self;
        unsafe fn mul(self, b: Self) -> Self;
        unsafe fn div(self, b: Self) -> Self;
        unsafe fn max(self, b: Self) -> Self;
        unsafe fn min(self, b: Self) -> Self;
        unsafe fn lt(self, b: Self) -> Self;
        unsafe fn gt(self, b: Self) -> Self;
        unsafe fn le(self, b: Self) -> Self;
        unsafe fn eq(self, b: Self) -> Self;
        unsafe fn ne(self, b: Self) -> Self;
        unsafe fn and(self, b: Self) -> Self;
        unsafe fn or(self, b: Self) -> Self;
        /// `!self & b`.
        unsafe fn and_not(self, b: Self) -> Self;
        /// Sign bits, lane `i` in bit `i`.
        unsafe fn mask(self) -> u32;
        /// Writes the lanes to the start of `out`.
        unsafe fn store(self, out: &mut [f32]);
        /// Reads the lanes from the start of `src`.
        unsafe fn load(src: &[f32]) -> Self;

        #[inline(always)]
        unsafe fn abs(self) -> Self {
            unsafe { Self::splat(-0.0).and_not(self) }
        }
    }

    #[derive(Clone, Copy)]
    struct F4(__m128);

    #[derive(Clone, Copy)]
    struct F8(__m256);

    /// `Simd` for a register type: two-operand operations by intrinsic, comparisons by
    /// predicate of `$cmp`.
    macro_rules! simd_impl {
        ($t:ident, $lanes:expr, $set1:ident, $movemask:ident, $storeu:ident, $loadu:ident,
         $cmp:ident, ops: [$($op:ident = $intrinsic:ident),*],
         comparisons: [$($test:ident = $predicate:ident),*]) => {
            impl Simd for $t {
                #[inline(always)]
                unsafe fn splat(x: f32) -> Self {
                    unsafe { $t($set1(x)) }
                }
                $(
                    #[inline(always)]
                    unsafe fn $op(self, b: Self) -> Self {
                        unsafe { $t($intrinsic(self.0, b.0)) }
                    }
                )*
                $(
                    #[inline(always)]
                    unsafe fn $test(self, b: Self) -> Self {
                        unsafe { $t($cmp(self.0, b.0, $predicate)) }
                    }
                )*
                #[inline(always)]
                unsafe fn mask(self) -> u32 {
                    unsafe { $movemask(self.0) as u32 }
                }
                #[inline(always)]
                unsafe fn store(self, out: &mut [f32]) {
                    assert!(out.len() >= $lanes);
                    unsafe { $storeu(out.as_mut_ptr(), self.0) }
                }
                #[inline(always)]
                unsafe fn load(src: &[f32]) -> Self {
                    assert!(src.len() >= $lanes);
                    unsafe { $t($loadu(src.as_ptr())) }
                }
            }
        };
    }

    /// SSE comparisons by predicate, as `_mm256_cmp_ps` takes them (all SSE2).
    #[inline(always)]
    unsafe fn cmp_sse(a: __m128, b: __m128, predicate: i32) -> __m128 {
        unsafe {
            match predicate {
                _CMP_LT_OQ => _mm_cmplt_ps(a, b),
                _CMP_GT_OQ => _mm_cmpgt_ps(a, b),
                _CMP_LE_OQ => _mm_cmple_ps(a, b),
                _CMP_EQ_OQ => _mm_cmpeq_ps(a, b),
                _ => _mm_cmpneq_ps(a, b),
            }
        }
    }

    #[inline(always)]
    unsafe fn cmp_avx(a: __m256, b: __m256, predicate: i32) -> __m256 {
        unsafe {
            match predicate {
                _CMP_LT_OQ => _mm256_cmp_ps::<_CMP_LT_OQ>(a, b),
                _CMP_GT_OQ => _mm256_cmp_ps::<_CMP_GT_OQ>(a, b),
                _CMP_LE_OQ => _mm256_cmp_ps::<_CMP_LE_OQ>(a, b),
                _CMP_EQ_OQ => _mm256_cmp_ps::<_CMP_EQ_OQ>(a, b),
                _ => _mm256_cmp_ps::<_CMP_NEQ_UQ>(a, b),
            }
        }
    }

    simd_impl!(F4, 4, _mm_set1_ps, _mm_movemask_ps, _mm_storeu_ps, _mm_loadu_ps, cmp_sse,
        ops: [add = _mm_add_ps, sub = _mm_sub_ps, mul = _mm_mul_ps, div = _mm_div_ps,
              max = _mm_max_ps, min = _mm_min_ps, and = _mm_and_ps, or = _mm_or_ps,
              and_not = _mm_andnot_ps],
        comparisons: [lt = _CMP_LT_OQ, gt = _CMP_GT_OQ, le = _CMP_LE_OQ, eq = _CMP_EQ_OQ,
                      ne = _CMP_NEQ_UQ]);
    simd_impl!(F8, 8, _mm256_set1_ps, _mm256_movemask_ps, _mm256_storeu_ps, _mm256_loadu_ps,
        cmp_avx,
        ops: [add = _mm256_add_ps, sub = _mm256_sub_ps, mul = _mm256_mul_ps,
              div = _mm256_div_ps, max = _mm256_max_ps, min = _mm256_min_ps,
              and = _mm256_and_ps, or = _mm256_or_ps, and_not = _mm256_andnot_ps],
        comparisons: [lt = _CMP_LT_OQ, gt = _CMP_GT_OQ, le = _CMP_LE_OQ, eq = _CMP_EQ_OQ,
                      ne = _CMP_NEQ_UQ]);

    /// The ray as both x86 kernels use it.
    pub struct X86Ray {
        origin: [f32; 3],
        inv: [f32; 3],
        near: [usize; 3],
        far: [usize; 3],
        t_min: f32,
        /// `shear[column][row]`, as `Mat3A` columns.
        shear: [[f32; 3]; 3],
    }

    #[inline(always)]
    fn x86_ray(ray: &PreparedRay) -> X86Ray {
        let (near, far) = plane_rows(ray);
        let m = &ray.shear;
        X86Ray {
            origin: ray.origin.to_array(),
            inv: ray.inv_dir.to_array(),
            near,
            far,
            t_min: ray.t_min,
            shear: [
                m.x_axis.to_array(),
                m.y_axis.to_array(),
                m.z_axis.to_array(),
            ],
        }
    }

    /// Where a SIMD test reads its lanes: plane rows of child slots, or vertex coordinates of
    /// packet lanes. (Accessors, not closures: closures would not inherit the AVX2 target
    /// feature and would not inline.)
    trait Rows<V> {
        /// Plane row `row` (box test) or coordinate `axis` of vertex `k` (`row = 3k + axis`).
        unsafe fn row(&self, row: usize) -> V;
    }

    /// Child slots `4·half .. 4·half + 4` of a node.
    struct HalfNode<'a>(&'a WideNode, usize);

    impl Rows<F4> for HalfNode<'_> {
        #[inline(always)]
        unsafe fn row(&self, row: usize) -> F4 {
            unsafe { F4::load(&self.0.planes[row][4 * self.1..]) }
        }
    }

    impl Rows<F8> for WideNode {
        #[inline(always)]
        unsafe fn row(&self, row: usize) -> F8 {
            unsafe { F8::load(&self.planes[row]) }
        }
    }

    impl Rows<F4> for Packet {
        #[inline(always)]
        unsafe fn row(&self, row: usize) -> F4 {
            unsafe { F4::load(&self.vertices[row / 3][row % 3]) }
        }
    }

    /// Two packets as eight lanes (the first in lanes 0..4).
    struct PacketPair<'a>(&'a Packet, &'a Packet);

    impl Rows<F8> for PacketPair<'_> {
        #[inline(always)]
        unsafe fn row(&self, row: usize) -> F8 {
            unsafe {
                let (low, high): (F4, F4) = (self.0.row(row), self.1.row(row));
                F8(_mm256_set_m128(high.0, low.0))
            }
        }
    }

    /// `(plane − o_axis) · inv_axis` for plane row `row`.
    #[inline(always)]
    unsafe fn slab<V: Simd>(rows: &impl Rows<V>, r: &X86Ray, row: usize, axis: usize) -> V {
        unsafe {
            rows.row(row)
                .sub(V::splat(r.origin[axis]))
                .mul(V::splat(r.inv[axis]))
        }
    }

    /// [`Portable::overlap`](super::Portable) on the child slots of `rows`: the entry distances
    /// and the hit lanes.
    #[inline(always)]
    unsafe fn boxes<V: Simd>(rows: &impl Rows<V>, r: &X86Ray, t_far: f32) -> (V, u32) {
        unsafe {
            let near = slab(rows, r, r.near[0], 0)
                .max(slab(rows, r, r.near[1], 1))
                .max(slab(rows, r, r.near[2], 2))
                .max(V::splat(r.t_min));
            let far = slab(rows, r, r.far[0], 0)
                .min(slab(rows, r, r.far[1], 1))
                .min(slab(rows, r, r.far[2], 2));
            let far = far.add(far.abs().mul(V::splat(BOX_EXIT_MARGIN)));
            let far = far.min(V::splat(t_far));
            (near, near.le(far).mask())
        }
    }

    /// Component `c` of `shear · rel`: `(X_c·rx + Y_c·ry) + Z_c·rz`, as `Mat3A * Vec3A`.
    #[inline(always)]
    unsafe fn shear_component<V: Simd>(r: &X86Ray, rel: &[V; 3], c: usize) -> V {
        unsafe {
            let x = V::splat(r.shear[0][c]).mul(rel[0]);
            let y = V::splat(r.shear[1][c]).mul(rel[1]);
            let z = V::splat(r.shear[2][c]).mul(rel[2]);
            x.add(y).add(z)
        }
    }

    /// Vertex `k` of every lane in the ray's sheared frame: `shear · (v − o)`.
    #[inline(always)]
    unsafe fn sheared<V: Simd>(rows: &impl Rows<V>, r: &X86Ray, k: usize) -> [V; 3] {
        unsafe {
            let rel = [
                rows.row(3 * k).sub(V::splat(r.origin[0])),
                rows.row(3 * k + 1).sub(V::splat(r.origin[1])),
                rows.row(3 * k + 2).sub(V::splat(r.origin[2])),
            ];
            [
                shear_component(r, &rel, 0),
                shear_component(r, &rel, 1),
                shear_component(r, &rel, 2),
            ]
        }
    }

    /// `p.x · q.y − p.y · q.x`.
    #[inline(always)]
    unsafe fn cross<V: Simd>(p: &[V; 3], q: &[V; 3]) -> V {
        unsafe { p[0].mul(q[1]).sub(p[1].mul(q[0])) }
    }

    /// The lanes of `x`.
    #[inline(always)]
    unsafe fn lanes_of<V: Simd>(x: V) -> [f32; HIT_LANES] {
        let mut out = [0.0; HIT_LANES];
        unsafe { x.store(&mut out) };
        out
    }

    /// `edge_functions`' f64 recomputation for the lanes of `fallback` (rare).
    #[cold]
    #[inline(never)]
    fn recompute_edges(
        sheared: [[[f32; HIT_LANES]; 3]; 3],
        uvw: &mut [[f32; HIT_LANES]; 3],
        fallback: u32,
    ) {
        let mut remaining = fallback;
        while remaining != 0 {
            let lane = remaining.trailing_zeros() as usize;
            remaining &= remaining - 1;
            let [a, b, c] = sheared.map(|p| Vec3A::new(p[0][lane], p[1][lane], p[2][lane]));
            let (u, v, w) = edge_functions(a, b, c);
            (uvw[0][lane], uvw[1][lane], uvw[2][lane]) = (u, v, w);
        }
    }

    /// [`Portable::packets`](super::Portable) on the triangle lanes of `rows`, written to `hits`
    /// from lane `base`.
    #[inline(always)]
    unsafe fn triangles<V: Simd>(
        rows: &impl Rows<V>,
        r: &X86Ray,
        lanes: u32,
        limit: f32,
        hits: &mut PacketHits,
        base: usize,
    ) {
        unsafe {
            let (a, b, c) = (
                sheared(rows, r, 0),
                sheared(rows, r, 1),
                sheared(rows, r, 2),
            );
            let (mut u, mut v, mut w) = (cross(&c, &b), cross(&a, &c), cross(&b, &a));
            let zero = V::splat(0.0);
            let fallback = u.eq(zero).or(v.eq(zero)).or(w.eq(zero)).mask() & lanes;
            if fallback != 0 {
                let point = |p: &[V; 3]| [lanes_of(p[0]), lanes_of(p[1]), lanes_of(p[2])];
                let mut uvw = [lanes_of(u), lanes_of(v), lanes_of(w)];
                recompute_edges([point(&a), point(&b), point(&c)], &mut uvw, fallback);
                (u, v, w) = (V::load(&uvw[0]), V::load(&uvw[1]), V::load(&uvw[2]));
            }
            let negative = u.lt(zero).or(v.lt(zero)).or(w.lt(zero));
            let positive = u.gt(zero).or(v.gt(zero)).or(w.gt(zero));
            // Lanes whose edge functions do not differ in sign (most lanes of a leaf fail here).
            let same_side = negative.and(positive).and_not(zero.eq(zero));
            if same_side.mask() & lanes == 0 {
                return;
            }
            let det = u.add(v).add(w);
            let t = u.mul(a[2]).add(v.mul(b[2])).add(w.mul(c[2])).div(det);
            let hit = same_side
                .and(det.ne(zero))
                .and(t.gt(V::splat(r.t_min)))
                .and(t.lt(V::splat(limit)));
            hits.mask |= (hit.mask() & lanes) << base;
            t.store(&mut hits.t[base..]);
            v.store(&mut hits.v[base..]);
            w.store(&mut hits.w[base..]);
            det.store(&mut hits.det[base..]);
        }
    }

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
}

#[cfg(test)]
mod tests {
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
                        && lanes_of(h1.mask)
                            .all(|l| solution_bits(&h1, l) == solution_bits(&h2, l));
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
}
