//! Image-space subsurface scattering of paper 002 (Mertens et al. 2003) with the Jensen dipole:
//! the rendering method `image-space`. Its GLSL twin is `image_space.glsl` beside it.
//!
//! Each of the `spp` passes `s` of a frame runs two stages over the G-buffer:
//! 1. **irradiance** from the eye [002 §5]: every translucent pixel q gets
//!    `E(x_q) = ∫ L_i F_t(n_q·ωi) (n_q·ωi) dωi` [002 Eq. 5], estimated with light samples and
//!    shadow rays ([`irradiance`]);
//! 2. **gather**: every translucent pixel o estimates `B(x_o) = ∫ R_d(‖x − x_o‖) E(x) dA_x`
//!    [002 Eq. 4] on the tangent plane of x_o ([`gather_pixel`]) and shows
//!    `L = F_t(n_o·ωo)/π · B` [002 Eq. 3].
//!
//! `F_t` is the material's normalised Fresnel transmittance of the BSSRDF
//! ([`FresnelTransmission`], per material `ior`), so that `L` factors the dipole BSSRDF of the
//! path tracer ([`bssrdf_dipole`](sss::bssrdf::bssrdf_dipole)) exactly.
//!
//! The gather draws points `p′` on the tangent plane (geometric normal of x_o) from two sets,
//! `N_i` importance samples whose radius follows the dipole of a channel picked with `P(c)`
//! (pole by `ρ`, exact Newton inversion [002 §4, Eq. 6–7]) and `N_u` samples uniform on the disk of
//! radius `R′ = r_max_all` [002 §6.1]. Each `p′` is projected through the eye into the image; the
//! pixel q whose sample is nearest gives the entry point x (where the eye ray through `p′` meets
//! q's tangent plane), its normal `n` and `E(x_q)` ([`lookup_pixel`]).
//! With `r = ‖x − x_o‖`, `r′ = ‖p′ − x_o‖` and the Jacobian `J = |dA_x/dA_p′|` of the central
//! projection ([`projection_jacobian`], [002 Eq. 8]) the balance heuristic over both sets gives
//!
//! `B ≈ Σ_j R_d(r_j) E(x_j) J_j / (N_i p_i(r′_j) + N_u p_u)`,  `p_i = Σ_c P(c) R_d,c(r′)/ρ_c`,
//! `p_u = 1/(πR′²)`,
//!
//! which reduces to [002 Eq. 9] (`ρ R_d(r)/R_d(r′) E J / N`) for one channel and no uniform
//! samples. The Jacobian is kept (the paper drops it on the GPU).
//!
//! **Bias.** The estimate is unbiased for the integral over the entry points the image shows. It
//! misses the others, and counts them ([`EntryCounts`]): `p′` projecting off screen, onto another
//! object or onto nothing (an occluded or unseen entry point), and entry points beyond the
//! truncation radius (`r > R′`, or `r′ > R′` for a dipole sample; the profile is cut at `R′` as in
//! the path-traced reference, [`DipoleProfiles`]). Pixel discretisation (q's tangent plane and `E`
//! for the surface under `p′`) and the tangent-plane disk (a curved surface reaches `r ≤ R′`
//! outside it) add more. The reference to measure it against is the path tracer with
//! [`ProfileKind::Dipole`](sss::profile::ProfileKind) (the same truncated dipole).
//!
//! Random numbers: pass `s` of pixel `p` draws the irradiance from
//! `StreamKey { p, frame, s, PURPOSE_IRRADIANCE }` and the gather from
//! `StreamKey { p, frame, s, PURPOSE_GATHER }`; Lambert pixels get the path tracer's sample `s`
//! ([`pt::sample_stream`]). Every pixel and pass is a pure function of these, so frames are
//! bit-identical for any thread count.

use std::f32::consts::{FRAC_1_PI, PI, TAU};

use glam::{DVec3, Vec3};
use rayon::prelude::*;
use restir::rng::{Stream, StreamKey};

use geometry::{Frame, Hit};
use sss::InputError;
use sss::integrator::pt::{self, PtSettings, SampleMeans, Shading, occluded};
use sss::material::{DipoleProfiles, FresnelTransmission, Material, Translucent};
use sss::scene::{GBuffer, GPixel, Scene};

pub use super::contract::{LookupKind, PURPOSE_GATHER, PURPOSE_IRRADIANCE};

