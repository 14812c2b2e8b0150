//! Warps from uniform random numbers to the distributions the estimators draw from, in the
//! spirit of pbrt-v4's `util/sampling.h`: each warp's sample, density and inverse side by side.
//! Shift mappings that reuse random numbers (`restir::Shift`) need the inverse; MIS and
//! unbiased contribution weights need the density.
//!
//! Densities are with respect to the measure named in each function (area or solid angle).
//! Inverses return the random numbers that the sampler maps to the given point, up to rounding.
//! Shape-specific samplers that need a scene's geometry (a sphere light's visible cap, a
//! profile's radius) stay with their shape or profile.

use std::f32::consts::{FRAC_1_PI, PI, TAU};

use glam::{Vec2, Vec3};

/// A point uniform in the disk of `radius` about the origin: `r = R√u₁`, `φ = 2πu₂` (polar map,
/// [pbrt-v4 `SampleUniformDiskPolar`]); its density is [`uniform_disk_pdf`].
pub fn sample_uniform_disk(radius: f32, u_radius: f32, u_angle: f32) -> Vec2 {
    let r = radius * u_radius.sqrt();
    let phi = TAU * u_angle;
    r * Vec2::new(phi.cos(), phi.sin())
}

/// Area density `1/(πR²)` of [`sample_uniform_disk`] inside the disk of `radius`.
pub fn uniform_disk_pdf(radius: f32) -> f32 {
    1.0 / (PI * radius * radius)
}

/// The random numbers `[u_radius, u_angle]` with `sample_uniform_disk(radius, ..) == p`.
pub fn invert_uniform_disk(radius: f32, p: Vec2) -> [f32; 2] {
    [
        (p.length_squared() / (radius * radius)).min(1.0),
        unit_angle(p.y.atan2(p.x)),
    ]
}

/// A cosine-distributed direction in the hemisphere around the unit vector `axis`
/// (Malley's method); its density is [`cosine_hemisphere_pdf`].
pub fn sample_cosine_hemisphere(axis: Vec3, u: [f32; 2]) -> Vec3 {
    let r = u[0].sqrt();
    let (sin_phi, cos_phi) = (TAU * u[1]).sin_cos();
    let z = (1.0 - u[0]).max(0.0).sqrt();
    let (t, b) = axis.any_orthonormal_pair();
    (r * cos_phi * t + r * sin_phi * b + z * axis).normalize()
}

/// Solid-angle density `max(0, cos θ)/π` of [`sample_cosine_hemisphere`] about `axis`.
pub fn cosine_hemisphere_pdf(axis: Vec3, dir: Vec3) -> f32 {
    axis.dot(dir).max(0.0) * FRAC_1_PI
}

/// The random numbers with `sample_cosine_hemisphere(axis, u) == dir` (up to rounding), for
/// `dir` in the hemisphere of `axis`.
pub fn invert_cosine_hemisphere(axis: Vec3, dir: Vec3) -> [f32; 2] {
    let (t, b) = axis.any_orthonormal_pair();
    let (x, y) = (dir.dot(t), dir.dot(b));
    [(x * x + y * y).min(1.0), unit_angle(y.atan2(x))]
}

/// Uniform barycentrics `[b0, b1, b2]` on a triangle: `b0 = 1 − √u₀`, `b1 = √u₀ (1 − u₁)`,
/// `b2 = √u₀ u₁` [pbrt-v3 §13.6.5 `UniformSampleTriangle`, with b1 and b2 swapped];
/// the point `b0 v0 + b1 v1 + b2 v2` has density [`uniform_triangle_pdf`].
pub fn sample_uniform_triangle(u: [f32; 2]) -> [f32; 3] {
    let su = u[0].sqrt();
    [1.0 - su, su * (1.0 - u[1]), su * u[1]]
}

/// Area density `1/A` of [`sample_uniform_triangle`] on the triangle `v0 v1 v2`.
pub fn uniform_triangle_pdf([v0, v1, v2]: [Vec3; 3]) -> f32 {
    1.0 / (0.5 * (v1 - v0).cross(v2 - v0).length())
}

/// The random numbers with `sample_uniform_triangle(u) == b`, for barycentrics `b` of a point in
/// the triangle: `u₀ = (1 − b0)²`, `u₁ = b2 / (b1 + b2)` (0 at the vertex `v0`).
pub fn invert_uniform_triangle([_, b1, b2]: [f32; 3]) -> [f32; 2] {
    let s = b1 + b2;
    [
        (s * s).clamp(0.0, 1.0),
        if s > 0.0 {
            (b2 / s).clamp(0.0, 1.0)
        } else {
            0.0
        },
    ]
}

/// A distance in `(0, d)` from the exponential of rate `sigma_t` truncated to `(0, d)`:
/// `t = −ln(1 − u(1 − e^{−σt d}))/σt` [000 slide 56] (`d = ∞`: the plain exponential); its
/// density is [`truncated_exponential_pdf`].
pub fn sample_truncated_exponential(sigma_t: f32, d: f32, u: f32) -> f32 {
    -(u * (-sigma_t * d).exp_m1()).ln_1p() / sigma_t
}

/// Density `σt e^{−σt t} / (1 − e^{−σt d})` of [`sample_truncated_exponential`] at `t ∈ (0, d)`.
pub fn truncated_exponential_pdf(sigma_t: f32, d: f32, t: f32) -> f32 {
    sigma_t * (-sigma_t * t).exp() / -(-sigma_t * d).exp_m1()
}

/// The random number with `sample_truncated_exponential(sigma_t, d, u) == t`: the truncated
/// CDF `(1 − e^{−σt t}) / (1 − e^{−σt d})`.
pub fn invert_truncated_exponential(sigma_t: f32, d: f32, t: f32) -> f32 {
    ((-sigma_t * t).exp_m1() / (-sigma_t * d).exp_m1()).clamp(0.0, 1.0)
}

/// An angle from `atan2` (in `[−π, π]`) as the random number `u ∈ [0, 1)` with `φ = 2πu`.
fn unit_angle(phi: f32) -> f32 {
    let u = phi / TAU;
    if u < 0.0 { u + 1.0 } else { u }
}

#[cfg(test)]
mod tests;
