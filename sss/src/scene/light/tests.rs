use super::*;
use glam::{DVec3, vec3};
use restir::rng::{Stream, StreamKey};

/// Two-sided critical value of the standard normal at α = 1e-3.
const Z_CRIT: f64 = 3.2905;

fn stream(purpose: u32) -> Stream {
    StreamKey::new(0, 0, 0, purpose).stream(0x5CE_11E5)
}

/// Mean and standard error of `n` i.i.d. draws.
fn mean_se(n: usize, mut draw: impl FnMut() -> f64) -> (f64, f64) {
    let (mut sum, mut sum2) = (0.0, 0.0);
    for _ in 0..n {
        let v = draw();
        sum += v;
        sum2 += v * v;
    }
    let mean = sum / n as f64;
    let var = (sum2 / n as f64 - mean * mean).max(0.0) * n as f64 / (n as f64 - 1.0);
    (mean, (var / n as f64).sqrt())
}

fn quad() -> Light {
    Light::Quad {
        corner: vec3(-0.6, 1.5, -0.4),
        edge_u: vec3(1.0, 0.0, 0.3),
        edge_v: vec3(0.0, -0.2, 0.8),
        radiance: vec3(2.0, 1.5, 1.0),
    }
}

fn triangle() -> Light {
    Light::Triangle {
        vertices: [
            vec3(0.5, 1.2, -0.5),
            vec3(0.3, 1.1, 0.9),
            vec3(-0.7, 1.4, 0.2),
        ],
        radiance: vec3(1.0, 2.0, 3.0),
        two_sided: false,
    }
}

fn sphere(radius: f32) -> Light {
    Light::Sphere {
        center: vec3(0.4, 2.0, 0.3),
        radius,
        radiance: vec3(3.0, 2.0, 1.0),
    }
}

/// Shading point and a normal with every light fully above its horizon.
const X: Vec3 = Vec3::new(0.05, 0.0, 0.1);
fn normal() -> Vec3 {
    vec3(0.1, 1.0, -0.05).normalize()
}

/// The first point where the ray `x + t·w` meets the light (test-only intersection).
fn hit_light(light: &Light, x: Vec3, w64: DVec3) -> Option<Vec3> {
    let w = w64.as_vec3();
    match *light {
        Light::Quad {
            corner,
            edge_u,
            edge_v,
            ..
        } => {
            let n = edge_u.cross(edge_v);
            let t = n.dot(corner - x) / n.dot(w);
            let d = x + t * w - corner;
            let s = d.cross(edge_v).dot(n) / n.length_squared();
            let r = edge_u.cross(d).dot(n) / n.length_squared();
            (t > 0.0 && (0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&r)).then(|| x + t * w)
        }
        Light::Triangle {
            vertices: [v0, v1, v2],
            ..
        } => {
            let (e1, e2) = (v1 - v0, v2 - v0);
            let p = w.cross(e2);
            let det = e1.dot(p);
            let s = x - v0;
            let b1 = s.dot(p) / det;
            let q = s.cross(e1);
            let b2 = w.dot(q) / det;
            let t = e2.dot(q) / det;
            (t > 0.0 && b1 >= 0.0 && b2 >= 0.0 && b1 + b2 <= 1.0).then(|| x + t * w)
        }
        Light::Sphere { center, radius, .. } => {
            // In f64: in f32 the discriminant of a small, distant sphere cancels badly.
            let (oc, w) = ((x - center).as_dvec3(), w64);
            let b = oc.dot(w);
            let disc = b * b - (oc.length_squared() - (radius as f64).powi(2));
            let t = -b - disc.max(0.0).sqrt();
            (disc >= 0.0 && t > 0.0).then(|| (x.as_dvec3() + t * w).as_vec3())
        }
        Light::Point { .. } | Light::Directional { .. } => None,
    }
}