/// Sample counts of one pass.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImageSpaceSettings {
    /// Light samples per translucent pixel for `E` [002 Eq. 5].
    pub irradiance_samples: u32,
    /// Dipole importance samples per translucent pixel [002 §4].
    pub importance_samples: u32,
    /// Uniform disk samples per translucent pixel [002 §6.1].
    pub uniform_samples: u32,
    /// `P(c)`: probability that an importance sample follows channel `c`'s dipole (renormalised
    /// over the channels with `ρ_c > 0`).
    pub channel: [f32; 3],
}

impl Default for ImageSpaceSettings {
    /// One light sample, eight importance and two uniform samples, channels uniform.
    fn default() -> Self {
        ImageSpaceSettings {
            irradiance_samples: 1,
            importance_samples: 8,
            uniform_samples: 2,
            channel: [1.0 / 3.0; 3],
        }
    }
}

impl ImageSpaceSettings {
    /// At least one tangent-plane sample, and `P(c)` finite, ≥ 0, not all 0; the error names
    /// `image_space.<field>` and its value.
    pub fn validate(&self) -> Result<(), InputError> {
        let err = |field: &str, value: String, reason: &str| {
            Err(InputError::new(
                "(image-space settings)",
                format!("image_space.{field}"),
                value,
                reason,
            ))
        };
        if self.importance_samples as u64 + self.uniform_samples as u64 == 0 {
            return err(
                "importance_samples",
                "0 + 0 uniform".into(),
                "need at least one tangent-plane sample",
            );
        }
        let sum: f32 = self.channel.iter().sum();
        if self.channel.iter().any(|p| !(p.is_finite() && *p >= 0.0)) || !(sum > 0.0) {
            return err(
                "channel",
                format!("{:?}", self.channel),
                "each P(c) must be finite and ≥ 0, and their sum > 0",
            );
        }
        Ok(())
    }
}

/// What the gather found for its samples (summed over pixels and passes).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct EntryCounts {
    /// Tangent-plane samples drawn.
    pub samples: u64,
    /// Samples whose `p′` projects outside the image or behind the eye.
    pub off_screen: u64,
    /// Samples whose pixel shows another object or nothing: the entry point under `p′` is
    /// occluded or not part of the visible surface (or the ray misses the pixel's tangent plane).
    pub occluded: u64,
    /// Samples beyond the truncation radius (`r′ > R′` or `r > R′`).
    pub outside: u64,
    /// Samples whose entry surface is seen exactly edge-on (`J` undefined).
    pub edge_on: u64,
}

impl EntryCounts {
    fn add(&mut self, other: &EntryCounts) {
        self.samples += other.samples;
        self.off_screen += other.off_screen;
        self.occluded += other.occluded;
        self.outside += other.outside;
        self.edge_on += other.edge_on;
    }

    /// Samples that reached an entry point and contributed.
    pub fn used(&self) -> u64 {
        self.samples - self.off_screen - self.occluded - self.outside - self.edge_on
    }
}

/// A rendered frame and its entry statistics.
#[derive(Clone, Debug, PartialEq)]
pub struct ImageSpaceFrame {
    pub image: SampleMeans,
    pub entries: EntryCounts,
}

/// The dipoles of one material with the channel probabilities of its importance samples.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GatherProfile {
    pub dipoles: DipoleProfiles,
    /// The material's `F_t` (of its `ior`), for `E` and the exit radiance.
    pub fresnel: FresnelTransmission,
    /// `ρ_c` [002 Eq. 7] per channel.
    pub reflectance: [f32; 3],
    /// `P(c)` renormalised over the channels with `ρ_c > 0`; all 0 if none has.
    pub channel: [f32; 3],
}

impl GatherProfile {
    /// The gather profile of `material` with importance-channel probabilities `channel`.
    pub fn new(material: &Translucent, channel: [f32; 3]) -> GatherProfile {
        let dipoles = DipoleProfiles::new(material);
        let reflectance = dipoles.channels.map(|d| d.total_reflectance());
        let weights: [f32; 3] = std::array::from_fn(|c| {
            if reflectance[c] > 0.0 {
                channel[c]
            } else {
                0.0
            }
        });
        let sum: f32 = weights.iter().sum();
        GatherProfile {
            dipoles,
            fresnel: material.fresnel(),
            reflectance,
            channel: if sum > 0.0 {
                weights.map(|w| w / sum)
            } else {
                [0.0; 3]
            },
        }
    }

    /// The importance channel whose cumulative interval contains `u` (never one of probability 0).
    fn pick_channel(&self, u: f32) -> usize {
        let mut cumulative = 0.0;
        let mut last = 0;
        for (c, &p) in self.channel.iter().enumerate() {
            if p <= 0.0 {
                continue;
            }
            cumulative += p;
            last = c;
            if u < cumulative {
                return c;
            }
        }
        last
    }

