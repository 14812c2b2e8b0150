//! Lights and many-light selection (DESIGN §4): one-sided emissive quads and triangles sampled by
//! area, spheres sampled by the solid angle of their visible cap, and delta point and directional
//! lights. A light is picked with probability proportional to its power.
//!
//! The lights of a scene file's `[[lights]]` are not part of the BVH: they neither occlude nor
//! show up in camera rays unless the scene also adds an object with matching geometry. An
//! emissive object's triangles are lights too ([`Light::Triangle`], one- or two-sided as its
//! material says) and are geometry: those emitters occlude and are seen.
//!
//! Every sampler is paired with its solid-angle pdf ([`Lights::sample`] ↔ [`Lights::pdf`]); for
//! delta lights the sample's `pdf` is only the selection probability and its `radiance` is the
//! quantity that takes the place of `L_e` in `f · L / pdf` (intensity / distance² for a point
//! light, the irradiance for a directional one).

use std::f32::consts::PI;

use geometry::Frame;
use glam::Vec3;

use crate::color::luminance;
use crate::sampling::sample_uniform_triangle;

pub use crate::contract::light::DIRECTIONAL_DISTANCE;

/// One light source.
#[derive(Clone, Debug, PartialEq)]
pub enum Light {
    /// Parallelogram `corner + s·edge_u + t·edge_v`, `s, t ∈ [0, 1]`, emitting radiance `radiance`
    /// from the side of `edge_u × edge_v` only.
    Quad {
        corner: Vec3,
        edge_u: Vec3,
        edge_v: Vec3,
        radiance: Vec3,
    },
    /// Triangle emitting `radiance` from the side of `(v1 − v0) × (v2 − v0)`, and from both
    /// sides when `two_sided` (a triangle of a two-sided emissive mesh).
    Triangle {
        vertices: [Vec3; 3],
        radiance: Vec3,
        two_sided: bool,
    },
    /// Sphere emitting `radiance` outward from its whole surface.
    Sphere {
        center: Vec3,
        radius: f32,
        radiance: Vec3,
    },
    /// Isotropic point light of radiant intensity `intensity` (W/sr).
    Point { position: Vec3, intensity: Vec3 },
    /// Light arriving along the unit `direction` (the direction of travel) with irradiance
    /// `irradiance` on a surface facing it.
    Directional { direction: Vec3, irradiance: Vec3 },
}

/// A point sampled on a light as seen from a shading point x2.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSample {
    pub light: u32,
    /// The light vertex x3.
    pub point: Vec3,
    /// Surface normal at x3 (facing x2 for area lights; the direction of travel for directional
    /// lights; zero for point lights).
    pub normal: Vec3,
    /// Unit direction x2 → x3.
    pub wi: Vec3,
    /// ‖x3 − x2‖.
    pub distance: f32,
    /// `L_e` toward x2 (for delta lights, see the module documentation).
    pub radiance: Vec3,
    /// Solid-angle density at x2 including the selection probability; for delta lights the
    /// selection probability alone.
    pub pdf: f32,
    pub is_delta: bool,
}

/// A point on one light, before selection: `(point, normal, solid-angle pdf, radiance)`.
struct PointOnLight {
    point: Vec3,
    normal: Vec3,
    pdf: f32,
    radiance: Vec3,
}

impl Light {
    pub fn is_delta(&self) -> bool {
        matches!(self, Light::Point { .. } | Light::Directional { .. })
    }

    /// Emitted power (luminance of watts); a directional light counts the power falling on the
    /// disk of radius `scene_radius` that covers the scene.
    pub fn power(&self, scene_radius: f32) -> f32 {
        match *self {
            Light::Quad {
                edge_u,
                edge_v,
                radiance,
                ..
            } => PI * edge_u.cross(edge_v).length() * luminance(radiance),
            Light::Triangle {
                vertices: [v0, v1, v2],
                radiance,
                two_sided,
            } => {
                let sides = if two_sided { 2.0 } else { 1.0 };
                sides * PI * 0.5 * (v1 - v0).cross(v2 - v0).length() * luminance(radiance)
            }
            Light::Sphere {
                radius, radiance, ..
            } => 4.0 * PI * PI * radius * radius * luminance(radiance),
            Light::Point { intensity, .. } => 4.0 * PI * luminance(intensity),
            Light::Directional { irradiance, .. } => {
                PI * scene_radius * scene_radius * luminance(irradiance)
            }
        }
    }

