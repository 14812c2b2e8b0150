//! Surface events at the medium's boundary: Fresnel reflectance of a smooth dielectric
//! ([`fresnel_dielectric`], shared with the BSSRDF in [`crate::material::fresnel`]),
//! refraction, and cosine-distributed (Lambertian) transmission directions.

use std::f32::consts::{FRAC_1_PI, TAU};

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

/// A cosine-distributed direction in the hemisphere around the unit vector `axis`
/// (Malley's method); its density is [`cosine_pdf`].
pub fn sample_cosine(axis: Vec3, u: [f32; 2]) -> Vec3 {
    let r = u[0].sqrt();
    let (sin_phi, cos_phi) = (TAU * u[1]).sin_cos();
    let z = (1.0 - u[0]).max(0.0).sqrt();
    let (t, b) = axis.any_orthonormal_pair();
    (r * cos_phi * t + r * sin_phi * b + z * axis).normalize()
}

/// Solid-angle density `max(0, cos θ)/π` of [`sample_cosine`] about `axis`.
pub fn cosine_pdf(axis: Vec3, dir: Vec3) -> f32 {
    axis.dot(dir).max(0.0) * FRAC_1_PI
}

/// The random numbers with `sample_cosine(axis, u) == dir` (up to rounding), for `dir` in the
/// hemisphere of `axis`.
pub fn invert_cosine(axis: Vec3, dir: Vec3) -> [f32; 2] {
    let (t, b) = axis.any_orthonormal_pair();
    let (x, y) = (dir.dot(t), dir.dot(b));
    let u_phi = y.atan2(x) / TAU;
    [
        (x * x + y * y).min(1.0),
        if u_phi < 0.0 { u_phi + 1.0 } else { u_phi },
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use restir::rng::StreamKey;
    use restir::stats::chi_square_gof;

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

    #[test]
    fn cosine_sampling_inverts() {
        let mut stream = StreamKey::new(0, 0, 0, 0xC05).stream(5);
        let axis = Vec3::new(0.0, -0.6, 0.8);
        for _ in 0..10_000 {
            let u = [stream.next_f32(), stream.next_f32()];
            let back = invert_cosine(axis, sample_cosine(axis, u));
            assert!((back[0] - u[0]).abs() < 1e-3, "{u:?} → {back:?}");
            let dphi = (back[1] - u[1]).abs();
            assert!(
                dphi.min(1.0 - dphi) < 1e-3 || u[0] < 1e-4,
                "{u:?} → {back:?}"
            );
        }
    }

    /// Chi-square p-value of `n` directions from `sample` binned in `cos θ` (20 equal bins)
    /// against the probabilities of [`cosine_pdf`], integrated numerically (Simpson, 2π ∫ pdf dμ).
    fn cosine_chi_square_p(sample: impl Fn(Vec3, [f32; 2]) -> Vec3, n: usize) -> f64 {
        const BINS: usize = 20;
        let axis = Vec3::new(0.0, -0.6, 0.8);
        let mut stream = StreamKey::new(0, 0, 0, 0xC06).stream(9);
        let mut observed = vec![0.0; BINS];
        for _ in 0..n {
            let mu = axis.dot(sample(axis, [stream.next_f32(), stream.next_f32()]));
            observed[((mu.clamp(0.0, 1.0) * BINS as f32) as usize).min(BINS - 1)] += 1.0;
        }
        let (t, _) = axis.any_orthonormal_pair();
        let density = |mu: f64| {
            let dir = (mu as f32) * axis + (1.0 - mu * mu).max(0.0).sqrt() as f32 * t;
            std::f64::consts::TAU * cosine_pdf(axis, dir) as f64
        };
        let expected: Vec<f64> = (0..BINS)
            .map(|k| {
                let (a, h) = (k as f64 / BINS as f64, 1.0 / (BINS * 100) as f64);
                let inner: f64 = (1..100)
                    .map(|i| density(a + i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 })
                    .sum();
                (density(a) + density(a + 100.0 * h) + inner) * h / 3.0
            })
            .collect();
        chi_square_gof(&observed, &expected, 5.0).p_value
    }

    /// Cosine sampling against its pdf: chi-square in cos θ, 20 bins, N = 100 000, α = 1e-3.
    /// Negative control: uniform-hemisphere directions (cos θ = 1 − u) against the same pdf.
    #[test]
    fn cosine_sampling_matches_its_pdf() {
        const N: usize = 100_000;
        const ALPHA: f64 = 1e-3;
        let p = cosine_chi_square_p(sample_cosine, N);
        eprintln!("cosine sampling: chi-square p = {p:.3}");
        assert!(
            p > ALPHA,
            "cosine sampling: chi-square p = {p:.2e} ≤ α = {ALPHA} (N = {N}, 20 bins)"
        );
        let uniform = |axis: Vec3, u: [f32; 2]| {
            let (t, b) = axis.any_orthonormal_pair();
            let z = 1.0 - u[0];
            let r = (1.0 - z * z).max(0.0).sqrt();
            let (sin_phi, cos_phi) = (TAU * u[1]).sin_cos();
            r * cos_phi * t + r * sin_phi * b + z * axis
        };
        let p = cosine_chi_square_p(uniform, N);
        assert!(
            p < ALPHA,
            "negative control (uniform hemisphere) not detected: p = {p:.2e}, α = {ALPHA}"
        );
    }
}