    /// Tangent-plane area density of one importance sample at radius `r′`: `Σ_c P(c) R_d,c(r′)/ρ_c`
    /// (each term is [`Dipole::pdf_disk`](sss::profile::Dipole::pdf_disk) with `ρ_c` cached).
    fn importance_density(&self, r: f32) -> f32 {
        let mut sum = 0.0;
        for c in 0..3 {
            if self.channel[c] > 0.0 {
                sum +=
                    self.channel[c] * (self.dipoles.channels[c].profile(r) / self.reflectance[c]);
            }
        }
        sum
    }
}

/// The receiving pixel x_o of the gather.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Receiver {
    pub position: Vec3,
    /// The frame of x_o's geometric normal (facing the camera): the tangent plane is `t, b`.
    pub frame: Frame,
    /// The eye (centre of projection of the image).
    pub eye: Vec3,
}

/// What the image shows under a tangent-plane point `p′`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Lookup {
    /// The entry point x with its unit geometric normal and irradiance `E(x)`.
    Entry {
        position: Vec3,
        normal: Vec3,
        irradiance: Vec3,
    },
    OffScreen,
    /// Another object or no hit.
    Occluded,
}

impl Lookup {
    /// The lookup without its entry point: the code a GPU lookup returns.
    pub fn kind(&self) -> LookupKind {
        match self {
            Lookup::Entry { .. } => LookupKind::Entry,
            Lookup::OffScreen => LookupKind::OffScreen,
            Lookup::Occluded => LookupKind::Occluded,
        }
    }
}

/// `|dA_x / dA_p′|` for the central projection from `eye` of the plane through `p_prime` with unit
/// normal `n_prime` onto the surface at `x` with unit normal `n` [002 Eq. 8]: equal solid angles,
/// `dA_x cos α / d² = dA_p′ cos α′ / d′²`, give `(cos α′ d²) / (cos α d′²)` with `d = ‖x − e‖`,
/// `cos α = |n·(x − e)|/d` (primed alike). 0 when the surface is seen edge-on (`cos α = 0`).
pub fn projection_jacobian(eye: Vec3, p_prime: Vec3, n_prime: Vec3, x: Vec3, n: Vec3) -> f32 {
    let (v_prime, v) = (p_prime - eye, x - eye);
    // With cos α = |n·v|/d and cos α′ = |n′·v′|/d′ the ratio is |n′·v′| d³ / (|n·v| d′³).
    let (d2, d2_prime) = (v.length_squared(), v_prime.length_squared());
    let denominator = n.dot(v).abs() * d2_prime * d2_prime.sqrt();
    if !(denominator > 0.0) {
        return 0.0;
    }
    n_prime.dot(v_prime).abs() * d2 * d2.sqrt() / denominator
}

/// `B(x_o)` per channel [002 Eq. 4] from `N_i + N_u` tangent-plane samples (module doc); `lookup`
/// maps a tangent-plane point to what the image shows there. Counts its samples into `counts`.
pub fn gather_pixel(
    receiver: &Receiver,
    profile: &GatherProfile,
    settings: &ImageSpaceSettings,
    lookup: impl Fn(Vec3) -> Lookup,
    rng: &mut Stream,
    counts: &mut EntryCounts,
) -> Vec3 {
    let r_support = profile.dipoles.r_max_all;
    let importance = if profile.channel == [0.0; 3] {
        0
    } else {
        settings.importance_samples
    };
    let uniform_density = settings.uniform_samples as f32 / (PI * r_support * r_support);
    let mut sum = Vec3::ZERO;
    for j in 0..importance + settings.uniform_samples {
        counts.samples += 1;
        let r_prime = if j < importance {
            let c = profile.pick_channel(rng.next_f32());
            profile.dipoles.channels[c].sample_radius(rng.next_f32())
        } else {
            r_support * rng.next_f32().sqrt()
        };
        let phi = TAU * rng.next_f32();
        if !(r_prime <= r_support) {
            counts.outside += 1;
            continue;
        }
        let Frame { t, b, n } = receiver.frame;
        let p_prime = receiver.position + r_prime * (phi.cos() * t + phi.sin() * b);
        let (x, normal, irradiance) = match lookup(p_prime) {
            Lookup::Entry {
                position,
                normal,
                irradiance,
            } => (position, normal, irradiance),
            Lookup::OffScreen => {
                counts.off_screen += 1;
                continue;
            }
            Lookup::Occluded => {
                counts.occluded += 1;
                continue;
            }
        };
        let r = (x - receiver.position).length();
        if r > r_support {
            counts.outside += 1;
            continue;
        }
        let jacobian = projection_jacobian(receiver.eye, p_prime, n, x, normal);
        if jacobian == 0.0 {
            counts.edge_on += 1;
            continue;
        }
        let density = importance as f32 * profile.importance_density(r_prime) + uniform_density;
        sum += profile.dipoles.profile_rgb(r) * irradiance * (jacobian / density);
    }
    sum
}

