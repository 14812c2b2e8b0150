//! Tests of the boundary term's domain, candidates and shift: the conformance kit
//! (`restir::check`) on pixels of the `slab` scene across pixels and frames, with a negative
//! control, the candidates' density against the one they report, and the refusal of
//! non-diffuse boundaries. The reuse's unbiasedness is tested on images in
//! `lab/tests/single_scatter_restir.rs`.

use glam::Vec3;
use restir::check::{MisCase, partition_of_unity};
use restir::check::{
    ShiftCase, finite_difference_jacobian, negative_control, reciprocal_jacobian, round_trip,
};
use restir::mis::{ConfidenceOnly, DefensivePairwise, Gbh};
use restir::rng::StreamKey;
use restir::shift::LocalCoords;

use super::*;
use sss::scene::Lights;

/// `slab` at 32 × 24 lit by its quad light alone (the local coordinates below parametrise it).
fn slab() -> Scene {
    let scene = Scene::builtin("slab").expect("built-in");
    let quad = scene
        .lights
        .iter()
        .find(|l| matches!(l, Light::Quad { .. }))
        .expect("slab has a quad light")
        .clone();
    Scene {
        camera: scene.camera.with_resolution(32, 24),
        lights: Lights::new(vec![quad], 1.0).expect("one light"),
        ..scene
    }
}

/// The quad of light 0: `(corner, edge_u, edge_v)`.
fn quad(scene: &Scene) -> (Vec3, Vec3, Vec3) {
    match *scene.lights.get(0) {
        Light::Quad {
            corner,
            edge_u,
            edge_v,
            ..
        } => (corner, edge_u, edge_v),
        _ => panic!("light 0 is not a quad"),
    }
}

/// `(z, φ)` of the world direction (`dω = dz dφ`) and `(s, t)` of the vertex on light 0's
/// quad (`dA ∝ ds dt`): identity maps keep both measures, so `J = 1` is `|det ∂T/∂x|` here.
impl LocalCoords for BoundaryDomain<'_> {
    fn dim(&self) -> usize {
        4
    }

    fn to_local(&self, x: &BoundarySample, out: &mut [f64]) {
        let (corner, u, v) = quad(self.scene);
        let r = x.point - corner;
        out[0] = x.dir.z as f64;
        out[1] = (x.dir.y as f64).atan2(x.dir.x as f64);
        out[2] = (r.dot(u) / u.length_squared()) as f64;
        out[3] = (r.dot(v) / v.length_squared()) as f64;
    }

    fn sample_at_local(&self, c: &[f64]) -> Option<BoundarySample> {
        let (corner, u, v) = quad(self.scene);
        let (z, phi) = (c[0], c[1]);
        let inside = |s: f64| (0.0..=1.0).contains(&s);
        if !(z.abs() <= 1.0 && inside(c[2]) && inside(c[3])) {
            return None;
        }
        let r = (1.0 - z * z).sqrt();
        let dir = Vec3::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32);
        (dir.dot(self.n1) < 0.0).then(|| BoundarySample {
            dir,
            light: 0,
            point: corner + c[2] as f32 * u + c[3] as f32 * v,
        })
    }
}

/// The domains of the slab's pixels at `frame` (row-major; `None` off the slab).
fn domains<'a>(scene: &'a Scene, media: &[Option<Medium>], frame: u32) -> Vec<BoundaryDomain<'a>> {
    let gbuffer = GBuffer::render(scene, frame);
    gbuffer
        .pixels
        .iter()
        .filter_map(|g| {
            g.as_ref()
                .and_then(|g| BoundaryDomain::new(scene, media, g))
        })
        .collect()
}

/// Checks 1–3 of `restir::check` on pairs of slab pixels (neighbours, far apart, across the
/// 16-frame trajectory), both directions, 200 candidates each: the round trip is exact, `J·J'`
/// = 1, and finite differences in `(z, φ, s, t)` give `|det| = 1` within 1e-3. Negative control:
/// `J × 1.03` fails the reciprocal and finite-difference checks.
#[test]
fn same_vertices_passes_the_shift_checks() {
    let scene = slab();
    let media = check_materials(&scene).unwrap();
    let first = domains(&scene, &media, 0);
    let last = domains(&scene, &media, 15);
    assert!(
        first.len() > 100 && last.len() > 100,
        "the slab fills the view"
    );
    let n = first.len().min(last.len());
    let pairs = vec![
        (&first[n / 2], &first[n / 2 + 1]),
        (&first[n / 3], &last[n / 3]),
        (&first[5], &last[n - 5]),
        (&first[n - 1], &last[0]),
    ];
    let case = ShiftCase {
        pairs,
        sampler: &Candidates,
        samples_per_pair: 200,
        seed: 11,
    };
    let reports = [
        round_trip(&SameVertices, &case, 0.0),
        reciprocal_jacobian(&SameVertices, &case, 1e-6),
        finite_difference_jacobian(&SameVertices, &case, 1e-3, 1e-3),
    ];
    for report in &reports {
        eprintln!("{report}");
        assert!(report.passed, "{report}");
        let tested = report.figure("tested").or(report.figure("shifted"));
        assert!(tested.is_some_and(|n| n >= 800.0), "{report}");
    }
    let broken = [
        reciprocal_jacobian(&ScaledJacobian(1.03), &case, 1e-6),
        finite_difference_jacobian(&ScaledJacobian(1.03), &case, 1e-3, 1e-3),
    ];
    let control = negative_control("J × 1.03", &broken);
    eprintln!("{control}");
    assert!(control.passed, "{control}");
    assert!(broken.iter().all(|r| !r.passed), "both checks catch it");
}

