//! The exit point x1, the entry point x2 and the probe ray of BSSRDF IS (DESIGN §9 "Probe ray").

use std::cell::Cell;

use geometry::{Frame, Geometry, Hit, Ray};
use glam::{Vec2, Vec3, Vec3A};

use super::technique::{Axis, RadiusSampling, Technique};
use crate::material::{FresnelTransmission, Translucent};
use crate::profile::Burley;

/// The exit point x1 on a translucent object, with what sampling and evaluation need.
///
/// Normals: `frame` is built from the geometric normal flipped toward the camera; it defines the
/// three projection axes and so enters `p_disk`. The shading normal (flipped to the same side)
/// enters only the Fresnel term `F_t(n1·ωo)`. The profiles (and `F_t`) are cached here for all
/// evaluations at this x1; x2 lies on the same object, so they serve `F_t(n2·ωi)` too.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExitPoint {
    pub position: Vec3,
    pub frame: Frame,
    pub shading_normal: Vec3,
    /// Unit direction from x1 toward the camera (ωo).
    pub view: Vec3,
    pub object: u32,
    /// Per-channel profiles `d_c` and their truncation radii `r_max,c`.
    pub profiles: [Burley; 3],
    pub r_max: Vec3,
    /// The material's normalised Fresnel transmittance `F_t`.
    pub fresnel: FresnelTransmission,
    /// `F_t(n1·ωo)` of the shading normal and view above, which every BSSRDF value at this x1
    /// multiplies by.
    pub fresnel_out: f32,
}

/// The material's per-channel profiles and Fresnel transmittance (its `F_t` normalisation takes
/// two logarithms). A scene has a few materials and a reuse pass builds millions of exit points,
/// so each thread keeps the last material's: the same values, computed once per run of equal
/// materials.
fn derived(material: &Translucent) -> ([Burley; 3], FresnelTransmission) {
    type Derived = (Translucent, [Burley; 3], FresnelTransmission);
    thread_local! {
        static LAST: Cell<Option<Derived>> = const { Cell::new(None) };
    }
    LAST.with(|last| match last.get() {
        Some((m, profiles, fresnel)) if m == *material => (profiles, fresnel),
        _ => {
            let profiles = material.d().to_array().map(Burley::new);
            let fresnel = material.fresnel();
            last.set(Some((*material, profiles, fresnel)));
            (profiles, fresnel)
        }
    })
}

impl ExitPoint {
    /// `geometric_normal` must already face the camera; the shading normal is flipped to its side.
    pub fn new(
        position: Vec3,
        geometric_normal: Vec3,
        shading_normal: Vec3,
        view: Vec3,
        object: u32,
        material: &Translucent,
    ) -> ExitPoint {
        let (profiles, fresnel) = derived(material);
        ExitPoint::with_profiles(
            position,
            geometric_normal,
            shading_normal,
            view,
            object,
            profiles,
            fresnel,
        )
    }

    /// [`ExitPoint::new`] with explicit profiles (their `r_max` derived) instead of the
    /// material's, e.g. the full profile that samples paper 000's `R − R1`.
    pub fn with_profiles(
        position: Vec3,
        geometric_normal: Vec3,
        shading_normal: Vec3,
        view: Vec3,
        object: u32,
        profiles: [Burley; 3],
        fresnel: FresnelTransmission,
    ) -> ExitPoint {
        let shading_normal = if shading_normal.dot(geometric_normal) < 0.0 {
            -shading_normal
        } else {
            shading_normal
        };
        ExitPoint {
            position,
            frame: Frame::from_normal(geometric_normal),
            shading_normal,
            view,
            object,
            profiles,
            r_max: Vec3::from_array(profiles.map(|p| p.r_max())),
            fresnel,
            fresnel_out: fresnel.eval(shading_normal.dot(view)),
        }
    }

