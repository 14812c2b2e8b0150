//! The ray as the traversal kernels see it, and the watertight ray–triangle test of Woop,
//! Benthin & Wald 2013 (a ray through a shared edge or vertex of a closed mesh cannot slip
//! between triangles). [`intersect_triangle`] is the scalar reference: the SIMD packet tests in
//! `kernel` repeat its operations lane by lane and must agree with it bit for bit.

#[cfg(test)]
use glam::Vec3;
use glam::{Mat3A, Vec2, Vec3A};

use super::ray::Ray;

/// Direction components smaller than this in magnitude use `±1/MIN_DIR` as their inverse, which
/// keeps every slab distance finite (no `0 · ∞ = NaN`).
const MIN_DIR: f32 = 1e-20;

/// A ray prepared for traversal: slab inverses and the watertight shear.
pub(super) struct PreparedRay {
    pub origin: Vec3A,
    pub inv_dir: Vec3A,
    pub negative: [bool; 3],
    /// Rows: `e_kx − S_x e_kz`, `e_ky − S_y e_kz`, `S_z e_kz` [Woop et al. 2013, §3].
    pub shear: Mat3A,
    pub t_min: f32,
    pub t_max: f32,
}

impl PreparedRay {
    /// `None` for a zero or non-finite direction, or an empty/non-finite interval.
    #[inline]
    pub fn new(ray: &Ray) -> Option<PreparedRay> {
        let d = ray.dir + Vec3A::ZERO;
        let valid = d.is_finite()
            && d != Vec3A::ZERO
            && ray.origin.is_finite()
            && !ray.t_min.is_nan()
            && !ray.t_max.is_nan()
            && ray.t_min < ray.t_max;
        if !valid {
            return None;
        }
        let abs = d.abs();
        // Reciprocals lane by lane (the same quotients as scalar division).
        let tiny = abs.cmplt(Vec3A::splat(MIN_DIR));
        let inv_dir = Vec3A::ONE / Vec3A::select(tiny, Vec3A::splat(MIN_DIR).copysign(d), d);
        // kz: the axis of largest |d|; (kx, ky) the other two in cyclic order, swapped when
        // d_kz < 0 to keep the winding [Woop et al. 2013, §3]. Constant lane moves per case
        // (no runtime indexing).
        let kz = if abs.x >= abs.y && abs.x >= abs.z {
            0
        } else if abs.y >= abs.z {
            1
        } else {
            2
        };
        let [x, y, z] = d.to_array();
        let (d_kx, d_ky, d_kz) = match kz {
            0 => (y, z, x),
            1 => (z, x, y),
            _ => (x, y, z),
        };
        let flip = d_kz < 0.0;
        let (d_kx, d_ky) = if flip { (d_ky, d_kx) } else { (d_kx, d_ky) };
        // (S_x, S_y, S_z) = (d_kx / d_kz, d_ky / d_kz, 1 / d_kz).
        let s = Vec3A::new(d_kx, d_ky, 1.0) / d_kz;
        // Columns kx, ky, kz of the shear are X, Y and (−S_x, −S_y, S_z).
        let (e_x, e_y, e_z) = (Vec3A::X, Vec3A::Y, Vec3A::new(-s.x, -s.y, s.z));
        let shear = match (kz, flip) {
            (0, false) => Mat3A::from_cols(e_z, e_x, e_y),
            (0, true) => Mat3A::from_cols(e_z, e_y, e_x),
            (1, false) => Mat3A::from_cols(e_y, e_z, e_x),
            (1, true) => Mat3A::from_cols(e_x, e_z, e_y),
            (_, false) => Mat3A::from_cols(e_x, e_y, e_z),
            (_, true) => Mat3A::from_cols(e_y, e_x, e_z),
        };
        Some(PreparedRay {
            origin: ray.origin,
            inv_dir,
            negative: [d.x < 0.0, d.y < 0.0, d.z < 0.0],
            shear,
            t_min: ray.t_min,
            t_max: ray.t_max,
        })
    }
}

/// The edge functions `(u, v, w)` of the sheared vertices `a, b, c`; where one is exactly zero
/// all three are recomputed in `f64` [Woop et al. 2013, §4].
#[inline(always)]
pub(super) fn edge_functions(a: Vec3A, b: Vec3A, c: Vec3A) -> (f32, f32, f32) {
    let u = c.x * b.y - c.y * b.x;
    let v = a.x * c.y - a.y * c.x;
    let w = b.x * a.y - b.y * a.x;
    if u == 0.0 || v == 0.0 || w == 0.0 {
        let (a, b, c) = (a.as_dvec3(), b.as_dvec3(), c.as_dvec3());
        return (
            (c.x * b.y - c.y * b.x) as f32,
            (a.x * c.y - a.y * c.x) as f32,
            (b.x * a.y - b.y * a.x) as f32,
        );
    }
    (u, v, w)
}

