//! The portable kernel: plain Rust, one lane at a time. It is the reference the SIMD kernels
//! must match bit for bit, and the kernel of non-x86 targets.

use glam::Vec3A;

use super::{Kernel, PacketHits, plane_rows, widen};
use crate::watertight::{PreparedRay, solve};
use crate::wide::{LANES, Packet, WideNode};

/// Plain Rust: the reference for the SIMD kernels and the kernel of non-x86 targets.
pub(crate) struct Portable;

pub(crate) struct PortableRay {
    origin: Vec3A,
    inv: Vec3A,
    shear: glam::Mat3A,
    t_min: f32,
    near: [usize; 3],
    far: [usize; 3],
}

/// `maxps`/`minps` semantics (the second operand when unordered), so that the portable and
/// SIMD kernels agree even on the NaN of a widened `−∞` exit.
fn max_ps(a: f32, b: f32) -> f32 {
    if a > b { a } else { b }
}

fn min_ps(a: f32, b: f32) -> f32 {
    if a < b { a } else { b }
}

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
