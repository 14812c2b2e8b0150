//! The x86-64 kernels: the box and triangle tests written once over 4-lane (SSE) and 8-lane
//! (AVX) registers ([`Simd`]), and the kernels that use them, [`Sse2`] and [`Avx2`].

use std::arch::x86_64::*;

use glam::Vec3A;

use super::{BOX_EXIT_MARGIN, HIT_LANES, PacketHits, plane_rows};
use crate::watertight::{PreparedRay, edge_functions};
use crate::wide::{Packet, WideNode};

mod avx2;
mod sse2;

pub use avx2::Avx2;
pub use sse2::Sse2;

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
