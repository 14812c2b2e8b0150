//! Paper 000's hybrid estimator [000 "Combined Approach"]: at a translucent primary hit x1, the
//! zero-scattering (boundary) term and single scattering are path traced, and only the rest goes
//! through diffusion, with the multiple-scattering-only profile `R − R1`. A sibling of [`pt`]:
//! one estimate per pixel sample from the G-buffer, every number from an explicit stream.
//! GLSL twin: `sss/glsl/single_scatter.glsl`.
//!
//! **Medium and boundary.** The material's medium by paper 000's colour mapping
//! ([`Medium::from_translucent`]: `fit = "dmfp"` is an input error) and its `boundary`
//! (diffuse by default: Lambertian transmission at entry and exit, next-event estimation at the
//! exit as in the talk [000 slides 57–60]; a smooth dielectric or index-matched boundary too).
//! The path enters against `ωo` as the random walk does ([`enter`]), and every boundary event
//! is the walk's ([`cross`], [`incident`]); the object's own mesh is the boundary.
//!
//! **Zero and single scattering** [000 slides 49–68]. Along each unscattered chord of length `d`
//! (the entry chord, and for a dielectric each chord after an internal reflection):
//! - single scattering: a distance `t ∈ (0, d)` from the truncated exponential of channel `c`,
//!   `t = −ln(1 − ξ(1 − e^{−σt,c d}))/σt,c` [000 slide 56], with `c` drawn with probability
//!   `P_c`; the estimate is `σs e^{−σt t} / p(t) · (phase value / phase pdf) · L_esc` per channel,
//!   with the one-sample MIS density `p(t) = Σ_c P_c σt,c e^{−σt,c t}/(1 − e^{−σt,c d})` (the
//!   talk's chromatic pdf [000 "RGB variation in σt"]) and `L_esc` the light arriving through the
//!   boundary along the Henyey–Greenstein-sampled direction, attenuated by the exact
//!   `e^{−σt d₁}` of its chords [000 slide 68, "use exact d1"];
//! - zero scattering: at the chord's end the path carries `e^{−σt d}` to the boundary event; it
//!   leaves (the boundary term `e^{−σt d0} f0 L0` [000 slide 60]) or is reflected and goes on.
//!
//! On a half-space the entry chord may never end (`d = ∞`): the distance pdf is then the plain
//! exponential, and there is no boundary term. Internal reflections (dielectric only) pass a
//! Russian roulette on the carried weight; chains longer than [`SingleScatterSettings::
//! max_segments`] are cut and reported ([`Orders::truncated`]).
//!
//! **Channel selection.** `P_c ∝ σs,c = σt,c α_c` ([`ChannelSelection::Scattering`], the talk's
//! channel CDF) or `1/3` ([`ChannelSelection::Uniform`]); both are unbiased (one-sample MIS).
//!
//! **Multiple scattering: the signed estimator of `R − R1`.** Per channel, `Rn = R − R1` of
//! [`ScatteringOrders`] (`α = σs/σt`, `ℓ = 1/σt`, paper 000's searchlight `R(α)`). x2 is drawn by
//! BSSRDF importance sampling on the *full* profile `R̄_{ℓ/s(A(α))}` ([`pt::estimate_bssrdf`],
//! NEE at x2), and each hit contributes `f/p` with `f = Rn(r)/π · F_t F_t · cos · L_e` evaluated
//! with its sign. `Rn < 0` near `r = 0` once `α ≳ 0.29`; the estimator stays unbiased because
//! `p_disk > 0` wherever `Rn ≠ 0` inside the truncation radius `r_max` of the full profile (the
//! single profile, `d1 = ℓ/5.434 ≤ ℓ/s(A)`, is narrower), and its weights are bounded: both
//! profiles behave as `1/r` at 0 (ratio `d_full/d1`) and `R̄_1` decays faster. Single samples,
//! and the expectation itself where the light is concentrated within about one mean free path
//! of x1, can be negative: they are kept as they are (non-finite samples are counted).

use std::sync::atomic::{AtomicU64, Ordering};