    /// Right-handed basis `(p_x, p_y, p_z)` of the disk of `axis`, `p_z` = the axis:
    /// normal `(t, b, n)`, tangent `(b, n, t)`, bitangent `(n, t, b)`.
    pub fn disk_basis(&self, axis: Axis) -> [Vec3; 3] {
        let Frame { t, b, n } = self.frame;
        match axis {
            Axis::Normal => [t, b, n],
            Axis::Tangent => [b, n, t],
            Axis::Bitangent => [n, t, b],
        }
    }

    /// Disk coordinates `(l·p_x, l·p_y)` of `x2` for `axis`, `l = x2 − x1`; their length is `r_a`.
    pub fn disk_coordinates(&self, axis: Axis, x2: Vec3) -> Vec2 {
        let [px, py, _] = self.disk_basis(axis);
        let l = x2 - self.position;
        Vec2::new(l.dot(px), l.dot(py))
    }
}

/// The entry point x2: a surface point identified by triangle and barycentrics.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EntryPoint {
    pub object: u32,
    pub prim: u32,
    pub bary: Vec2,
    pub position: Vec3,
    /// Unit, from the triangle's winding (outward on closed meshes); enters `p_disk`.
    pub geometric_normal: Vec3,
    /// Enters the cosine and `F_t(n2·ωi)`; not flipped.
    pub shading_normal: Vec3,
}

impl EntryPoint {
    pub fn new(geometry: &Geometry, prim: u32, bary: Vec2) -> EntryPoint {
        EntryPoint {
            object: geometry.object_of(prim),
            prim,
            bary,
            position: geometry.position(prim, bary),
            geometric_normal: geometry.geometric_normal(prim),
            shading_normal: geometry.shading_normal(prim, bary),
        }
    }

    pub fn from_hit(geometry: &Geometry, hit: &Hit) -> EntryPoint {
        EntryPoint::new(geometry, hit.prim, hit.bary)
    }
}

/// The probe ray of technique `t` through the disk point at polar coordinates `(r, φ)`: the chord
/// of the `r_max,c` sphere around x1 along `−axis`, `t ∈ (0, 2h)`, `h = √(r_max,c² − r²)`.
/// `None` when `r ≥ r_max,c` (the chord is empty).
pub fn chord(x1: &ExitPoint, t: Technique, disk: Vec2) -> Option<Ray> {
    let r_max = x1.r_max[t.channel];
    let h2 = r_max * r_max - disk.length_squared();
    if h2.is_nan() || h2 <= 0.0 {
        return None;
    }
    let h = h2.sqrt();
    let [px, py, axis] = x1.disk_basis(t.axis);
    let q = x1.position + disk.x * px + disk.y * py;
    Some(Ray::new(
        Vec3A::from(q + h * axis),
        Vec3A::from(-axis),
        0.0,
        2.0 * h,
    ))
}

/// The probe ray for technique `t` and random numbers `(u_radius, u_angle)`: radius by the exact
/// inverse CDF of channel `c`, angle `2π u_angle` [001 Eq. 4, Fig. 2b].
pub fn probe_ray(x1: &ExitPoint, t: Technique, u_radius: f32, u_angle: f32) -> Option<Ray> {
    probe_ray_with(x1, t, RadiusSampling::Exact, u_radius, u_angle)
}

/// [`probe_ray`] with the radius drawn by `radius` instead of the exact inverse CDF.
pub fn probe_ray_with(
    x1: &ExitPoint,
    t: Technique,
    radius: RadiusSampling,
    u_radius: f32,
    u_angle: f32,
) -> Option<Ray> {
    let r = radius.sample_radius(&x1.profiles[t.channel], u_radius);
    let phi = std::f32::consts::TAU * u_angle;
    chord(x1, t, r * Vec2::new(phi.cos(), phi.sin()))
}

/// All hits of `ray` on x1's object, sorted by `t`; the intersection index is the rank.
pub fn trace_probe(geometry: &Geometry, x1: &ExitPoint, ray: &Ray, hits: &mut Vec<Hit>) {
    geometry.all_hits_on_object(ray, x1.object, hits);
}