/// Check 4: GBH (temporal) and defensive pairwise (spatial) weights form a partition of unity
/// at the candidates of a receiver among a 3 × 3 block and the previous frame's pixel, within
/// 1e-5, over 2 000 candidates with confidences 1–20. Negative control: `1/M` (confidence only)
/// loses weight where a neighbour cannot produce the sample (the receiver sits on the slab's
/// edge, so some neighbours' chords leave through other faces or miss the light).
#[test]
fn mis_weights_partition_unity() {
    let scene = slab();
    let media = check_materials(&scene).unwrap();
    let gbuffer = GBuffer::render(&scene, 1);
    let at = |x: u32, y: u32| {
        gbuffer
            .get(x, y)
            .and_then(|g| BoundaryDomain::new(&scene, &media, g))
    };
    // The first slab pixel of the middle row: its left neighbours are off the slab or on a side.
    let row = gbuffer.height / 2;
    let column = (0..gbuffer.width)
        .find(|&x| at(x, row).is_some())
        .expect("the slab crosses the middle row");
    let receiver = at(column, row).unwrap();
    let mut others: Vec<BoundaryDomain> = (row - 1..=row + 1)
        .flat_map(|y| (column..=column + 2).map(move |x| (x, y)))
        .filter(|&(x, y)| (x, y) != (column, row))
        .filter_map(|(x, y)| at(x, y))
        .collect();
    others.extend(domains(&scene, &media, 0).into_iter().take(3));
    let confidences: Vec<f32> = (0..=others.len())
        .map(|j| 1.0 + (j * 7 % 20) as f32)
        .collect();
    let case = MisCase {
        receiver: &receiver,
        others: others.iter().collect(),
        confidences,
        sampler: &Candidates,
        samples: 2000,
        seed: 5,
    };
    for report in [
        partition_of_unity(&SameVertices, &Gbh, &case, 1e-5),
        partition_of_unity(&SameVertices, &DefensivePairwise, &case, 1e-5),
    ] {
        eprintln!("{report}");
        assert!(report.passed, "{report}");
    }
    let control = partition_of_unity(&SameVertices, &ConfidenceOnly, &case, 1e-5);
    eprintln!("control: {control}");
    assert!(!control.passed, "1/M must lose weight: {control}");
}

/// The candidates' density is the one they report, and `f/p` is finite: over 4 000 candidates
/// of 40 slab pixels, `pdf(x)` equals the drawn density bit for bit and every contribution is
/// finite; some candidates are lit on every light (the test sees light), and every direction
/// enters the surface. With the scene's quad and point light, and with a sphere, a triangle and
/// a directional light behind the slab (every kind of vertex).
#[test]
fn candidates_report_their_density() {
    let behind = vec![
        Light::Sphere {
            center: Vec3::new(0.0, 0.7, -1.0),
            radius: 0.2,
            radiance: Vec3::splat(20.0),
        },
        Light::Triangle {
            vertices: [
                Vec3::new(-0.5, 0.2, -0.8),
                Vec3::new(0.5, 0.2, -0.8),
                Vec3::new(0.0, 1.2, -0.8),
            ],
            radiance: Vec3::splat(10.0),
            two_sided: false,
        },
        Light::Directional {
            direction: Vec3::new(0.3, -0.2, 1.0).normalize(),
            irradiance: Vec3::splat(3.0),
        },
    ];
    let own = Scene::builtin("slab").unwrap().lights;
    for lights in [own, Lights::new(behind, 2.0).unwrap()] {
        let slab = Scene::builtin("slab").unwrap();
        let scene = Scene {
            camera: slab.camera.with_resolution(32, 24),
            lights,
            ..slab
        };
        let media = check_materials(&scene).unwrap();
        let all = domains(&scene, &media, 3);
        let mut lit = vec![0u32; scene.lights.len()];
        let mut drawn = 0;
        for (i, domain) in all.iter().step_by(all.len() / 40).enumerate() {
            let mut rng = StreamKey::new(i as u32, 0, 0, PURPOSE_BOUNDARY_CANDIDATES).stream(2);
            for _ in 0..100 {
                let Some((x, pdf)) = Candidates.sample(domain, &mut rng) else {
                    continue;
                };
                drawn += 1;
                assert_eq!(pdf, Candidates.pdf(domain, &x));
                let f = domain.contribution(&x);
                assert!(
                    f.is_finite() && (f / pdf).is_finite(),
                    "{x:?}: f = {f}, p = {pdf}"
                );
                assert!(x.dir.dot(domain.normal()) < 0.0);
                lit[x.light as usize] += (domain.target(&x) > 0.0) as u32;
            }
        }
        eprintln!("{drawn} candidates, lit per light {lit:?}");
        assert!(drawn > 2000 && lit.iter().all(|&n| n > 0), "{lit:?}");
    }
}

/// Dielectric and index-matched boundaries are refused in one line naming the material's
/// `boundary` and its value; diffuse ones are accepted.
#[test]
fn non_diffuse_boundaries_are_refused() {
    let mut scene = Scene::builtin("slab").unwrap();
    assert!(check_materials(&scene).is_ok());
    for (kind, value) in [
        (BoundaryKind::Dielectric, "\"dielectric\""),
        (BoundaryKind::IndexMatched, "\"index-matched\""),
    ] {
        let Material::Translucent(t) = &mut scene.materials[0] else {
            panic!("slab's first material is translucent");
        };
        t.boundary = kind;
        let error = check_materials(&scene).expect_err("refused");
        assert_eq!(
            (error.field.as_str(), error.value.as_str()),
            ("materials[0].boundary", value)
        );
        assert!(!error.to_string().contains('\n'));
    }
}