use geometry::Hit;
use glam::Vec3;
use restir::rng::{Stream, StreamKey};

use super::pt::{self, PtSettings, SampleMeans};
use crate::InputError;
use crate::bssrdf::{EntryPoint, ExitPoint, bssrdf_of_profile};
use crate::material::{FresnelTransmission, Material};
use crate::profile::{Burley, ScatteringOrders};
use crate::random_walk::{
    Boundary, Crossing, ExitLighting, Medium, MeshBoundary, PhaseFunction, cross, enter, incident,
    roulette,
};
use crate::sampling::sample_truncated_exponential;
use crate::scene::{GBuffer, GPixel, Scene};

pub use crate::contract::single_scatter::{
    ChannelSelection, DEFAULT_MAX_SEGMENTS, PURPOSE_SINGLE_SCATTER,
};

impl ChannelSelection {
    /// `P_c` for a medium with scattering coefficients `sigma_s`.
    pub fn probabilities(self, sigma_s: Vec3) -> Vec3 {
        let sum = sigma_s.x + sigma_s.y + sigma_s.z;
        match self {
            ChannelSelection::Scattering if sum > 0.0 && sum.is_finite() => sigma_s / sum,
            _ => Vec3::splat(1.0 / 3.0),
        }
    }
}

/// Knobs of the estimator.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SingleScatterSettings {
    pub channel: ChannelSelection,
    /// BSSRDF IS of the multiple-scattering part (hit policy, techniques).
    pub diffusion: PtSettings,
    /// Unscattered chords per chain (dielectric internal reflections) before it is cut off.
    pub max_segments: u32,
}

impl Default for SingleScatterSettings {
    fn default() -> Self {
        SingleScatterSettings {
            channel: ChannelSelection::Scattering,
            diffusion: PtSettings::default(),
            max_segments: DEFAULT_MAX_SEGMENTS,
        }
    }
}

/// One estimate, split by scattering order.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Orders {
    /// Unscattered light (the boundary term).
    pub zero: Vec3,
    /// Path-traced single scattering.
    pub single: Vec3,
    /// Diffusion with `R − R1` (signed).
    pub multiple: Vec3,
    /// A chain of internal reflections was cut at `max_segments` (a bias to count).
    pub truncated: bool,
}

impl Orders {
    pub fn total(&self) -> Vec3 {
        self.zero + self.single + self.multiple
    }
}

/// The channel whose cumulative interval of `probabilities` contains `u ∈ [0, 1)`; channels of
/// probability 0 are never returned.
pub fn pick_channel(probabilities: Vec3, u: f32) -> usize {
    let mut cumulative = 0.0;
    let mut last = 0;
    for c in 0..3 {
        if probabilities[c] <= 0.0 {
            continue;
        }
        cumulative += probabilities[c];
        last = c;
        if u < cumulative {
            return c;
        }
    }
    last
}

/// The density of a distance drawn by [`sample_truncated_exponential`] (extinction `σt,c`,
/// truncated to the chord `d`) after picking the channel with `probabilities`: the mixture
/// `Σ_c P_c σt,c e^{−σt,c t} / (1 − e^{−σt,c d})` of
/// [`crate::sampling::truncated_exponential_pdf`], written out with `P_c σt,c` multiplied
/// first (the order its GLSL twin keeps).
pub fn distance_pdf(sigma_t: Vec3, probabilities: Vec3, d: f32, t: f32) -> f32 {
    (0..3)
        .filter(|&c| probabilities[c] > 0.0)
        .map(|c| {
            probabilities[c] * sigma_t[c] * (-sigma_t[c] * t).exp() / -(-sigma_t[c] * d).exp_m1()
        })
        .sum()
}

