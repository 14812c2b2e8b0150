//! Emissive meshes are lights that are geometry: path tracing a scene whose emitter is an
//! emissive quad object equals path tracing the same scene with a plain object there and the
//! equivalent `quad` light(s) of the scene file, within the noise.
//!
//! * Scenes: a translucent ball on a Lambert floor under a 1 × 1 panel facing down at y = 2, a
//!   second ball above the panel, 48 × 36 pixels, the camera below the panel's level so that it
//!   sees its lower face. **One-sided**: the panel's material emits `L_e` from its front (the
//!   lower face); the reference scene has a plain panel and one quad light facing down.
//!   **Two-sided**: the panel emits from both faces; the reference has two quad lights, one per
//!   face. The upper ball is lit only through the upper face.
//! * Rows: per scene, region (the translucent balls; the floor) and channel (r, g, b), the mean
//!   over the region's pixels of `pt` at [`SPP`] samples, one value per replica (seed `k`,
//!   reference seeds `1000 + k`). The panel's own pixels are left out: only the emitter scene's
//!   camera sees its emission (and nothing lights the panel), which
//!   `camera_rays_see_emission_on_emitting_sides` tests exactly.
//! * Test: per row, [`equivalence`] of the relative difference of the two scenes' means at
//!   confidence `1 − α/rows` (Bonferroni, α = 0.01), δ = 2%: every row must be equivalent.
//! * N: from a pilot of [`PILOT`] replicas per scene, the per-replica CV of every row (× 1.2), and
//!   the smallest N whose planned family power (Bonferroni over the rows, both sides sampled
//!   with N replicas) is ≥ 0.95; printed.
//! * Negative control near δ: the reference's light radiance × 1.03 (3%, 1.5 δ) must be found
//!   not equivalent (biased) in at least one row of each scene with the same N; planned power to
//!   reject it printed.

use std::path::Path;

use glam::{DVec3, Vec3};
use restir::stats::{Equivalence, EquivalencePlan, Summary, Verdict, equivalence};
use sss::integrator::PtSettings;
use sss::integrator::pt::render;
use sss::material::Material;
use sss::scene::{GBuffer, Scene};

/// Samples per pixel of one replica.
const SPP: u32 = 16;
/// Replicas of the pilot that measures the CVs.
const PILOT: usize = 64;
const DELTA: f64 = 0.02;
const ALPHA: f64 = 0.01;
const CV_MARGIN: f64 = 1.2;
const FAMILY_POWER: f64 = 0.95;
/// The near-δ control's factor on the reference's light radiance.
const CONTROL: f32 = 1.03;
const LE: f32 = 4.0;

/// The shared part of both scenes: camera, balls, floor; `{panel}` is the panel's material and
/// `{lights}` the reference's lights.
const SCENE: &str = r#"
[camera]
resolution = [48, 36]
vfov = 50.0
eye = [0.3, 1.1, 3.2]
target = [0.0, 1.4, 0.0]

[[materials]]
name = "wax"
type = "translucent"
albedo = [0.8, 0.6, 0.4]
mfp = [0.1, 0.05, 0.02]

[[materials]]
name = "floor"
type = "lambert"
albedo = [0.5, 0.5, 0.5]

[[materials]]
name = "panel"
type = "lambert"
albedo = [0.3, 0.3, 0.3]
{panel}

[[objects]]
name = "ball"
material = "wax"
shape = { type = "sphere", radius = 0.4, segments = 48, rings = 24 }
transform = { translate = [0.0, 0.4, 0.0] }

[[objects]]
name = "upper-ball"
material = "wax"
shape = { type = "sphere", radius = 0.3, segments = 48, rings = 24 }
transform = { translate = [0.0, 2.6, -0.2] }

[[objects]]
name = "floor"
material = "floor"
shape = { type = "quad", size = [6.0, 6.0] }

# The 1 × 1 panel at y = 2, its front (winding normal) facing down.
[[objects]]
name = "panel"
material = "panel"
shape = { type = "quad", size = [1.0, 1.0] }
transform = { translate = [0.0, 2.0, 0.0], rotate = [180.0, 0.0, 0.0] }

{lights}
"#;

/// The panel's corners as a quad light facing down, and facing up.
const DOWN: &str = "corner = [-0.5, 2.0, -0.5]\nedge_u = [1.0, 0.0, 0.0]\nedge_v = [0.0, 0.0, 1.0]";
const UP: &str = "corner = [-0.5, 2.0, -0.5]\nedge_u = [0.0, 0.0, 1.0]\nedge_v = [1.0, 0.0, 0.0]";

