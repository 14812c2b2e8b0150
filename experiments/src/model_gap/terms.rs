//! One sample of every quantity the random-walk / diffusion gap is decomposed into, at a
//! translucent primary hit x1, all lit at the exits by the scene's lights (`SceneLighting`):
//!
//! * the volumetric random walk by the number of volume collisions before its exit — 0 (the
//!   unscattered boundary term), 1, ≥ 2 (`sss::random_walk::{enter, walk, incident}`, exactly
//!   `estimate_exitant` with the exit binned by `Exit::scatter_count`);
//! * paper 000's hybrid estimator by part (`sss::integrator::single_scatter`): path-traced zero
//!   and single scattering, and the diffusion with the multiple-scattering-only profile
//!   `R − R1`;
//! * the diffusion with paper 000's single-scattering profile `R1 = (α/5.108) R̄_{ℓ/5.434}` on the
//!   *same* BSSRDF probe and light samples as `R − R1` (a copy of the stream), so
//!   `R1 + (R − R1)` is paper 000's full profile `R = A(α) R̄_{ℓ/s(A(α))}` sample by sample;
//! * the material's BSSRDF (`A R̄_{ℓ/s(A)}` with the material's own `A`, the path tracer `pt`).
//!
//! Each estimator draws from its own streams (purposes "MG" + n, its exits' light selection
//! included) of `(pixel, frame, sample)`, so the terms of one replica are independent of each
//! other and of every other replica.

use std::cell::RefCell;

use geometry::Hit;
use glam::Vec3;
use restir::rng::{Stream, StreamKey};
use sss::integrator::pt::{self, PtSettings};
use sss::integrator::single_scatter::{
    MultipleScattering, Shading, SingleScatterSettings, path_traced,
};
use sss::random_walk::{Medium, MeshBoundary, WalkEnd, WalkSettings, enter, incident, walk};
use sss::scene::{GPixel, Scene};

use engine::scene_lighting::SceneLighting;

/// The terms, in the order of [`Terms::values`].
pub const TERM_NAMES: [&str; 8] = [
    "walk 0",
    "walk 1",
    "walk ≥2",
    "path 0",
    "path 1",
    "R − R1",
    "R1",
    "BSSRDF",
];

/// Index of each term in [`Terms::values`].
pub const WALK_0: usize = 0;
pub const WALK_1: usize = 1;
pub const WALK_MULTIPLE: usize = 2;
pub const PATH_0: usize = 3;
pub const PATH_1: usize = 4;
pub const DIFFUSION_MULTIPLE: usize = 5;
pub const DIFFUSION_SINGLE: usize = 6;
pub const BSSRDF: usize = 7;

/// `purpose`s of the streams (ASCII "MG" + n).
const PURPOSE_WALK: u32 = 0x4D47_0001;
const PURPOSE_HYBRID: u32 = 0x4D47_0002;
const PURPOSE_BSSRDF: u32 = 0x4D47_0003;
const PURPOSE_WALK_LIGHT: u32 = 0x4D47_0004;
const PURPOSE_HYBRID_LIGHT: u32 = 0x4D47_0005;

/// One sample of every term (RGB), and whether a chain was cut (walk or internal reflections).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Terms {
    pub values: [Vec3; 8],
    pub truncated: bool,
}

fn key(pixel: u32, frame: u32, sample: u32, purpose: u32) -> StreamKey {
    StreamKey {
        pixel,
        frame,
        pass: sample,
        purpose,
    }
}

/// The scene's lights at the exits, with the light-selection stream of `key`.
fn lighting(scene: &Scene, key: StreamKey, seed: u64) -> SceneLighting<'_> {
    SceneLighting {
        scene,
        selection: RefCell::new(key.stream(seed)),
    }
}