/// Follows the unscattered path from `pos` along `dir` (weight `beta`) through internal
/// reflections until it leaves, and returns `beta`-weighted light arriving through its exit,
/// attenuated by `e^{−σt d}` per chord; `chord(pos, dir, d, beta, stream)` sees every chord
/// first (`d = ∞` where the boundary is not reached). `None` when cut at `max_segments`.
#[allow(clippy::too_many_arguments)]
fn unscattered<B: Boundary + ?Sized, P: PhaseFunction, L: ExitLighting>(
    boundary: &B,
    medium: &Medium<P>,
    mut pos: Vec3,
    mut dir: Vec3,
    mut beta: Vec3,
    lighting: &L,
    max_segments: u32,
    stream: &mut Stream,
    mut chord: impl FnMut(Vec3, Vec3, f32, Vec3, &mut Stream),
) -> Option<Vec3> {
    for _ in 0..max_segments {
        let hit = boundary.intersect(pos, dir, f32::INFINITY);
        chord(pos, dir, hit.map_or(f32::INFINITY, |h| h.t), beta, stream);
        let Some(hit) = hit else {
            return Some(Vec3::ZERO);
        };
        beta *= (-medium.sigma_t() * hit.t).exp();
        pos += hit.t * dir;
        match cross(medium.interface(), dir, hit.normal, stream) {
            Crossing::Leaves(direction) => {
                return Some(beta * incident(pos, hit.normal, direction, lighting, stream));
            }
            Crossing::Reflected(reflected) => {
                dir = reflected;
                match roulette(beta, stream.next_f32()) {
                    Some(b) => beta = b,
                    None => return Some(Vec3::ZERO),
                }
            }
        }
    }
    None
}

/// Single scattering from one chord `pos + t·dir`, `t ∈ (0, d)` (module doc): the channel, the
/// distance and the phase direction, then the unscattered escape. `None` when the escape was cut.
#[allow(clippy::too_many_arguments)]
fn scatter_on_chord<B: Boundary + ?Sized, P: PhaseFunction, L: ExitLighting>(
    boundary: &B,
    medium: &Medium<P>,
    probabilities: Vec3,
    pos: Vec3,
    dir: Vec3,
    d: f32,
    lighting: &L,
    max_segments: u32,
    stream: &mut Stream,
) -> Option<Vec3> {
    let channel = pick_channel(probabilities, stream.next_f32());
    let sigma_t = medium.sigma_t();
    let t = sample_truncated_exponential(sigma_t[channel], d, stream.next_f32());
    let pdf = distance_pdf(sigma_t, probabilities, d, t);
    let scattered = medium
        .phase()
        .sample(dir, [stream.next_f32(), stream.next_f32()]);
    if !(d > 0.0 && pdf > 0.0 && scattered.pdf > 0.0) {
        return Some(Vec3::ZERO);
    }
    // [000 slide 68]: σs e^{−σt t} / p(t), the phase weight, then the exact escape.
    let weight = medium.sigma_s() * (-sigma_t * t).exp() * (scattered.value / scattered.pdf) / pdf;
    unscattered(
        boundary,
        medium,
        pos + t * dir,
        scattered.dir,
        weight,
        lighting,
        max_segments,
        stream,
        |_, _, _, _, _| {},
    )
}

/// Zero- and single-scattering estimate of the radiance leaving `x1` (on `boundary`, unit
/// outward normal `n1`) toward `wo` (module doc); `multiple` is 0.
#[allow(clippy::too_many_arguments)]
pub fn path_traced<B: Boundary + ?Sized, P: PhaseFunction, L: ExitLighting>(
    boundary: &B,
    medium: &Medium<P>,
    x1: Vec3,
    n1: Vec3,
    wo: Vec3,
    lighting: &L,
    settings: &SingleScatterSettings,
    stream: &mut Stream,
) -> Orders {
    let mut orders = Orders::default();
    let Some((dir, entry)) = enter(medium.interface(), n1, wo, stream) else {
        return orders;
    };
    let probabilities = settings.channel.probabilities(medium.sigma_s());
    let mut single = Vec3::ZERO;
    let mut truncated = false;
    let zero = unscattered(
        boundary,
        medium,
        x1,
        dir,
        Vec3::splat(entry),
        lighting,
        settings.max_segments,
        stream,
        |pos, dir, d, beta, stream| {
            let scattered = scatter_on_chord(
                boundary,
                medium,
                probabilities,
                pos,
                dir,
                d,
                lighting,
                settings.max_segments,
                stream,
            );
            match scattered {
                Some(light) => single += beta * light,
                None => truncated = true,
            }
        },
    );
    orders.zero = zero.unwrap_or(Vec3::ZERO);
    orders.single = single;
    orders.truncated = truncated || zero.is_none();
    orders
}

