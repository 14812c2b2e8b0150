//! Surface events at the medium's boundary: Fresnel reflectance of a smooth dielectric
//! ([`fresnel_dielectric`], shared with the BSSRDF in [`crate::material::fresnel`]),
//! refraction and reflection. Cosine-distributed (Lambertian) transmission directions are
//! drawn with [`crate::sampling::sample_cosine_hemisphere`].

use glam::Vec3;

pub use crate::material::fresnel::fresnel_dielectric;

/// Snell refraction of the propagation direction `dir` through a surface with unit normal `n`
/// facing the incident side (`dir · n < 0`), `eta = η_transmitted / η_incident`. `None` under
/// total internal reflection.
pub fn refract(dir: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let cos_i = -dir.dot(n);
    let sin2_t = (1.0 - cos_i * cos_i).max(0.0) / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some((dir / eta + (cos_i / eta - cos_t) * n).normalize())
}

/// Mirror reflection of the propagation direction `dir` about the unit normal `n`.
pub fn reflect(dir: Vec3, n: Vec3) -> Vec3 {
    dir - 2.0 * dir.dot(n) * n
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fresnel_limits_and_reciprocity() {
        let eta = 1.5f32;
        let normal = ((eta - 1.0) / (eta + 1.0)).powi(2);
        assert!((fresnel_dielectric(1.0, eta) - normal).abs() < 1e-6);
        assert!((fresnel_dielectric(1.0, 1.0 / eta) - normal).abs() < 1e-6);
        assert!(
            (fresnel_dielectric(0.0, eta) - 1.0).abs() < 1e-6,
            "grazing reflects"
        );
        assert_eq!(fresnel_dielectric(1.0, 1.0), 0.0);
        // Beyond the critical angle (sin θc = 1/1.5) from inside: total internal reflection.
        assert_eq!(fresnel_dielectric(0.7, 1.0 / eta), 1.0);
        // Reciprocity: F(θi, η) = F(θt, 1/η).
        let cos_i = 0.6f32;
        let cos_t = (1.0 - (1.0 - cos_i * cos_i) / (eta * eta)).sqrt();
        assert!(
            (fresnel_dielectric(cos_i, eta) - fresnel_dielectric(cos_t, 1.0 / eta)).abs() < 1e-6
        );
    }

    #[test]
    fn refraction_obeys_snell_and_reverses() {
        let n = Vec3::Z;
        let dir = Vec3::new(0.6, 0.0, -0.8);
        let eta = 1.33;
        let t = refract(dir, n, eta).unwrap();
        let sin_i = dir.cross(n).length();
        let sin_t = t.cross(n).length();
        assert!(
            (sin_i - eta * sin_t).abs() < 1e-6,
            "Snell: {sin_i} vs {}",
            eta * sin_t
        );
        assert!(t.z < 0.0);
        let back = refract(-t, -n, 1.0 / eta).unwrap();
        assert!((back + dir).length() < 1e-6);
        assert!(refract(Vec3::new(0.9, 0.0, 0.43589).normalize(), -n, 1.0 / 1.5).is_none());
        assert_eq!(reflect(dir, n), Vec3::new(0.6, 0.0, 0.8));
    }
}