fn load(panel: &str, lights: &str) -> Scene {
    let text = SCENE.replace("{panel}", panel).replace("{lights}", lights);
    Scene::from_toml_str(&text, Path::new("emitters.toml")).expect("test scene")
}

/// The emitter scene (`two_sided` or not) and the reference scene with its radiance × `factor`.
fn pair(two_sided: bool, factor: f32) -> (Scene, Scene) {
    let emitter = load(
        &format!("emission = [{LE}, {LE}, {LE}]\ntwo_sided = {two_sided}"),
        "",
    );
    let le = LE * factor;
    let quad = |side: &str| {
        format!("[[lights]]\ntype = \"quad\"\n{side}\nradiance = [{le}, {le}, {le}]\n")
    };
    let lights = if two_sided {
        quad(DOWN) + &quad(UP)
    } else {
        quad(DOWN)
    };
    (emitter, load("", &lights))
}

/// The panel's object id.
const PANEL: u32 = 3;
/// Regions of the rows: the translucent balls, the floor.
const REGIONS: usize = 2;

/// Per region and channel, the mean over the region's pixels of `pt` at [`SPP`] with `seed`.
fn replica(scene: &Scene, gbuffer: &GBuffer, seed: u64) -> [[f64; 3]; REGIONS] {
    let image = render(scene, gbuffer, &PtSettings::default(), seed, 0, SPP);
    assert_eq!(image.nonfinite, 0);
    let (mut sums, mut counts) = ([DVec3::ZERO; REGIONS], [0usize; REGIONS]);
    for (value, g) in image.pixels.iter().zip(&gbuffer.pixels) {
        let Some(g) = g.filter(|g| g.object != PANEL) else {
            continue;
        };
        let r = match scene.material_of_object(g.object) {
            Material::Translucent(_) => 0,
            Material::Lambert(_) => 1,
        };
        sums[r] += *value;
        counts[r] += 1;
    }
    assert!(counts.iter().all(|&c| c > 20), "region pixels {counts:?}");
    std::array::from_fn(|r| (sums[r] / counts[r] as f64).to_array())
}

/// Every row's replica values: `rows[region * 3 + channel][k]`.
fn replicas(scene: &Scene, seeds: std::ops::Range<u64>) -> Vec<Vec<f64>> {
    let gbuffer = GBuffer::render(scene, 0);
    let per_seed: Vec<[[f64; 3]; REGIONS]> = seeds.map(|s| replica(scene, &gbuffer, s)).collect();
    (0..3 * REGIONS)
        .map(|row| per_seed.iter().map(|r| r[row / 3][row % 3]).collect())
        .collect()
}

fn cv(xs: &[f64]) -> f64 {
    let s = Summary::from_samples(xs);
    s.variance.sqrt() / s.mean.abs()
}

/// The smallest N with a planned probability ≥ [`FAMILY_POWER`] that all `rows` rows (CVs of
/// the emitter side and the reference side) are equivalent at `1 − α/rows` when nothing differs.
fn planned_n(cvs: &[(f64, f64)], rows: usize) -> usize {
    let alpha = ALPHA / rows as f64;
    (4..=8192)
        .find(|&n| {
            let misses: f64 = cvs
                .iter()
                .map(|&(a, b)| {
                    let plan = EquivalencePlan {
                        delta: DELTA,
                        alpha,
                        reference_rel_se: b / (n as f64).sqrt(),
                        reference_n: n,
                    };
                    1.0 - plan.equivalence_power(a, n, 0.0)
                })
                .sum();
            misses <= 1.0 - FAMILY_POWER
        })
        .expect("a feasible N")
}

fn rows(emitter: &[Vec<f64>], reference: &[Vec<f64>], rows: usize) -> Vec<Equivalence> {
    emitter
        .iter()
        .zip(reference)
        .map(|(e, r)| {
            equivalence(
                &Summary::from_samples(e),
                &Summary::from_samples(r),
                DELTA,
                1.0 - ALPHA / rows as f64,
            )
        })
        .collect()
}