/// Sample `sample` of every term at `x1` (pixel `pixel` of frame `frame`); `None` off
/// translucent objects. `media` = `Medium::of_scene(scene)`.
pub fn sample(
    scene: &Scene,
    media: &[Option<Medium>],
    x1: &GPixel,
    [pixel, frame, sample]: [u32; 3],
    seed: u64,
    hits: &mut Vec<Hit>,
) -> Option<Terms> {
    let Shading::Translucent {
        medium,
        multiple,
        x1: exit,
        n1,
        inward_winding,
    } = Shading::new(scene, media, x1)
    else {
        return None;
    };
    let boundary = MeshBoundary {
        geometry: &scene.geometry,
        object: x1.object,
        inward_winding,
    };
    let mut terms = Terms::default();

    let mut s = key(pixel, frame, sample, PURPOSE_WALK).stream(seed);
    let lights = lighting(scene, key(pixel, frame, sample, PURPOSE_WALK_LIGHT), seed);
    if let Some((dir, entry)) = enter(medium.interface(), n1, x1.view, &mut s) {
        match walk(
            &boundary,
            &medium,
            x1.position,
            dir,
            &WalkSettings::default(),
            &mut s,
        ) {
            WalkEnd::Exited(e) => {
                let light = incident(e.point, e.normal, e.direction, &lights, &mut s);
                terms.values[(e.scatter_count as usize).min(WALK_MULTIPLE)] =
                    entry * e.weight * light;
            }
            WalkEnd::Truncated => terms.truncated = true,
            WalkEnd::Terminated => {}
        }
    }

    let settings = SingleScatterSettings::default();
    let mut s = key(pixel, frame, sample, PURPOSE_HYBRID).stream(seed);
    let lights = lighting(scene, key(pixel, frame, sample, PURPOSE_HYBRID_LIGHT), seed);
    let orders = path_traced(
        &boundary,
        &medium,
        x1.position,
        n1,
        x1.view,
        &lights,
        &settings,
        &mut s,
    );
    terms.truncated |= orders.truncated;
    terms.values[PATH_0] = orders.zero;
    terms.values[PATH_1] = orders.single;
    let single_only = MultipleScattering {
        full_albedo: Vec3::ZERO,
        single_albedo: -multiple.single_albedo,
        ..multiple
    };
    let mut same = s.clone();
    terms.values[DIFFUSION_MULTIPLE] =
        diffusion(scene, &exit, &settings.diffusion, &multiple, &mut s, hits);
    terms.values[DIFFUSION_SINGLE] = diffusion(
        scene,
        &exit,
        &settings.diffusion,
        &single_only,
        &mut same,
        hits,
    );

    let mut s = key(pixel, frame, sample, PURPOSE_BSSRDF).stream(seed);
    let material = pt::Shading::new(scene, x1);
    terms.values[BSSRDF] = pt::estimate(scene, &material, &PtSettings::default(), &mut s, hits);
    Some(terms)
}

/// BSSRDF IS at x1 (whose profiles sample x2) of the profile `profile.profile_rgb` (signed).
fn diffusion(
    scene: &Scene,
    x1: &sss::bssrdf::ExitPoint,
    settings: &PtSettings,
    profile: &MultipleScattering,
    stream: &mut Stream,
    hits: &mut Vec<Hit>,
) -> Vec3 {
    pt::estimate_bssrdf(scene, x1, settings, stream, hits, |x2, wi, le| {
        profile.contribution(x1, x2, wi, le)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use sss::integrator::single_scatter::estimate;
    use sss::random_walk::estimate_exitant;
    use sss::scene::GBuffer;

    /// On `slab` (16 × 12, frame 15; thin, so every order is frequent), sample by sample with the same streams: the walk's
    /// orders sum to `estimate_exitant`, and path 0 + path 1 + (R − R1) is
    /// `single_scatter::estimate` (the terms are those estimators, split, not re-derived); one
    /// sample per pixel takes each order somewhere. Negative control: another sample index
    /// gives other walks.
    #[test]
    fn terms_split_the_estimators_they_name() {
        let mut scene = Scene::builtin("slab").unwrap();
        scene.camera = scene.camera.with_resolution(16, 12);
        let gbuffer = GBuffer::render(&scene, 15);
        let media = Medium::of_scene(&scene).unwrap();
        let (mut hits, mut seen, mut differs) = (Vec::new(), [false; 3], 0);
        for (pixel, g) in gbuffer.pixels.iter().enumerate() {
            let Some(g) = g else { continue };
            let pixel = pixel as u32;
            let light = |purpose| lighting(&scene, key(pixel, 15, 0, purpose), 3);
            let Some(t) = sample(&scene, &media, g, [pixel, 15, 0], 3, &mut hits) else {
                continue;
            };
            let Shading::Translucent {
                medium,
                n1,
                inward_winding,
                ..
            } = Shading::new(&scene, &media, g)
            else {
                unreachable!()
            };
            let boundary = MeshBoundary {
                geometry: &scene.geometry,
                object: g.object,
                inward_winding,
            };
            let mut s = key(pixel, 15, 0, PURPOSE_WALK).stream(3);
            let walk_light = light(PURPOSE_WALK_LIGHT);
            let l = estimate_exitant(
                &boundary,
                &medium,
                g.position,
                n1,
                g.view,
                &walk_light,
                &mut s,
            );
            assert_eq!(
                t.values[WALK_0] + t.values[WALK_1] + t.values[WALK_MULTIPLE],
                l
            );
            for order in 0..3 {
                seen[order] |= t.values[order] != Vec3::ZERO;
            }
            let mut s = key(pixel, 15, 0, PURPOSE_HYBRID).stream(3);
            let shading = Shading::new(&scene, &media, g);
            let settings = SingleScatterSettings::default();
            let hybrid_light = light(PURPOSE_HYBRID_LIGHT);
            let o = estimate(
                &scene,
                &shading,
                &settings,
                &hybrid_light,
                &mut s,
                &mut hits,
            );
            assert_eq!(
                (
                    t.values[PATH_0],
                    t.values[PATH_1],
                    t.values[DIFFUSION_MULTIPLE]
                ),
                (o.zero, o.single, o.multiple)
            );
            let other = sample(&scene, &media, g, [pixel, 15, 1], 3, &mut hits).unwrap();
            differs += (other.values[..3] != t.values[..3]) as u32;
        }
        assert_eq!(seen, [true; 3], "every order occurs");
        assert!(
            differs > 20,
            "control: another sample index, {differs} pixels differ"
        );
    }
}