/// Paper 000's multiple-scattering-only profile `Rn = R − R1` per channel, with the quantities
/// derived once: the full profile's albedo `A(α)` and Burley profile (which samples x2), and the
/// single-scattering albedo `α/5.108` and profile.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MultipleScattering {
    pub full_albedo: Vec3,
    pub full: [Burley; 3],
    pub single_albedo: Vec3,
    pub single: [Burley; 3],
}

impl MultipleScattering {
    /// The profiles of `medium`: `α = σs/σt` and `ℓ = 1/σt` per channel.
    pub fn new<P: PhaseFunction>(medium: &Medium<P>) -> MultipleScattering {
        let (albedo, sigma_t) = (medium.albedo(), medium.sigma_t());
        let orders: [ScatteringOrders; 3] = std::array::from_fn(|c| ScatteringOrders {
            alpha: albedo[c],
            mfp: 1.0 / sigma_t[c],
        });
        MultipleScattering {
            full_albedo: Vec3::from_array(orders.map(|o| o.full().0)),
            full: orders.map(|o| o.full().1),
            single_albedo: Vec3::from_array(orders.map(|o| o.single().0)),
            single: orders.map(|o| o.single().1),
        }
    }

    /// `Rn(r) = A R̄_full(r) − (α/5.108) R̄_1(r)` per channel (signed, not truncated).
    pub fn profile_rgb(&self, r: f32) -> Vec3 {
        Vec3::from_array(std::array::from_fn(|c| {
            self.full_albedo[c] * self.full[c].pdf_disk(r)
                - self.single_albedo[c] * self.single[c].pdf_disk(r)
        }))
    }

    /// `S = Rn(‖x1 − x2‖)/π · F_t F_t`, 0 beyond the widest full-profile `r_max` of x1 (whose
    /// profiles must be [`MultipleScattering::full`]).
    pub fn bssrdf(&self, x1: &ExitPoint, x2: &EntryPoint, wi: Vec3) -> Vec3 {
        let r = (x2.position - x1.position).length();
        if r > x1.r_max.max_element() {
            return Vec3::ZERO;
        }
        bssrdf_of_profile(self.profile_rgb(r), x1, x2, wi)
    }

    /// `f = S · max(0, n2·ωi) · L_e`, unshadowed.
    pub fn contribution(&self, x1: &ExitPoint, x2: &EntryPoint, wi: Vec3, radiance: Vec3) -> Vec3 {
        let cos_i = x2.shading_normal.dot(wi);
        if cos_i.is_nan() || cos_i <= 0.0 {
            return Vec3::ZERO;
        }
        self.bssrdf(x1, x2, wi) * cos_i * radiance
    }
}

/// What the estimator needs about one pixel's primary hit, prepared once for all its samples.
#[derive(Clone, Copy, Debug)]
pub enum Shading<'a> {
    Translucent {
        medium: Medium,
        multiple: MultipleScattering,
        /// x1 with the full profiles of `multiple` (BSSRDF IS) and the material's `F_t`.
        x1: ExitPoint,
        /// The outward geometric normal at x1 (the path-traced entry).
        n1: Vec3,
        /// Whether the object's winding makes its geometric normals point inward.
        inward_winding: bool,
    },
    /// Lambert surfaces: the path tracer's direct lighting.
    Lambert(pt::Shading<'a>),
}