/// `shear · (v − origin)` for each vertex: the triangle in the ray's sheared frame.
#[cfg(test)]
#[inline(always)]
pub(super) fn sheared(tri: &[Vec3; 3], ray: &PreparedRay) -> [Vec3A; 3] {
    tri.map(|v| ray.shear * (Vec3A::from(v) - ray.origin))
}

/// A hit of the ray on the sheared triangle `a, b, c`, before the interval test: `t` and the
/// unnormalised barycentrics `v, w` with their sum `det` (`bary = (v, w) / det`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Solution {
    pub t: f32,
    pub v: f32,
    pub w: f32,
    pub det: f32,
}

impl Solution {
    pub fn bary(&self) -> Vec2 {
        Vec2::new(self.v / self.det, self.w / self.det)
    }
}

/// The watertight test on sheared vertices: `None` when the edge functions differ in sign or
/// all vanish [Woop et al. 2013, §3].
#[cfg(any(test, not(target_arch = "x86_64")))]
#[inline(always)]
pub(super) fn solve(a: Vec3A, b: Vec3A, c: Vec3A) -> Option<Solution> {
    let (u, v, w) = edge_functions(a, b, c);
    if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
        return None;
    }
    let det = u + v + w;
    if det == 0.0 {
        return None;
    }
    let t = (u * a.z + v * b.z + w * c.z) / det;
    Some(Solution { t, v, w, det })
}

/// Watertight ray–triangle test [Woop et al. 2013]: `(t, (u, v))` with `t_min < t < t_max`.
/// The reference the packet kernels are tested against.
#[cfg(test)]
#[inline(always)]
pub(super) fn intersect_triangle(
    tri: &[Vec3; 3],
    ray: &PreparedRay,
    t_max: f32,
) -> Option<(f32, Vec2)> {
    let [a, b, c] = sheared(tri, ray);
    let s = solve(a, b, c)?;
    (s.t > ray.t_min && s.t < t_max).then(|| (s.t, s.bary()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::rays;

    /// The construction of Woop et al. 2013 §3 written out with scalar divisions and the shear
    /// rows transposed, as the SIMD version in [`PreparedRay::new`] must reproduce bit for bit.
    fn reference(ray: &Ray) -> (Vec3A, Mat3A) {
        let d = ray.dir + Vec3A::ZERO;
        let inv = |x: f32| {
            if x.abs() < MIN_DIR {
                1.0 / MIN_DIR.copysign(x)
            } else {
                1.0 / x
            }
        };
        let abs = d.abs();
        let kz = if abs.x >= abs.y && abs.x >= abs.z {
            0
        } else if abs.y >= abs.z {
            1
        } else {
            2
        };
        let (mut kx, mut ky) = ((kz + 1) % 3, (kz + 2) % 3);
        if d[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        let (sx, sy, sz) = (d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]);
        let mut rows = [[0.0f32; 3]; 3];
        rows[0][kx] = 1.0;
        rows[0][kz] = -sx;
        rows[1][ky] = 1.0;
        rows[1][kz] = -sy;
        rows[2][kz] = sz;
        (
            Vec3A::new(inv(d.x), inv(d.y), inv(d.z)),
            Mat3A::from_cols_array_2d(&rows).transpose(),
        )
    }

    #[test]
    fn prepared_ray_matches_the_reference_construction() {
        let bits = |v: Vec3A| v.to_array().map(f32::to_bits);
        let mut tiny = rays(200);
        // Components below MIN_DIR in magnitude, of both signs.
        for r in tiny.clone().iter().take(100) {
            let d = r.dir * Vec3A::new(1e-21, 1.0, -1e-22);
            tiny.push(Ray { dir: d, ..*r });
        }
        let mut checked = 0;
        for ray in &tiny {
            let Some(prepared) = PreparedRay::new(ray) else {
                continue;
            };
            let (inv, shear) = reference(ray);
            assert_eq!(bits(prepared.inv_dir), bits(inv), "{ray:?}");
            for (a, b) in [
                (prepared.shear.x_axis, shear.x_axis),
                (prepared.shear.y_axis, shear.y_axis),
                (prepared.shear.z_axis, shear.z_axis),
            ] {
                assert_eq!(bits(a), bits(b), "{ray:?}");
            }
            checked += 1;
        }
        assert!(checked > 1000, "{checked}");
        // Negative control: the comparison tells a transposed shear apart.
        let ray = &tiny[0];
        let (_, shear) = reference(ray);
        assert_ne!(
            bits(PreparedRay::new(ray).unwrap().shear.transpose().x_axis),
            bits(shear.x_axis)
        );
    }
}