    /// `L_e` leaving `point` (on this light) toward `toward`; zero from the back of one-sided
    /// emitters and from points of a sphere that face away from `toward`.
    pub fn radiance(&self, point: Vec3, toward: Vec3) -> Vec3 {
        match *self {
            Light::Quad {
                edge_u,
                edge_v,
                radiance,
                ..
            } => {
                if edge_u.cross(edge_v).dot(toward - point) > 0.0 {
                    radiance
                } else {
                    Vec3::ZERO
                }
            }
            Light::Triangle {
                vertices: [v0, v1, v2],
                radiance,
                two_sided,
            } => {
                if two_sided || (v1 - v0).cross(v2 - v0).dot(toward - point) > 0.0 {
                    radiance
                } else {
                    Vec3::ZERO
                }
            }
            Light::Sphere {
                center, radiance, ..
            } => {
                if (point - center).dot(toward - point) > 0.0 {
                    radiance
                } else {
                    Vec3::ZERO
                }
            }
            Light::Point { intensity, .. } => {
                let d2 = point.distance_squared(toward);
                if d2 > 0.0 { intensity / d2 } else { Vec3::ZERO }
            }
            Light::Directional { irradiance, .. } => irradiance,
        }
    }

    /// Samples a point of this light seen from `x`, with its solid-angle pdf; `None` when the
    /// point cannot emit toward `x` (behind a one-sided emitter, degenerate configuration).
    fn sample_point(&self, x: Vec3, u: [f32; 2]) -> Option<PointOnLight> {
        match *self {
            Light::Quad {
                corner,
                edge_u,
                edge_v,
                radiance,
            } => {
                let point = corner + u[0] * edge_u + u[1] * edge_v;
                let normal = edge_u.cross(edge_v).normalize();
                let pdf = self.pdf(x, point);
                (pdf > 0.0).then_some(PointOnLight {
                    point,
                    normal,
                    pdf,
                    radiance,
                })
            }
            Light::Triangle {
                vertices: [v0, v1, v2],
                radiance,
                two_sided,
            } => {
                let [b0, b1, b2] = sample_uniform_triangle(u);
                let point = b0 * v0 + b1 * v1 + b2 * v2;
                let winding = (v1 - v0).cross(v2 - v0).normalize();
                // A two-sided emitter's normal at x3 faces x2, as a one-sided one's must.
                let normal = if two_sided && winding.dot(x - point) < 0.0 {
                    -winding
                } else {
                    winding
                };
                let pdf = self.pdf(x, point);
                (pdf > 0.0).then_some(PointOnLight {
                    point,
                    normal,
                    pdf,
                    radiance,
                })
            }
            Light::Sphere {
                center,
                radius,
                radiance,
            } => {
                sample_sphere_cone(center, radius, x, u).map(|(point, normal, pdf)| PointOnLight {
                    point,
                    normal,
                    pdf,
                    radiance,
                })
            }
            Light::Point {
                position,
                intensity,
            } => {
                let d2 = position.distance_squared(x);
                (d2 > 0.0).then(|| PointOnLight {
                    point: position,
                    normal: Vec3::ZERO,
                    pdf: 1.0,
                    radiance: intensity / d2,
                })
            }
            Light::Directional {
                direction,
                irradiance,
            } => Some(PointOnLight {
                point: x - DIRECTIONAL_DISTANCE * direction,
                normal: direction,
                pdf: 1.0,
                radiance: irradiance,
            }),
        }
    }