/// The G-buffer lookup of the gather: the pixel q whose (jittered) sample lies nearest to the
/// projection of `p′` at `gbuffer`'s frame, an entry point if it shows `object`. The entry point
/// is where the eye ray through `p′` meets q's tangent plane (q's position and geometric normal),
/// its normal and `E` are q's. The paper reconstructs x from q's depth alone [002 §6.2]; taking q's
/// hit point itself would put every `p′` of x_o's own pixel at `r = 0`, where `R_d` peaks. Both
/// over-weight profiles narrower than a pixel; the plane is exact on planar surfaces. `Occluded`
/// where the ray runs parallel to that plane or meets it behind the eye.
pub fn lookup_pixel(
    scene: &Scene,
    gbuffer: &GBuffer,
    irradiance: &[Vec3],
    object: u32,
    p_prime: Vec3,
) -> Lookup {
    let Some(c) = scene.camera.project(gbuffer.frame, p_prime) else {
        return Lookup::OffScreen;
    };
    let q = (c - scene.camera.jitter(gbuffer.frame)).floor();
    if !(q.x >= 0.0 && q.y >= 0.0 && q.x < gbuffer.width as f32 && q.y < gbuffer.height as f32) {
        return Lookup::OffScreen;
    }
    let (qx, qy) = (q.x as u32, q.y as u32);
    match gbuffer.get(qx, qy) {
        Some(g) if g.object == object => {
            let eye = scene.camera.eye(gbuffer.frame);
            let ray = p_prime - eye;
            let t = g.geometric_normal.dot(g.position - eye) / g.geometric_normal.dot(ray);
            if !(t > 0.0 && t.is_finite()) {
                return Lookup::Occluded;
            }
            Lookup::Entry {
                position: eye + ray * t,
                normal: g.geometric_normal,
                irradiance: irradiance[(qy * gbuffer.width + qx) as usize],
            }
        }
        _ => Lookup::Occluded,
    }
}

/// `E(x)` at a visible surface point [002 Eq. 5]: the mean of `samples` light samples
/// `L_e F_t(n_s·ωi) (n_s·ωi) / p_light`, shadow-tested (`F_t = fresnel`, the material's, and the
/// cosine on the shading normal, as for x2 in the BSSRDF).
pub fn irradiance_at(
    scene: &Scene,
    x: &GPixel,
    fresnel: &FresnelTransmission,
    samples: u32,
    rng: &mut Stream,
) -> Vec3 {
    let mut sum = Vec3::ZERO;
    for _ in 0..samples {
        let Some(light) = scene
            .lights
            .sample(x.position, [rng.next_f32(), rng.next_f32(), rng.next_f32()])
        else {
            continue;
        };
        let cos = x.shading_normal.dot(light.wi);
        if !(cos > 0.0 && light.pdf > 0.0) {
            continue;
        }
        if occluded(
            scene,
            x.position,
            x.geometric_normal,
            light.wi,
            light.distance,
        ) {
            continue;
        }
        sum += light.radiance * (fresnel.eval(cos) * cos / light.pdf);
    }
    if samples > 0 {
        sum / samples as f32
    } else {
        Vec3::ZERO
    }
}

/// The irradiance stage of pass `pass`: `E` of every pixel on a translucent object (0 elsewhere).
pub fn irradiance(
    scene: &Scene,
    gbuffer: &GBuffer,
    settings: &ImageSpaceSettings,
    seed: u64,
    pass: u32,
) -> Vec<Vec3> {
    let mut out = vec![Vec3::ZERO; gbuffer.pixels.len()];
    out.par_iter_mut()
        .zip(&gbuffer.pixels)
        .enumerate()
        .for_each(|(pixel, (e, g))| {
            let Some(g) = g else { return };
            let Material::Translucent(material) = scene.material_of_object(g.object) else {
                return;
            };
            let mut rng =
                StreamKey::new(pixel as u32, gbuffer.frame, pass, PURPOSE_IRRADIANCE).stream(seed);
            let fresnel = material.fresnel();
            *e = irradiance_at(scene, g, &fresnel, settings.irradiance_samples, &mut rng);
        });
    out
}