/// A cone around the direction from `x` to the light that contains all of it.
fn bounding_cone(light: &Light, x: Vec3) -> (Vec3, f32) {
    let points: Vec<Vec3> = match *light {
        Light::Quad {
            corner,
            edge_u,
            edge_v,
            ..
        } => {
            vec![
                corner,
                corner + edge_u,
                corner + edge_v,
                corner + edge_u + edge_v,
            ]
        }
        Light::Triangle { vertices, .. } => vertices.to_vec(),
        Light::Sphere { center, radius, .. } => {
            let axis = (center - x).normalize();
            return (axis, 1.01 * (radius / center.distance(x)).asin());
        }
        _ => unreachable!(),
    };
    let axis = points
        .iter()
        .map(|&p| (p - x).normalize())
        .sum::<Vec3>()
        .normalize();
    let angle = points
        .iter()
        .map(|&p| axis.angle_between(p - x))
        .fold(0.0, f32::max);
    (axis, 1.01 * angle)
}

/// `∫ pdf(x, ω) dω` over all directions, estimated with directions uniform in a cone that
/// contains the light: mean of `pdf(x, hit(ω)) / p_cone` (directions in f64, so that their
/// rounding does not move the boundary of a light only 0.02 rad wide).
fn integrate_pdf(light: &Light, pdf: impl Fn(Vec3) -> f32, n: usize, purpose: u32) -> (f64, f64) {
    let (axis, angle) = bounding_cone(light, X);
    let frame = Frame::from_normal(axis);
    let [t, b, n_axis] = [frame.t, frame.b, frame.n].map(|v| v.as_dvec3().normalize());
    let cos_c = (angle as f64).cos();
    let p_cone = 1.0 / (2.0 * std::f64::consts::PI * (1.0 - cos_c));
    let mut rng = stream(purpose);
    mean_se(n, || {
        let cos_t = 1.0 - rng.next_f64() * (1.0 - cos_c);
        let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
        let phi = std::f64::consts::TAU * rng.next_f64();
        let w = (sin_t * phi.cos() * t + sin_t * phi.sin() * b + cos_t * n_axis).normalize();
        hit_light(light, X, w).map_or(0.0, |p| pdf(p) as f64 / p_cone)
    })
}

/// Sampling ↔ pdf pairing: ∫ pdf dω = 1 for each area light (α = 1e-3 two-sided z-test per
/// light, N = 2^16 directions). Negative controls: the quad pdf without the cosine at the
/// light, and the cone pdf with `sin θ_max` in place of `1 − cos θ_max`, are rejected.
#[test]
fn pdf_integrates_to_one_over_directions() {
    let n = 1 << 16;
    let lights = [quad(), triangle(), sphere(0.8), sphere(0.04)];
    for (k, light) in lights.iter().enumerate() {
        let (mean, se) = integrate_pdf(light, |p| light.pdf(X, p), n, 10 + k as u32);
        let z = (mean - 1.0) / se;
        eprintln!("light {k}: ∫pdf dω = {mean:.5} ± {se:.5}, z = {z:.2} (N = {n}, α = 1e-3)");
        assert!(
            z.abs() < Z_CRIT,
            "light {k}: ∫pdf = {mean} ± {se}, z = {z}, α = 1e-3, N = {n}"
        );
    }
    let Light::Quad { edge_u, edge_v, .. } = quad() else {
        unreachable!()
    };
    let n_quad = edge_u.cross(edge_v).normalize();
    let no_cos = |p: Vec3| quad().pdf(X, p) * n_quad.dot((X - p).normalize());
    let (mean, se) = integrate_pdf(&quad(), no_cos, n, 20);
    eprintln!("negative control (no cos): {mean:.4} ± {se:.4}");
    assert!(
        ((mean - 1.0) / se).abs() > Z_CRIT,
        "negative control (no cos): {mean} ± {se}"
    );
    let wrong_cone = |p: Vec3| {
        let Light::Sphere { center, radius, .. } = sphere(0.8) else {
            unreachable!()
        };
        let pdf = sphere(0.8).pdf(X, p);
        let sin_max = radius / center.distance(X);
        pdf * 2.0 * PI * (1.0 - (1.0 - sin_max * sin_max).sqrt()) / (2.0 * PI * sin_max)
    };
    let (mean, se) = integrate_pdf(&sphere(0.8), wrong_cone, n, 21);
    eprintln!("negative control (wrong cone): {mean:.4} ± {se:.4}");
    assert!(
        ((mean - 1.0) / se).abs() > Z_CRIT,
        "negative control (wrong cone): {mean} ± {se}"
    );
}

