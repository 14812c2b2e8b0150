//! The benchmark's ray sets, all from explicit `StreamKey` streams: incoherent rays, shadow
//! segments toward a quad light, and chords from uniform surface points issued by a caller's
//! function (the benchmark's SSS probe chords, issued by `sss::bssrdf` exactly as the renderer
//! issues them).

use geometry::{Geometry, Ray};
use glam::{Vec2, Vec3, Vec3A};
use restir::rng::{Stream, StreamKey};

const SEED: u64 = 0x7A4E;

fn unit_vector(rng: &mut Stream) -> Vec3A {
    let z = 1.0 - 2.0 * rng.next_f32();
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = std::f32::consts::TAU * rng.next_f32();
    Vec3A::new(r * phi.cos(), r * phi.sin(), z)
}

/// Axis-aligned bounds of `object`'s triangles.
pub fn object_bounds(geometry: &Geometry, object: u32) -> (Vec3, Vec3) {
    (0..geometry.triangle_count())
        .filter(|&p| geometry.object_of(p) == object)
        .flat_map(|p| geometry.vertices(p))
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        })
}

/// Uniform points on `object`'s surface: `(triangle, barycentrics)`.
struct SurfaceSampler {
    prims: Vec<u32>,
    cdf: Vec<f64>,
}

impl SurfaceSampler {
    fn new(geometry: &Geometry, object: u32) -> SurfaceSampler {
        let prims: Vec<u32> = (0..geometry.triangle_count())
            .filter(|&p| geometry.object_of(p) == object)
            .collect();
        let mut total = 0.0;
        let cdf = prims
            .iter()
            .map(|&p| {
                total += geometry.triangle_area(p) as f64;
                total
            })
            .collect();
        SurfaceSampler { prims, cdf }
    }

    fn sample(&self, rng: &mut Stream) -> (u32, Vec2) {
        let target = rng.next_f32() as f64 * self.cdf.last().copied().unwrap_or(0.0);
        let i = self
            .cdf
            .partition_point(|&c| c <= target)
            .min(self.prims.len() - 1);
        let (a, b) = (rng.next_f32(), rng.next_f32());
        let bary = if a + b > 1.0 {
            Vec2::new(1.0 - a, 1.0 - b)
        } else {
            Vec2::new(a, b)
        };
        (self.prims[i], bary)
    }
}

/// Origins uniform in `object`'s bounds grown by 20%, directions uniform on the sphere, t ∈ (0, ∞).
pub fn incoherent(geometry: &Geometry, object: u32, count: usize) -> Vec<Ray> {
    let (lo, hi) = object_bounds(geometry, object);
    let (centre, half) = (0.5 * (lo + hi), 0.6 * (hi - lo));
    let mut rng = StreamKey::new(0, 0, 0, 1).stream(SEED);
    (0..count)
        .map(|_| {
            let u = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - 1.0;
            Ray::new(
                (centre + half * u).into(),
                unit_vector(&mut rng),
                0.0,
                f32::INFINITY,
            )
        })
        .collect()
}

/// Shadow segments from uniform points on `object` (offset by `epsilon` along the normal on the
/// light's side; the benchmark passes `sss::integrator::pt::SHADOW_EPSILON`) to uniform points on
/// a quad light one object size above it, as `sss::integrator::pt` issues them.
pub fn shadow(geometry: &Geometry, object: u32, count: usize, epsilon: f32) -> Vec<Ray> {
    let (lo, hi) = object_bounds(geometry, object);
    let size = (hi - lo).max_element();
    let sampler = SurfaceSampler::new(geometry, object);
    let mut rng = StreamKey::new(0, 0, 0, 2).stream(SEED);
    (0..count)
        .map(|_| {
            let (prim, bary) = sampler.sample(&mut rng);
            let x = geometry.position(prim, bary);
            let light = Vec3::new(
                lo.x + (hi.x - lo.x) * (2.0 * rng.next_f32() - 0.5),
                hi.y + size,
                lo.z + (hi.z - lo.z) * (2.0 * rng.next_f32() - 0.5),
            );
            let n = geometry.geometric_normal(prim);
            let side = if n.dot(light - x) < 0.0 { -1.0 } else { 1.0 };
            let from = x + side * epsilon * n;
            Ray::segment(from.into(), light.into())
        })
        .collect()
}

/// `count` chords from points uniform on `object`: `chord(prim, bary, rng)` issues the chord at
/// the point `(prim, bary)`, drawing its own random numbers from `rng`; `None` (an empty chord)
/// is redrawn.
pub fn chords(
    geometry: &Geometry,
    object: u32,
    count: usize,
    mut chord: impl FnMut(u32, Vec2, &mut Stream) -> Option<Ray>,
) -> Vec<Ray> {
    let sampler = SurfaceSampler::new(geometry, object);
    let mut rng = StreamKey::new(0, 0, 0, 3).stream(SEED);
    let mut rays = Vec::with_capacity(count);
    while rays.len() < count {
        let (prim, bary) = sampler.sample(&mut rng);
        rays.extend(chord(prim, bary, &mut rng));
    }
    rays
}