impl<'a> Shading<'a> {
    /// `media` = [`Medium::of_scene`]`(scene)`.
    pub fn new(scene: &'a Scene, media: &[Option<Medium>], x1: &GPixel) -> Shading<'a> {
        let index = scene.objects[x1.object as usize].material as usize;
        match (&scene.materials[index], media[index]) {
            (Material::Translucent(material), Some(medium)) => {
                Shading::translucent(scene, x1, medium, material.fresnel())
            }
            _ => Shading::Lambert(pt::Shading::new(scene, x1)),
        }
    }

    /// x1 on a translucent object with an explicit medium and Fresnel transmittance.
    pub fn translucent(
        scene: &Scene,
        x1: &GPixel,
        medium: Medium,
        fresnel: FresnelTransmission,
    ) -> Shading<'a> {
        let multiple = MultipleScattering::new(&medium);
        let inward_winding = scene.geometry.geometric_normal(x1.prim).dot(x1.view) < 0.0;
        Shading::Translucent {
            medium,
            multiple,
            x1: ExitPoint::with_profiles(
                x1.position,
                x1.geometric_normal,
                x1.shading_normal,
                x1.view,
                x1.object,
                multiple.full,
                fresnel,
            ),
            n1: x1.geometric_normal,
            inward_winding,
        }
    }
}

/// One estimate of the radiance leaving x1 toward the camera, by scattering order (Lambert
/// pixels: all of it in `zero`). Stream order: the path-traced part, then the BSSRDF IS probe and
/// its light samples (x2's lights from `scene.lights`; the exits' from `lighting`).
pub fn estimate<L: ExitLighting>(
    scene: &Scene,
    shading: &Shading,
    settings: &SingleScatterSettings,
    lighting: &L,
    rng: &mut Stream,
    hits: &mut Vec<Hit>,
) -> Orders {
    match shading {
        Shading::Translucent {
            medium,
            multiple,
            x1,
            n1,
            inward_winding,
        } => {
            let boundary = MeshBoundary {
                geometry: &scene.geometry,
                object: x1.object,
                inward_winding: *inward_winding,
            };
            let mut orders = path_traced(
                &boundary,
                medium,
                x1.position,
                *n1,
                x1.view,
                lighting,
                settings,
                rng,
            );
            orders.multiple =
                pt::estimate_bssrdf(scene, x1, &settings.diffusion, rng, hits, |x2, wi, le| {
                    multiple.contribution(x1, x2, wi, le)
                });
            orders
        }
        Shading::Lambert(shading) => Orders {
            zero: pt::estimate(scene, shading, &settings.diffusion, rng, hits),
            ..Orders::default()
        },
    }
}

/// The random stream of sample `sample` of pixel `pixel` in `frame`.
pub fn sample_stream(pixel: u32, frame: u32, sample: u32, seed: u64) -> Stream {
    StreamKey {
        pixel,
        frame,
        pass: sample,
        purpose: PURPOSE_SINGLE_SCATTER,
    }
    .stream(seed)
}

/// The mean of samples `first_sample .. first_sample + spp` of every pixel (rayon over rows;
/// bit-identical for any thread count when `lighting_for(pixel)` is a function of the pixel).
/// `lighting_for` supplies the exits' [`ExitLighting`] per pixel (e.g. with its own keyed
/// light-selection stream). Non-finite samples are left out and counted; truncated chains are
/// returned as the second value. Errors: materials the medium mapping rejects (`dmfp`).
pub fn render<L: ExitLighting, F: Fn(u32) -> L + Sync>(
    scene: &Scene,
    gbuffer: &GBuffer,
    settings: &SingleScatterSettings,
    seed: u64,
    first_sample: u32,
    spp: u32,
    lighting_for: F,
) -> Result<(SampleMeans, u64), InputError> {
    let media = Medium::of_scene(scene)?;
    let truncated = AtomicU64::new(0);
    let image = pt::render_pixels(
        gbuffer,
        first_sample..first_sample + spp,
        |pixel, x1| (Shading::new(scene, &media, x1), lighting_for(pixel)),
        |(shading, lighting), pixel, sample, hits| {
            let mut rng = sample_stream(pixel, gbuffer.frame, sample, seed);
            let orders = estimate(scene, shading, settings, lighting, &mut rng, hits);
            if orders.truncated {
                truncated.fetch_add(1, Ordering::Relaxed);
            }
            orders.total()
        },
    );
    Ok((image, truncated.into_inner()))
}

#[cfg(test)]
mod tests;