/// Irradiance of a uniform polygon fully above the horizon (Lambert's formula):
/// `E = L/2 · |Σ_i γ_i n·(v_i × v_{i+1})/|v_i × v_{i+1}||`, `γ_i` the angle between the unit
/// vertex directions `v_i`, `v_{i+1}`.
fn polygon_irradiance(vertices: &[Vec3], x: Vec3, n: Vec3) -> f64 {
    let v: Vec<DVec3> = vertices
        .iter()
        .map(|&p| (p - x).as_dvec3().normalize())
        .collect();
    let sum: f64 = (0..v.len())
        .map(|i| {
            let (a, b) = (v[i], v[(i + 1) % v.len()]);
            a.angle_between(b) * n.as_dvec3().dot(a.cross(b).normalize())
        })
        .sum();
    0.5 * sum.abs()
}

/// Closed-form luminance irradiance at (X, normal) from one light.
fn irradiance(light: &Light) -> f64 {
    let n = normal();
    match *light {
        Light::Quad {
            corner,
            edge_u,
            edge_v,
            radiance,
        } => {
            let poly = [
                corner,
                corner + edge_u,
                corner + edge_u + edge_v,
                corner + edge_v,
            ];
            luminance(radiance) as f64 * polygon_irradiance(&poly, X, n)
        }
        Light::Triangle {
            vertices, radiance, ..
        } => luminance(radiance) as f64 * polygon_irradiance(&vertices, X, n),
        Light::Sphere {
            center,
            radius,
            radiance,
        } => {
            // π L sin²θ_max cos β for a sphere fully above the horizon.
            let to_c = (center - X).as_dvec3();
            let sin2 = (radius as f64).powi(2) / to_c.length_squared();
            std::f64::consts::PI
                * luminance(radiance) as f64
                * sin2
                * n.as_dvec3().dot(to_c.normalize())
        }
        Light::Point {
            position,
            intensity,
        } => {
            let d = (position - X).as_dvec3();
            luminance(intensity) as f64 * n.as_dvec3().dot(d.normalize()) / d.length_squared()
        }
        Light::Directional {
            direction,
            irradiance,
        } => luminance(irradiance) as f64 * n.as_dvec3().dot(-direction.as_dvec3()),
    }
}

fn all_lights() -> Lights {
    let lights = vec![
        quad(),
        triangle(),
        sphere(0.3),
        sphere(0.04),
        Light::Point {
            position: vec3(-0.5, 1.0, 0.5),
            intensity: vec3(0.3, 0.2, 0.4),
        },
        Light::Directional {
            direction: vec3(0.2, -1.0, 0.1).normalize(),
            irradiance: vec3(0.5, 0.5, 0.6),
        },
    ];
    Lights::new(lights, 2.0).unwrap()
}

/// `E[L_e · cos θ / pdf]` over [`Lights::sample`] against the sum of closed-form irradiances
/// of six lights of every kind (light selection by power included). α = 1e-3 two-sided z-test,
/// N = 2^18 samples. Negative control: the same estimator with uniform selection assumed
/// instead of the power pmf is rejected by the same test.
#[test]
fn irradiance_estimate_matches_closed_form() {
    let lights = all_lights();
    let expected: f64 = lights.iter().map(irradiance).sum();
    let n = 1 << 18;
    let estimate = |wrong_pmf: bool, purpose: u32| {
        let mut rng = stream(purpose);
        mean_se(n, || {
            let u = [rng.next_f32(), rng.next_f32(), rng.next_f32()];
            let Some(s) = lights.sample(X, u) else {
                return 0.0;
            };
            let mut pdf = s.pdf as f64;
            if wrong_pmf {
                pdf *= 1.0 / (lights.len() as f64 * lights.selection_pmf(s.light) as f64);
            }
            luminance(s.radiance) as f64 * normal().dot(s.wi).max(0.0) as f64 / pdf
        })
    };
    let (mean, se) = estimate(false, 30);
    let z = (mean - expected) / se;
    eprintln!("irradiance: {mean:.5} ± {se:.5} vs {expected:.5}, z = {z:.2} (N = {n}, α = 1e-3)");
    assert!(
        z.abs() < Z_CRIT,
        "E = {mean} ± {se} vs closed form {expected}: z = {z}, α = 1e-3, N = {n}"
    );
    let (wrong, se_w) = estimate(true, 31);
    let z_w = (wrong - expected) / se_w;
    eprintln!("negative control (uniform pmf): {wrong:.5} ± {se_w:.5}, z = {z_w:.1}");
    assert!(
        z_w.abs() > Z_CRIT,
        "negative control (uniform pmf): {wrong} ± {se_w}, z = {z_w}"
    );
}

