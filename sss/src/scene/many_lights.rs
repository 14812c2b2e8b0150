//! The seeded many-light generator (`[many_lights]`): small sphere lights scattered uniformly in a
//! box, for the many-small-lights evaluation of paper 001 §6 (Fig. 7).

use std::f32::consts::PI;

use glam::Vec3;
use restir::rng::StreamKey;

use super::light::Light;
use crate::color::luminance;

/// `purpose` of the stream that places generated light `i` (`pixel = i`).
const MANY_LIGHTS_PURPOSE: u32 = 0x11A7_0001;

/// `count` sphere lights of radius `radius`, centres uniform in the box `[min, max]`, sharing
/// `total_power` (luminance watts) equally, with the chromaticity of `color`.
#[derive(Clone, Debug, PartialEq)]
pub struct ManyLights {
    pub count: u32,
    pub seed: u64,
    pub min: Vec3,
    pub max: Vec3,
    pub radius: f32,
    pub total_power: f32,
    pub color: Vec3,
}

impl ManyLights {
    /// The radiance of every light: power of a sphere light Φ = π · 4πr² · luminance(L).
    pub fn radiance(&self) -> Vec3 {
        let per_light = self.total_power / self.count as f32;
        self.color / luminance(self.color) * per_light / (4.0 * PI * PI * self.radius * self.radius)
    }

    /// The lights; light `i` depends only on `(seed, i)`. Inputs must be validated (positive
    /// radius, power and colour luminance).
    pub fn generate(&self) -> Vec<Light> {
        let radiance = self.radiance();
        (0..self.count)
            .map(|i| {
                let mut rng = StreamKey::new(i, 0, 0, MANY_LIGHTS_PURPOSE).stream(self.seed);
                let u = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
                Light::Sphere {
                    center: self.min + u * (self.max - self.min),
                    radius: self.radius,
                    radiance,
                }
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::vec3;

    fn spec(seed: u64) -> ManyLights {
        ManyLights {
            count: 512,
            seed,
            min: vec3(-2.0, 1.0, -2.0),
            max: vec3(2.0, 3.0, 1.0),
            radius: 0.02,
            total_power: 40.0,
            color: vec3(1.0, 0.8, 0.6),
        }
    }

    #[test]
    fn deterministic_inside_region_and_power_preserving() {
        let a = spec(7).generate();
        assert_eq!(a, spec(7).generate(), "same seed, same lights");
        let b = spec(8).generate();
        assert_eq!(b.len(), 512);
        assert!(
            a.iter().zip(&b).all(|(x, y)| x != y),
            "another seed moves every light"
        );
        let total: f64 = a.iter().map(|l| l.power(1.0) as f64).sum();
        assert!((total - 40.0).abs() < 40.0 * 1e-5, "total power {total}");
        for light in &a {
            let Light::Sphere { center, .. } = light else {
                panic!("sphere lights")
            };
            assert!(
                center.cmpge(spec(7).min).all() && center.cmple(spec(7).max).all(),
                "{center}"
            );
        }
        // Prefix stability: light i depends on (seed, i) only.
        let fewer = ManyLights {
            count: 10,
            ..spec(7)
        };
        let fewer_lights = fewer.generate();
        let Light::Sphere { center: c_few, .. } = fewer_lights[3] else {
            unreachable!()
        };
        let Light::Sphere { center: c_all, .. } = a[3] else {
            unreachable!()
        };
        assert_eq!(c_few, c_all);
    }
}