#[test]
fn emissive_meshes_equal_quad_lights_with_their_objects() {
    let sides = [false, true];
    let total_rows = 3 * REGIONS * sides.len();
    for two_sided in sides {
        let (emitter, reference) = pair(two_sided, 1.0);
        assert_eq!(emitter.lights.len(), 2, "the panel's two triangles");
        assert_eq!(reference.lights.len(), if two_sided { 2 } else { 1 });
        let pilot_e = replicas(&emitter, 0..PILOT as u64);
        let pilot_r = replicas(&reference, 1000..1000 + PILOT as u64);
        let cvs: Vec<(f64, f64)> = pilot_e
            .iter()
            .zip(&pilot_r)
            .map(|(e, r)| (CV_MARGIN * cv(e), CV_MARGIN * cv(r)))
            .collect();
        eprintln!("two-sided {two_sided}: pilot CVs (emitter, reference) {cvs:.4?}");
        let n = planned_n(&cvs, total_rows);
        let worst = cvs.iter().map(|&(a, b)| a.max(b)).fold(0.0, f64::max);
        let e = replicas(&emitter, 0..n as u64);
        let r = replicas(&reference, 1000..1000 + n as u64);
        let (_, control_scene) = pair(two_sided, CONTROL);
        let control = replicas(&control_scene, 1000..1000 + n as u64);
        let test = rows(&e, &r, total_rows);
        let near = rows(&e, &control, total_rows);
        let plan = EquivalencePlan {
            delta: DELTA,
            alpha: ALPHA / total_rows as f64,
            reference_rel_se: worst / (n as f64).sqrt(),
            reference_n: n,
        };
        eprintln!(
            "two-sided {two_sided}: N = {n} (largest CV {worst:.4} with margin {CV_MARGIN}; \
             power to reject a 3% difference in one row at that CV ≥ {:.3})",
            plan.rejection_power(
                worst,
                n,
                1.0 / CONTROL as f64 - 1.0,
                ALPHA / total_rows as f64
            )
        );
        for (i, (t, c)) in test.iter().zip(&near).enumerate() {
            eprintln!(
                "  {} {}: {:+.3}% [{:+.3}%, {:+.3}%] {:?}; control {:+.3}% {:?}",
                ["translucent", "floor"][i / 3],
                ["red", "green", "blue"][i % 3],
                100.0 * t.relative_bias,
                100.0 * t.ci_low,
                100.0 * t.ci_high,
                t.verdict,
                100.0 * c.relative_bias,
                c.verdict
            );
        }
        assert!(
            test.iter().all(|t| t.verdict == Verdict::Equivalent),
            "two-sided {two_sided}: a row is not equivalent"
        );
        assert!(
            near.iter().any(|c| c.verdict == Verdict::Biased),
            "two-sided {two_sided}: the 3% control was not detected"
        );
    }
}

/// The camera sees an emitter's emission on its emitting sides only, and the quad light of the
/// reference scene is not seen at all: on the panel's pixels the one-sided emitter scene is
/// brighter than the reference by `L_e` in expectation, the two-sided one too (the camera faces
/// the front), and a panel seen from above emits only when two-sided.
#[test]
fn camera_rays_see_emission_on_emitting_sides() {
    for two_sided in [false, true] {
        let (mut emitter, _) = pair(two_sided, 1.0);
        let g = GBuffer::render(&emitter, 0);
        let panel: Vec<_> = g
            .pixels
            .iter()
            .flatten()
            .filter(|p| p.object == PANEL)
            .collect();
        assert!(!panel.is_empty());
        let Material::Lambert(lambert) = *emitter.material_of_object(PANEL) else {
            panic!("the panel is Lambert")
        };
        for p in &panel {
            let front = emitter.geometry.geometric_normal(p.prim).dot(p.view) > 0.0;
            assert!(front, "the camera below sees the lower (front) face");
            assert_eq!(lambert.emitted(front), Vec3::splat(LE));
        }
        // From above, looking down at the panel's back past the upper ball.
        emitter.camera = sss::scene::Camera::new(
            [16, 16],
            10.0,
            [Vec3::new(0.6, 4.0, 0.8); 2],
            [Vec3::new(0.3, 2.0, 0.3); 2],
            Vec3::Y,
            false,
        );
        let above = GBuffer::render(&emitter, 0);
        let image = render(&emitter, &above, &PtSettings::default(), 3, 0, 1);
        let centre = (8 * 16 + 8) as usize;
        let hit = above.pixels[centre].expect("the panel fills the centre");
        assert_eq!(hit.object, PANEL);
        let seen = image.pixels[centre];
        if two_sided {
            assert!(seen.min_element() >= LE as f64, "{seen}");
        } else {
            assert!(seen.max_element() < LE as f64, "{seen}");
        }
    }
}