/// Each sample's pdf equals `Lights::pdf` at its point, selection frequencies follow the pmf,
/// and `radiance()` agrees with the sample's radiance.
#[test]
fn sample_agrees_with_pdf_and_radiance() {
    let lights = all_lights();
    let mut rng = stream(40);
    let mut counts = vec![0u32; lights.len()];
    let n = 1 << 16;
    for _ in 0..n {
        let u = [rng.next_f32(), rng.next_f32(), rng.next_f32()];
        let s = lights.sample(X, u).expect("every light faces X");
        counts[s.light as usize] += 1;
        let again = lights.radiance(s.light, s.point, X);
        assert!(
            (again - s.radiance).abs().max_element() <= 1e-4 * s.radiance.max_element(),
            "{again} vs {s:?}"
        );
        assert!(
            (s.wi.length() - 1.0).abs() < 1e-5 && (X + s.distance * s.wi - s.point).length() < 1e-3
        );
        if s.is_delta {
            assert_eq!(lights.pdf(X, s.light, s.point), 0.0);
            assert_eq!(s.pdf, lights.selection_pmf(s.light));
        } else {
            let pdf = lights.pdf(X, s.light, s.point);
            assert!(
                (pdf - s.pdf).abs() <= 1e-3 * s.pdf,
                "pdf {pdf} vs sample {}",
                s.pdf
            );
        }
    }
    // Pearson chi-square of the selection counts, 5 degrees of freedom: critical value at
    // α = 1e-3 is 20.52.
    let chi2: f64 = counts
        .iter()
        .enumerate()
        .map(|(i, &c)| {
            let e = n as f64 * lights.selection_pmf(i as u32) as f64;
            (c as f64 - e).powi(2) / e
        })
        .sum();
    assert!(
        chi2 < 20.52,
        "selection χ² = {chi2} (5 dof, α = 1e-3), counts {counts:?}"
    );
    let uniform: f64 = counts
        .iter()
        .map(|&c| (c as f64 - n as f64 / 6.0).powi(2) / (n as f64 / 6.0))
        .sum();
    eprintln!("selection χ² = {chi2:.2} (5 dof, N = {n}); uniform-pmf control χ² = {uniform:.0}");
    assert!(
        uniform > 20.52,
        "negative control: counts must reject a uniform pmf, χ² = {uniform}"
    );
}

/// One-sided emitters send nothing backwards; the sampler and pdf agree on that.
#[test]
fn back_of_one_sided_emitters_is_dark_and_unsampled() {
    let behind = vec3(0.0, 3.0, 0.0);
    let lights = Lights::new(vec![quad(), triangle()], 1.0).unwrap();
    let mut rng = stream(50);
    for _ in 0..256 {
        let u = [rng.next_f32(), rng.next_f32(), rng.next_f32()];
        assert!(lights.sample(behind, u).is_none());
        let front = lights.sample(X, u).unwrap();
        assert_eq!(lights.pdf(behind, front.light, front.point), 0.0);
        assert_eq!(
            lights.radiance(front.light, front.point, behind),
            Vec3::ZERO
        );
    }
    let s = Lights::new(vec![sphere(0.3)], 1.0).unwrap();
    let Light::Sphere { center, .. } = sphere(0.3) else {
        unreachable!()
    };
    assert!(
        s.sample(center, [0.5; 3]).is_none(),
        "inside an outward emitter"
    );
    let far_side = center + 0.3 * (center - X).normalize();
    assert_eq!(s.pdf(X, 0, far_side), 0.0, "hidden side of the sphere");
    assert!(Lights::new(vec![], 1.0).is_none());
}