    /// Solid-angle density at `x` of [`Light::sample_point`] producing `point` (a point on this
    /// light); 0 where it cannot be produced and for delta lights.
    pub fn pdf(&self, x: Vec3, point: Vec3) -> f32 {
        match *self {
            Light::Quad { edge_u, edge_v, .. } => {
                let n = edge_u.cross(edge_v);
                area_to_solid_angle(x, point, n.normalize(), n.length(), false)
            }
            Light::Triangle {
                vertices: [v0, v1, v2],
                two_sided,
                ..
            } => {
                let n = (v1 - v0).cross(v2 - v0);
                area_to_solid_angle(x, point, n.normalize(), 0.5 * n.length(), two_sided)
            }
            Light::Sphere { center, radius, .. } => sphere_pdf(center, radius, x, point),
            Light::Point { .. } | Light::Directional { .. } => 0.0,
        }
    }
}

/// Uniform area density `1/area` converted to solid angle at `x`: `‖p − x‖² / (area · cos θ_l)`
/// with `cos θ_l = n · (x − p)/‖x − p‖`; 0 from behind, unless `two_sided` (then `|cos θ_l|`).
fn area_to_solid_angle(x: Vec3, p: Vec3, n: Vec3, area: f32, two_sided: bool) -> f32 {
    let to_x = x - p;
    let d2 = to_x.length_squared();
    let cos_facing = n.dot(to_x) / d2.sqrt();
    let cos_l = if two_sided {
        cos_facing.abs()
    } else {
        cos_facing
    };
    if cos_l > 0.0 && area > 0.0 && d2 > 0.0 {
        d2 / (area * cos_l)
    } else {
        0.0
    }
}

/// `1 − cos θ_max` of the cone subtended by a sphere with the given `sin²θ_max`, written as
/// `sin²θ_max / (1 + cos θ_max)` so that it does not cancel for small, distant spheres.
fn one_minus_cos_max(sin2_max: f32) -> f32 {
    sin2_max / (1.0 + (1.0 - sin2_max).max(0.0).sqrt())
}

/// Uniform sampling of the cone of directions that see the sphere from `x` (after pbrt-v4
/// `Sphere::Sample(ctx, u)`, with `1 − cos θ` carried exactly instead of pbrt's small-angle
/// branch, whose density deviates from the returned pdf by up to `sin²θ_max / 4`), returning the point on the visible cap, its outward normal and the
/// solid-angle pdf `1 / (2π (1 − cos θ_max))`. `None` from inside: an outward emitter sends
/// nothing there.
fn sample_sphere_cone(
    center: Vec3,
    radius: f32,
    x: Vec3,
    u: [f32; 2],
) -> Option<(Vec3, Vec3, f32)> {
    let to_center = center - x;
    let dc2 = to_center.length_squared();
    if dc2 <= radius * radius {
        return None;
    }
    let dc = dc2.sqrt();
    let sin2_max = radius * radius / dc2;
    let sin_max = sin2_max.sqrt();
    let one_minus_max = one_minus_cos_max(sin2_max);
    // θ uniform in cos over [cos θ_max, 1], through `a = 1 − cos θ` (exact for tiny cones):
    // sin²θ = a (2 − a).
    let a = u[0] * one_minus_max;
    let (sin2_theta, cos_theta) = (a * (2.0 - a), 1.0 - a);
    // Angle α at the centre between −to_center and the sampled point.
    let cos_alpha =
        sin2_theta / sin_max + cos_theta * (1.0 - sin2_theta / sin2_max).max(0.0).sqrt();
    let sin_alpha = (1.0 - cos_alpha * cos_alpha).max(0.0).sqrt();
    let phi = 2.0 * PI * u[1];
    let frame = Frame::from_normal(-to_center / dc);
    let normal = frame.to_world(Vec3::new(
        sin_alpha * phi.cos(),
        sin_alpha * phi.sin(),
        cos_alpha,
    ));
    let point = center + radius * normal;
    let pdf = 1.0 / (2.0 * PI * one_minus_max);
    pdf.is_finite().then_some((point, normal, pdf))
}

/// Density of [`sample_sphere_cone`] at `point` on the sphere: the cone pdf on the cap visible
/// from `x`, 0 on the hidden side and from inside.
fn sphere_pdf(center: Vec3, radius: f32, x: Vec3, point: Vec3) -> f32 {
    let dc2 = center.distance_squared(x);
    let normal = (point - center) / radius;
    if dc2 <= radius * radius || normal.dot(x - point) < 0.0 {
        return 0.0;
    }
    let pdf = 1.0 / (2.0 * PI * one_minus_cos_max(radius * radius / dc2));
    if pdf.is_finite() { pdf } else { 0.0 }
}