/// The gather profile of every material (`None` for Lambert ones).
pub fn gather_profiles(scene: &Scene, settings: &ImageSpaceSettings) -> Vec<Option<GatherProfile>> {
    scene
        .materials
        .iter()
        .map(|m| match m {
            Material::Translucent(t) => Some(GatherProfile::new(t, settings.channel)),
            Material::Lambert(_) => None,
        })
        .collect()
}

/// Exit radiance of a translucent pixel from its `B`: `F_t(n_o·ωo)/π · B` [002 Eq. 3] with the
/// material's `F_t = fresnel`.
pub fn exit_radiance(x: &GPixel, fresnel: &FresnelTransmission, b: Vec3) -> Vec3 {
    b * (FRAC_1_PI * fresnel.eval(x.shading_normal.dot(x.view)))
}

/// One pass's value of every pixel (translucent: gather; Lambert: the path tracer's sample `pass`)
/// and its entry counts.
fn pass_values(
    scene: &Scene,
    gbuffer: &GBuffer,
    profiles: &[Option<GatherProfile>],
    settings: &ImageSpaceSettings,
    seed: u64,
    pass: u32,
) -> (Vec<Vec3>, EntryCounts) {
    let e = irradiance(scene, gbuffer, settings, seed, pass);
    let width = gbuffer.width as usize;
    let mut values = vec![Vec3::ZERO; gbuffer.pixels.len()];
    let eye = scene.camera.eye(gbuffer.frame);
    let counts = values
        .par_chunks_mut(width.max(1))
        .zip(gbuffer.pixels.par_chunks(width.max(1)))
        .enumerate()
        .map(|(py, (out, row))| {
            let mut counts = EntryCounts::default();
            let mut hits: Vec<Hit> = Vec::new();
            for (px, (out, g)) in out.iter_mut().zip(row).enumerate() {
                let Some(g) = g else { continue };
                let pixel = (py * width + px) as u32;
                let material = scene.objects[g.object as usize].material as usize;
                *out = match &profiles[material] {
                    Some(profile) => {
                        let receiver = Receiver {
                            position: g.position,
                            frame: Frame::from_normal(g.geometric_normal),
                            eye,
                        };
                        let mut rng =
                            StreamKey::new(pixel, gbuffer.frame, pass, PURPOSE_GATHER).stream(seed);
                        let b = gather_pixel(
                            &receiver,
                            profile,
                            settings,
                            |p| lookup_pixel(scene, gbuffer, &e, g.object, p),
                            &mut rng,
                            &mut counts,
                        );
                        exit_radiance(g, &profile.fresnel, b)
                    }
                    None => {
                        let mut rng = pt::sample_stream(pixel, gbuffer.frame, pass, seed);
                        let shading = Shading::new(scene, g);
                        pt::estimate(scene, &shading, &PtSettings::default(), &mut rng, &mut hits)
                    }
                };
            }
            counts
        })
        .reduce(EntryCounts::default, |mut a, b| {
            a.add(&b);
            a
        });
    (values, counts)
}

/// The image-space method on one frame: the mean of `spp` passes (module doc). Pixels without a
/// primary hit are 0; non-finite pass values are counted and left out of the mean.
pub fn render(
    scene: &Scene,
    gbuffer: &GBuffer,
    settings: &ImageSpaceSettings,
    seed: u64,
    spp: u32,
) -> ImageSpaceFrame {
    let profiles = gather_profiles(scene, settings);
    let mut sum = vec![DVec3::ZERO; gbuffer.pixels.len()];
    let mut nonfinite = 0;
    let mut entries = EntryCounts::default();
    for pass in 0..spp {
        let (values, counts) = pass_values(scene, gbuffer, &profiles, settings, seed, pass);
        entries.add(&counts);
        for (s, v) in sum.iter_mut().zip(values) {
            if v.is_finite() {
                *s += v.as_dvec3();
            } else {
                nonfinite += 1;
            }
        }
    }
    let pixels = if spp > 0 {
        sum.into_iter().map(|s| s / spp as f64).collect()
    } else {
        sum
    };
    ImageSpaceFrame {
        image: SampleMeans {
            width: gbuffer.width,
            height: gbuffer.height,
            pixels,
            nonfinite,
        },
        entries,
    }
}

#[cfg(test)]
mod tests;
