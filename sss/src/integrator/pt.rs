//! The path-tracing baseline (DESIGN §4): camera ray → G-buffer hit x1 → BSSRDF IS → x2 → light
//! sample at x2 (NEE) → shadow ray x2→x3, estimate `f / (p_disk · p_light)` [001 §2.1, §3.1].
//! Lambert surfaces get direct lighting by NEE, and emitters add their emission where the camera
//! sees an emitting side.
//!
//! Hit policies (both unbiased, with the same 9-technique MIS `p_disk`):
//! * [`HitPolicy::All`] sums `f(x2_j) / (p_disk(x2_j) p_light)` over every hit of the probe
//!   [001 Eq. 10]. Given a technique, the hits of its chords cover each surface point once per
//!   crossing, so their expected sum is `∫ Σ_t P_t p_t(x) f(x)/p_disk(x) dA = ∫ f dA` (one-sample
//!   MIS with the balance heuristic).
//! * [`HitPolicy::UniformOne`] keeps one hit with probability `1/n` and divides by that, i.e.
//!   estimates `f / (p_disk/n · p_light)` [001 Eq. 9]. `p_disk/n` is *not* the density of the kept
//!   point (that is `Σ_t P_t p_t / n_t`, with the hit count of each technique's chord), but the
//!   estimator is still unbiased: given the probe, its expectation over the uniform pick is
//!   exactly the all-hits sum above.
//!
//! Options beside the hit policy, both off by default: the techniques may draw their radii with
//! Xie's `g(ξ)` instead of the exact inverse ([`RadiusSampling`]; `p_disk` then uses the density
//! of `g(U)`, so the estimator stays unbiased), and `f` may evaluate the dipole profile of the
//! material instead of Burley's ([`ProfileKind::Dipole`], the reference of the image-space method
//! of paper 002). BSSRDF IS keeps sampling Burley radii under the dipole profile: `p_disk > 0`
//! wherever the truncated dipole `f` is, so the estimate is unbiased for it.

use geometry::{Hit, Ray};
use glam::{DVec3, Vec3, Vec3A};
use rayon::prelude::*;
use restir::rng::{Stream, StreamKey};

use crate::bssrdf::{
    EntryPoint, ExitPoint, Probe, RadiusSampling, TechniqueSelection, contribution,
    contribution_dipole, p_disk_with, pick_hit,
};
use crate::material::{DipoleProfiles, Lambert, Material, Translucent};
use crate::profile::ProfileKind;
use crate::scene::{GBuffer, GPixel, Scene};

pub use crate::contract::pt::{PURPOSE_PT, SHADOW_EPSILON};

/// Which probe hits become entry points x2.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum HitPolicy {
    /// One hit picked uniformly, weighted by the hit count [001 Eq. 9].
    UniformOne,
    /// Every hit, each with its own light sample [001 Eq. 10].
    All,
}

/// Settings of the baseline estimator.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PtSettings {
    pub hits: HitPolicy,
    pub selection: TechniqueSelection,
    /// How the techniques draw their radii.
    pub radius: RadiusSampling,
    /// Which profile `f` evaluates.
    pub profile: ProfileKind,
}

impl Default for PtSettings {
    fn default() -> Self {
        PtSettings {
            hits: HitPolicy::All,
            selection: TechniqueSelection::default(),
            radius: RadiusSampling::Exact,
            profile: ProfileKind::Burley,
        }
    }
}

/// An integrator's per-pixel result, row-major from the top row: the mean of each pixel's
/// samples, accumulated in `f64`, and how many samples were left out of the means because they
/// were not finite. Statistics read it as it is; outputs convert it to the `f32` image they
/// write (`engine::Image`).
#[derive(Clone, Debug, PartialEq)]
pub struct SampleMeans {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<DVec3>,
    /// Samples whose estimate was NaN or infinite; they are counted and left out of the mean.
    pub nonfinite: u64,
}

/// The random stream of sample `sample` of pixel `pixel` in `frame`.
pub fn sample_stream(pixel: u32, frame: u32, sample: u32, seed: u64) -> Stream {
    StreamKey {
        pixel,
        frame,
        pass: sample,
        purpose: PURPOSE_PT,
    }
    .stream(seed)
}

/// What the estimator needs about one pixel's primary hit, prepared once for all its samples.
#[derive(Clone, Copy, Debug)]
pub enum Shading<'a> {
    Translucent {
        material: &'a Translucent,
        x1: ExitPoint,
        /// The material's dipoles when the settings evaluate [`ProfileKind::Dipole`].
        dipoles: Option<DipoleProfiles>,
    },
    Lambert {
        material: &'a Lambert,
        x1: GPixel,
    },
}