/// The scene's lights with power-proportional selection (a CDF searched by bisection; the
/// probabilities are the CDF's own differences, so selection frequencies and `pmf` agree).
#[derive(Clone, Debug, PartialEq)]
pub struct Lights {
    lights: Vec<Light>,
    cdf: Vec<f32>,
    pmf: Vec<f32>,
}

impl Lights {
    /// Lights selected by power ([`Light::power`] with `scene_radius` for directional lights).
    /// `None` when there are no lights or the total power is not positive and finite.
    pub fn new(lights: Vec<Light>, scene_radius: f32) -> Option<Lights> {
        let powers: Vec<f64> = lights
            .iter()
            .map(|l| l.power(scene_radius).max(0.0) as f64)
            .collect();
        let total: f64 = powers.iter().sum();
        if lights.is_empty() || !(total > 0.0 && total.is_finite()) {
            return None;
        }
        let mut running = 0.0f64;
        let mut cdf: Vec<f32> = powers
            .iter()
            .map(|p| {
                running += p;
                (running / total) as f32
            })
            .collect();
        *cdf.last_mut()? = 1.0;
        let pmf = (0..cdf.len())
            .map(|i| cdf[i] - if i == 0 { 0.0 } else { cdf[i - 1] })
            .collect();
        Some(Lights { lights, cdf, pmf })
    }

    pub fn len(&self) -> usize {
        self.lights.len()
    }

    pub fn is_empty(&self) -> bool {
        self.lights.is_empty()
    }

    pub fn get(&self, light: u32) -> &Light {
        &self.lights[light as usize]
    }

    pub fn iter(&self) -> impl Iterator<Item = &Light> {
        self.lights.iter()
    }

    /// Probability of selecting `light`.
    pub fn selection_pmf(&self, light: u32) -> f32 {
        self.pmf[light as usize]
    }

    /// The selection CDF (`cdf[i]` = probability of lights `0..=i`), for the GPU twin of
    /// `select`.
    pub fn selection_cdf(&self) -> &[f32] {
        &self.cdf
    }

    /// The light whose CDF interval `[cdf[i−1], cdf[i])` contains `u ∈ [0, 1)`.
    fn select(&self, u: f32) -> u32 {
        let i = self.cdf.partition_point(|&c| c <= u);
        i.min(self.lights.len() - 1) as u32
    }

    /// Picks a light with `u[0]` and a point on it with `u[1..]`, as seen from the shading point
    /// `x` (x2). `None` when the sampled point cannot emit toward `x`.
    pub fn sample(&self, x: Vec3, u: [f32; 3]) -> Option<LightSample> {
        let light = self.select(u[0]);
        let pmf = self.pmf[light as usize];
        let on = self.lights[light as usize].sample_point(x, [u[1], u[2]])?;
        let offset = on.point - x;
        let distance = offset.length();
        if !(distance > 0.0 && pmf > 0.0) {
            return None;
        }
        Some(LightSample {
            light,
            point: on.point,
            normal: on.normal,
            wi: offset / distance,
            distance,
            radiance: on.radiance,
            pdf: pmf * on.pdf,
            is_delta: self.lights[light as usize].is_delta(),
        })
    }

    /// Solid-angle density at `x` of [`Lights::sample`] returning `point` on `light`, selection
    /// included; 0 for delta lights.
    pub fn pdf(&self, x: Vec3, light: u32, point: Vec3) -> f32 {
        self.pmf[light as usize] * self.lights[light as usize].pdf(x, point)
    }

    /// `L_e` leaving `point` on `light` toward `toward` ([`Light::radiance`]).
    pub fn radiance(&self, light: u32, point: Vec3, toward: Vec3) -> Vec3 {
        self.lights[light as usize].radiance(point, toward)
    }
}

#[cfg(test)]
mod tests;