impl<'a> Shading<'a> {
    /// The pixel prepared for the default settings (Burley profile).
    pub fn new(scene: &'a Scene, x1: &GPixel) -> Shading<'a> {
        Shading::prepare(scene, x1, ProfileKind::Burley)
    }

    /// The pixel prepared for evaluating `profile` (the dipole is derived here, once per pixel).
    pub fn prepare(scene: &'a Scene, x1: &GPixel, profile: ProfileKind) -> Shading<'a> {
        match scene.material_of_object(x1.object) {
            Material::Translucent(material) => Shading::Translucent {
                material,
                x1: ExitPoint::new(
                    x1.position,
                    x1.geometric_normal,
                    x1.shading_normal,
                    x1.view,
                    x1.object,
                    material,
                ),
                dipoles: (profile == ProfileKind::Dipole).then(|| DipoleProfiles::new(material)),
            },
            Material::Lambert(material) => Shading::Lambert { material, x1: *x1 },
        }
    }
}

/// One `f32` estimate of the radiance leaving x1 toward the camera. Under
/// [`ProfileKind::Dipole`] a `shading` from [`Shading::new`] has no dipoles and they are derived
/// for every sample: prepare it with [`Shading::prepare`].
pub fn estimate(
    scene: &Scene,
    shading: &Shading,
    settings: &PtSettings,
    rng: &mut Stream,
    hits: &mut Vec<Hit>,
) -> Vec3 {
    match shading {
        Shading::Translucent {
            material,
            x1,
            dipoles,
        } => match settings.profile {
            ProfileKind::Burley => estimate_bssrdf(scene, x1, settings, rng, hits, |x2, wi, le| {
                contribution(material, x1, x2, wi, le)
            }),
            ProfileKind::Dipole => {
                let dipoles = dipoles.unwrap_or_else(|| DipoleProfiles::new(material));
                estimate_bssrdf(scene, x1, settings, rng, hits, |x2, wi, le| {
                    contribution_dipole(&dipoles, x1, x2, wi, le)
                })
            }
        },
        Shading::Lambert { material, x1 } => estimate_lambert(scene, material, x1, rng),
    }
}

/// One BSSRDF-IS estimate at x1 of `∫ f(x2, ωi) dA dωi` for the path contribution
/// `contribution(x2, ωi, L_e)` of a BSSRDF on x1's cached profiles (they sample x2 and give
/// `p_disk`, with radii from `settings.radius`): the material's [`contribution`], its dipole's
/// ([`contribution_dipole`]), or paper 000's multiple-scattering-only profile
/// ([`single_scatter`](super::single_scatter)). Unbiased for any `f` — of either sign — that
/// vanishes where `p_disk` does; NEE at x2, shadow-tested, per the hit policy (module doc).
pub fn estimate_bssrdf(
    scene: &Scene,
    x1: &ExitPoint,
    settings: &PtSettings,
    rng: &mut Stream,
    hits: &mut Vec<Hit>,
    contribution: impl Fn(&EntryPoint, Vec3, Vec3) -> Vec3,
) -> Vec3 {
    let probe = Probe::sample(
        &settings.selection,
        rng.next_f32(),
        rng.next_f32(),
        rng.next_f32(),
    );
    probe.trace_with(&scene.geometry, x1, settings.radius, hits);
    let entry = |hit: &Hit, rng: &mut Stream| -> Vec3 {
        let x2 = EntryPoint::from_hit(&scene.geometry, hit);
        let p = p_disk_with(
            x1,
            &settings.selection,
            settings.radius,
            x2.position,
            x2.geometric_normal,
        );
        let Some(light) = scene.lights.sample(
            x2.position,
            [rng.next_f32(), rng.next_f32(), rng.next_f32()],
        ) else {
            return Vec3::ZERO;
        };
        let f = contribution(&x2, light.wi, light.radiance);
        if !(p > 0.0 && light.pdf > 0.0) || f == Vec3::ZERO {
            return Vec3::ZERO;
        }
        if occluded(
            scene,
            x2.position,
            x2.geometric_normal,
            light.wi,
            light.distance,
        ) {
            return Vec3::ZERO;
        }
        f / (p * light.pdf)
    };
    match settings.hits {
        HitPolicy::All => hits.iter().map(|h| entry(h, rng)).sum(),
        HitPolicy::UniformOne => {
            let u_pick = rng.next_f32();
            match pick_hit(hits, None, u_pick) {
                Some((_, hit)) => entry(&hit, rng) * hits.len() as f32,
                None => Vec3::ZERO,
            }
        }
    }
}

/// The radiance leaving a Lambert surface toward the camera: what it emits toward a viewer on
/// the side of x1's winding normal that the camera sees, plus its direct lighting.
fn estimate_lambert(scene: &Scene, material: &Lambert, x1: &GPixel, rng: &mut Stream) -> Vec3 {
    let front = scene.geometry.geometric_normal(x1.prim).dot(x1.view) > 0.0;
    material.emitted(front) + direct_lambert(scene, material, x1, rng)
}

/// Direct lighting of a Lambert surface: `(albedo/π) L_e max(0, n·ωi) / p_light`, visibility tested.
fn direct_lambert(scene: &Scene, material: &Lambert, x1: &GPixel, rng: &mut Stream) -> Vec3 {
    let Some(light) = scene.lights.sample(
        x1.position,
        [rng.next_f32(), rng.next_f32(), rng.next_f32()],
    ) else {
        return Vec3::ZERO;
    };
    let cos = x1.shading_normal.dot(light.wi);
    if !(cos > 0.0 && x1.geometric_normal.dot(light.wi) > 0.0 && light.pdf > 0.0) {
        return Vec3::ZERO;
    }
    if occluded(
        scene,
        x1.position,
        x1.geometric_normal,
        light.wi,
        light.distance,
    ) {
        return Vec3::ZERO;
    }
    material.albedo * (std::f32::consts::FRAC_1_PI * cos / light.pdf) * light.radiance
}

/// Whether the segment from `x` (offset to the side of `normal` that `wi` leaves through) to the
/// light at `distance` along `wi` is blocked.
pub fn occluded(scene: &Scene, x: Vec3, normal: Vec3, wi: Vec3, distance: f32) -> bool {
    let side = if normal.dot(wi) >= 0.0 { 1.0 } else { -1.0 };
    let origin = x + normal * (side * SHADOW_EPSILON);
    let ray = Ray::new(
        Vec3A::from(origin),
        Vec3A::from(wi),
        0.0,
        distance - 2.0 * SHADOW_EPSILON,
    );
    scene.geometry.occluded(&ray)
}

/// The mean of samples `first_sample .. first_sample + spp` of every pixel of `gbuffer` (rayon over
/// rows; each sample has its own stream, so the result is bit-identical for any thread count).
/// Pixels without a primary hit are 0.
pub fn render(
    scene: &Scene,
    gbuffer: &GBuffer,
    settings: &PtSettings,
    seed: u64,
    first_sample: u32,
    spp: u32,
) -> SampleMeans {
    render_pixels(
        gbuffer,
        first_sample..first_sample + spp,
        |_, x1| Shading::prepare(scene, x1, settings.profile),
        |shading, pixel, sample, hits| {
            let mut rng = sample_stream(pixel, gbuffer.frame, sample, seed);
            estimate(scene, shading, settings, &mut rng, hits)
        },
    )
}

/// The mean over `samples` of `sample(state, pixel, sample, hits)` for every pixel of `gbuffer`
/// with a primary hit, `state = prepare(pixel, x1)` once per pixel (rayon over rows; a sample
/// that is a function of its arguments gives the same bits for any thread count). Non-finite
/// samples count as 0 in the mean and are counted in [`SampleMeans::nonfinite`]; pixels
/// without a hit are 0.
pub fn render_pixels<S>(
    gbuffer: &GBuffer,
    samples: std::ops::Range<u32>,
    prepare: impl Fn(u32, &GPixel) -> S + Sync,
    sample: impl Fn(&S, u32, u32, &mut Vec<Hit>) -> Vec3 + Sync,
) -> SampleMeans {
    let width = gbuffer.width as usize;
    let spp = samples.len();
    let mut pixels = vec![DVec3::ZERO; gbuffer.pixels.len()];
    let nonfinite: u64 = pixels
        .par_chunks_mut(width.max(1))
        .zip(gbuffer.pixels.par_chunks(width.max(1)))
        .enumerate()
        .map(|(py, (out, row))| {
            let mut hits = Vec::new();
            let mut nonfinite = 0;
            for (px, (out, x1)) in out.iter_mut().zip(row).enumerate() {
                let Some(x1) = x1 else { continue };
                let pixel = (py * width + px) as u32;
                let state = prepare(pixel, x1);
                let mut sum = DVec3::ZERO;
                for index in samples.clone() {
                    let value = sample(&state, pixel, index, &mut hits);
                    if value.is_finite() {
                        sum += value.as_dvec3();
                    } else {
                        nonfinite += 1;
                    }
                }
                *out = if spp > 0 {
                    sum / spp as f64
                } else {
                    DVec3::ZERO
                };
            }
            nonfinite
        })
        .sum();
    SampleMeans {
        width: gbuffer.width,
        height: gbuffer.height,
        pixels,
        nonfinite,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The same frame with 1 and 2 rayon threads is bit-identical, for both hit policies, and no
    /// sample is NaN or infinite.
    #[test]
    fn frames_are_bit_identical_for_any_thread_count() {
        let mut scene = Scene::builtin("bumpy").expect("built-in scene");
        scene.camera = scene.camera.with_resolution(48, 36);
        let gbuffer = GBuffer::render(&scene, 0);
        for hits in [HitPolicy::All, HitPolicy::UniformOne] {
            let settings = PtSettings {
                hits,
                ..PtSettings::default()
            };
            let with = |threads: usize| {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                pool.install(|| render(&scene, &gbuffer, &settings, 5, 0, 2))
            };
            let (one, two) = (with(1), with(2));
            assert_eq!(one, two, "{hits:?}: 1 vs 2 threads differ");
            assert_eq!(one.nonfinite, 0, "{hits:?}: NaN/inf samples");
            assert!(
                one.pixels.iter().any(|p| p.max_element() > 0.0),
                "{hits:?}: black frame"
            );
            let other_seed = render(&scene, &gbuffer, &settings, 6, 0, 2);
            assert_ne!(one, other_seed, "{hits:?}: the seed has no effect");
        }
    }
}
