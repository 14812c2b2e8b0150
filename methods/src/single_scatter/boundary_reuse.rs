//! ReSTIR on paper 000's boundary (zero-scattering) term [000 "ReSTIR Sample"]: the option
//! `/restir` of [`single_scatter`](sss::integrator::single_scatter). Single scattering and the `R − R1` diffusion part are the
//! plain estimator's; only the boundary term `e^{−σt d0} f0 L0` [000 slide 60] is replaced by
//! the estimate `f(Y) · W_Y` of a per-pixel reservoir, reused over frames and pixels.
//!
//! **Domain** ([`BoundaryDomain`], one per pixel and frame; DESIGN §3). The boundary term of the
//! diffuse boundary (Lambertian transmission `1/π` at entry and exit) is an integral over the
//! entry direction `ω` (world space, solid angle) and, at the exit `x_e = x1 + d(ω) ω`, the light
//! vertex `y` (area measure on area lights, counting measure on point and directional lights):
//!
//! `f(ω, y) = cos θ_ω/π · e^{−σt d(ω)} · cos θ_e/π · L_e(y → x_e) · G(x_e, y) · V(x_e, y)`
//!
//! with `G = |cos θ_y| / ‖y − x_e‖²` for area lights and 1 for delta lights (whose `L_e` is
//! already the irradiance: [`Light::radiance`]). The target is `p̂ = luminance(f)`, so it holds
//! the chord's transmittance, both transmission factors and the exit's shadow ray; a pixel is
//! shaded with `f(Y) · W_Y`. The plain estimator reaches the same integral with next-event
//! estimation and an escape direction (balance heuristic); the reservoir's candidates use light
//! sampling alone ([`Candidates`]: `ω` cosine-distributed, `y` from
//! [`Lights::sample`](sss::scene::Lights::sample) at `x_e`), whose density is positive wherever
//! `f` is. `V` tests the scene's geometry only: lights do not occlude one another, as in
//! next-event estimation.
//!
//! **Shift** ([`SameVertices`]): the destination reuses the same world direction and the same
//! light vertex, `J = 1` in those measures; it fails where `ω` does not enter the destination's
//! surface (`ω · n1 ≥ 0`). The destination evaluates its own chord, exit and shadow ray.
//!
//! **Passes per frame** (every number from a [`StreamKey`] of the receiving pixel):
//! 1. candidates: `M` = spp candidates (the talk's `M = 1`), `c = M`;
//! 2. temporal: the previous frame's final reservoir at the reprojected pixel
//!    ([`GBuffer::reproject`], ReSTIR SSS's), its confidence capped at `cap · c` ([`cap_confidence`],
//!    [`DEFAULT_CAP`] like the ReSTIR SSS presets), GBH over the two domains [001 Eq. 8];
//! 3. spatial: the eight neighbours of the 3 × 3 block [000 "standard screen-space reuse within a
//!    3x3 region"], culled when they show another object or a normal with cosine below
//!    [`REPROJECTION_NORMAL_COSINE`], combined by defensive pairwise MIS with the pixel's own
//!    reservoir as canonical. Its output is the frame's final reservoir, shaded and passed on.
//!
//! **Materials.** Diffuse boundaries only: on a dielectric or index-matched boundary both the
//! entry and the exit direction are deltas (the exit is lit only along the refracted ray, with
//! no light sample), so the boundary term has no continuous variable to resample;
//! [`check_materials`] refuses those materials in one line.

use std::f32::consts::FRAC_1_PI;
use std::fmt;
use std::sync::atomic::{AtomicU64, Ordering};

use glam::Vec3;
use rayon::prelude::*;
use restir::mis::{DefensivePairwise, Gbh};
use restir::resample::{ResampleError, Source, generate_candidates, resample};
use restir::reservoir::{Reservoir, cap_confidence};
use restir::rng::{Stream, StreamKey};
use restir::shift::{CandidateSampler, Domain, Fail, Shift, Shifted};

use sss::InputError;
use sss::color::luminance;
use sss::integrator::pt::{self, SampleMeans};
use sss::integrator::single_scatter::{Shading, SingleScatterSettings, estimate, sample_stream};
use sss::material::{BoundaryKind, Material};
use sss::random_walk::{Boundary, ExitLighting, Medium, MeshBoundary};
use sss::sampling::{cosine_hemisphere_pdf, sample_cosine_hemisphere};
use sss::scene::{DIRECTIONAL_DISTANCE, GBuffer, GPixel, Light, REPROJECTION_NORMAL_COSINE, Scene};

/// `purpose` of the candidate streams (ASCII "SB" + 1: single-scatter boundary).
pub const PURPOSE_BOUNDARY_CANDIDATES: u32 = 0x5342_0001;
/// `purpose` of the temporal pass's selection streams ("SB" + 2).
pub const PURPOSE_BOUNDARY_TEMPORAL: u32 = 0x5342_0002;
/// `purpose` of the spatial pass's selection streams ("SB" + 3).
pub const PURPOSE_BOUNDARY_SPATIAL: u32 = 0x5342_0003;

/// The temporal confidence cap `κ` (`c_prev ≤ κ · c`), the ReSTIR SSS presets' default.
pub const DEFAULT_CAP: f32 = 3.0;

/// A point of the boundary term's domain: the entry direction and the exit's light vertex.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoundarySample {
    /// Unit world direction into the medium at x1 (solid-angle measure).
    pub dir: Vec3,
    /// Index of the light in `scene.lights`.
    pub light: u32,
    /// The vertex on an area light (area measure); zero for point and directional lights,
    /// whose vertex is the light itself.
    pub point: Vec3,
}

/// The boundary term of one pixel in one frame: x1, its outward normal, the object's mesh as the
/// boundary and the medium's extinction.
#[derive(Clone, Copy)]
pub struct BoundaryDomain<'a> {
    scene: &'a Scene,
    boundary: MeshBoundary<'a>,
    sigma_t: Vec3,
    x1: Vec3,
    n1: Vec3,
    object: u32,
}

impl<'a> BoundaryDomain<'a> {
    /// The domain of primary hit `g`, `None` unless it lies on a translucent object with a
    /// diffuse boundary (`media` = [`Medium::of_scene`]`(scene)`).
    pub fn new(
        scene: &'a Scene,
        media: &[Option<Medium>],
        g: &GPixel,
    ) -> Option<BoundaryDomain<'a>> {
        let medium = media[scene.objects[g.object as usize].material as usize]?;
        if medium.interface().kind() != BoundaryKind::Diffuse {
            return None;
        }
        let inward_winding = scene.geometry.geometric_normal(g.prim).dot(g.view) < 0.0;
        Some(BoundaryDomain {
            scene,
            boundary: MeshBoundary {
                geometry: &scene.geometry,
                object: g.object,
                inward_winding,
            },
            sigma_t: medium.sigma_t(),
            x1: g.position,
            n1: g.geometric_normal,
            object: g.object,
        })
    }

    /// Where the unscattered chord along `dir` leaves: `(d, x_e, outward normal)`.
    fn exit(&self, dir: Vec3) -> Option<(f32, Vec3, Vec3)> {
        let hit = self.boundary.intersect(self.x1, dir, f32::INFINITY)?;
        Some((hit.t, self.x1 + hit.t * dir, hit.normal))
    }

    /// `(ω_i, distance, G)` from the exit `x_e` to the vertex of `x` (module doc), `None` for an
    /// unknown light or a degenerate configuration.
    fn toward_light(&self, x: &BoundarySample, exit: Vec3) -> Option<(Vec3, f32, f32)> {
        let lights = &self.scene.lights;
        if x.light as usize >= lights.len() {
            return None;
        }
        let (offset, normal) = match *lights.get(x.light) {
            Light::Directional { direction, .. } => {
                return Some((-direction, DIRECTIONAL_DISTANCE, 1.0));
            }
            Light::Point { position, .. } => (position - exit, None),
            Light::Quad { edge_u, edge_v, .. } => (x.point - exit, Some(edge_u.cross(edge_v))),
            Light::Triangle {
                vertices: [v0, v1, v2],
                ..
            } => (x.point - exit, Some((v1 - v0).cross(v2 - v0))),
            Light::Sphere { center, .. } => (x.point - exit, Some(x.point - center)),
        };
        let distance = offset.length();
        if !(distance > 0.0) {
            return None;
        }
        let wi = offset / distance;
        let geometry = match normal {
            None => 1.0,
            Some(n) => n.normalize().dot(wi).abs() / (distance * distance),
        };
        geometry.is_finite().then_some((wi, distance, geometry))
    }

    /// `f(x)` per channel (module doc), 0 outside the support.
    pub fn contribution(&self, x: &BoundarySample) -> Vec3 {
        let cos_in = -x.dir.dot(self.n1);
        if !(cos_in > 0.0) {
            return Vec3::ZERO;
        }
        let Some((d, exit, normal)) = self.exit(x.dir) else {
            return Vec3::ZERO;
        };
        let Some((wi, distance, geometry)) = self.toward_light(x, exit) else {
            return Vec3::ZERO;
        };
        let cos_exit = normal.dot(wi);
        if !(cos_exit > 0.0 && geometry > 0.0) {
            return Vec3::ZERO;
        }
        let vertex = match self.scene.lights.get(x.light) {
            Light::Point { position, .. } => *position,
            Light::Directional { .. } => exit + DIRECTIONAL_DISTANCE * wi,
            _ => x.point,
        };
        let emitted = self.scene.lights.radiance(x.light, vertex, exit);
        if emitted == Vec3::ZERO || pt::occluded(self.scene, exit, normal, wi, distance) {
            return Vec3::ZERO;
        }
        // [000 slide 60]: f_t cos (entry) · e^{−σt d} · f_t cos (exit) · L_e G.
        (cos_in * FRAC_1_PI)
            * (-self.sigma_t * d).exp()
            * (cos_exit * FRAC_1_PI * geometry)
            * emitted
    }

    pub fn x1(&self) -> Vec3 {
        self.x1
    }

    pub fn normal(&self) -> Vec3 {
        self.n1
    }
}

impl Domain for BoundaryDomain<'_> {
    type Sample = BoundarySample;

    fn target(&self, x: &BoundarySample) -> f32 {
        luminance(self.contribution(x))
    }
}

/// Candidates of the boundary term: `ω` cosine-distributed about `−n1`, then a light vertex
/// from [`Lights::sample`](sss::scene::Lights::sample) at the exit. Density
/// `cos θ_ω/π · p_y`, with `p_y` the selection probability times the area density (area lights)
/// or the selection probability alone (delta lights). Draws five numbers.
#[derive(Clone, Copy, Debug, Default)]
pub struct Candidates;

impl Candidates {
    /// `p_y` of the vertex of `x` seen from the exit `exit` (module doc).
    fn vertex_pdf(domain: &BoundaryDomain, x: &BoundarySample, exit: Vec3) -> f32 {
        let lights = &domain.scene.lights;
        if x.light as usize >= lights.len() {
            return 0.0;
        }
        if lights.get(x.light).is_delta() {
            return lights.selection_pmf(x.light);
        }
        // Solid angle → area: p_A = p_ω |cos θ_y| / ‖y − x_e‖².
        match domain.toward_light(x, exit) {
            Some((_, _, geometry)) => lights.pdf(exit, x.light, x.point) * geometry,
            None => 0.0,
        }
    }
}

impl<'a> CandidateSampler<BoundaryDomain<'a>> for Candidates {
    fn sample(
        &self,
        domain: &BoundaryDomain<'a>,
        rng: &mut Stream,
    ) -> Option<(BoundarySample, f32)> {
        let dir = sample_cosine_hemisphere(-domain.n1, [rng.next_f32(), rng.next_f32()]);
        let u = [rng.next_f32(), rng.next_f32(), rng.next_f32()];
        let (_, exit, _) = domain.exit(dir)?;
        let s = domain.scene.lights.sample(exit, u)?;
        let x = BoundarySample {
            dir,
            light: s.light,
            point: if s.is_delta { Vec3::ZERO } else { s.point },
        };
        let pdf = self.pdf(domain, &x);
        (pdf.is_finite() && pdf > 0.0).then_some((x, pdf))
    }

    fn pdf(&self, domain: &BoundaryDomain<'a>, x: &BoundarySample) -> f32 {
        let Some((_, exit, _)) = domain.exit(x.dir) else {
            return 0.0;
        };
        cosine_hemisphere_pdf(-domain.n1, x.dir) * Candidates::vertex_pdf(domain, x, exit)
    }
}

/// The shift between pixels and frames: the same direction and light vertex, `J = 1`; fails
/// where the direction does not enter the destination's surface.
#[derive(Clone, Copy, Debug, Default)]
pub struct SameVertices;

impl<'a> Shift<BoundaryDomain<'a>> for SameVertices {
    fn shift(
        &self,
        x: &BoundarySample,
        _src: &BoundaryDomain<'a>,
        dst: &BoundaryDomain<'a>,
    ) -> Result<Shifted<BoundarySample>, Fail> {
        if x.dir.dot(dst.n1) < 0.0 {
            Ok(Shifted {
                y: *x,
                jacobian: 1.0,
            })
        } else {
            Err(Fail::OutOfSupport)
        }
    }
}

/// [`SameVertices`] with its Jacobian multiplied by `self.0`: deliberately wrong, the negative
/// control of the tests (`restir::check`, the unbiasedness test of `lab`).
#[derive(Clone, Copy, Debug)]
pub struct ScaledJacobian(pub f32);

impl<'a> Shift<BoundaryDomain<'a>> for ScaledJacobian {
    fn shift(
        &self,
        x: &BoundarySample,
        src: &BoundaryDomain<'a>,
        dst: &BoundaryDomain<'a>,
    ) -> Result<Shifted<BoundarySample>, Fail> {
        SameVertices.shift(x, src, dst).map(|s| Shifted {
            jacobian: self.0 * s.jacobian,
            ..s
        })
    }
}

/// Knobs of the reuse.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReuseSettings {
    /// Candidates per pixel and frame (`M`).
    pub candidates: u32,
    /// Temporal confidence cap `κ`.
    pub cap: f32,
}

/// Why the reuse produced no image.
#[derive(Clone, Debug, PartialEq)]
pub enum ReuseError {
    /// A material the option cannot take, or one the medium mapping rejects.
    Input(InputError),
    /// A resampling step rejected its input (a defect of a domain or shift).
    Resample {
        pixel: u32,
        frame: u32,
        error: ResampleError,
    },
}

impl fmt::Display for ReuseError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ReuseError::Input(e) => write!(f, "{e}"),
            ReuseError::Resample {
                pixel,
                frame,
                error,
            } => write!(f, "boundary reuse, pixel {pixel}, frame {frame}: {error}"),
        }
    }
}

impl std::error::Error for ReuseError {}

impl From<InputError> for ReuseError {
    fn from(e: InputError) -> Self {
        ReuseError::Input(e)
    }
}

/// The media of `scene` ([`Medium::of_scene`]), refusing translucent materials whose boundary is
/// not diffuse (module doc, "Materials").
pub fn check_materials(scene: &Scene) -> Result<Vec<Option<Medium>>, InputError> {
    for (i, material) in scene.materials.iter().enumerate() {
        if let Material::Translucent(t) = material
            && t.boundary != BoundaryKind::Diffuse
        {
            return Err(InputError::new(
                &scene.file,
                format!("materials[{i}].boundary"),
                match t.boundary {
                    BoundaryKind::Dielectric => "\"dielectric\"",
                    _ => "\"index-matched\"",
                },
                "ReSTIR on the boundary term needs \"diffuse\" (this one's entry and exit are deltas)",
            ));
        }
    }
    Medium::of_scene(scene)
}

/// One frame's domains and final reservoirs (`None` off diffuse translucent objects).
struct FrameState<'a> {
    gbuffer: GBuffer,
    domains: Vec<Option<BoundaryDomain<'a>>>,
    reservoirs: Vec<Reservoir<BoundarySample>>,
}

/// The reuse over frames `0..frames` (module doc), calling `shade(frame, domains, reservoirs)`
/// with every frame's final reservoirs from frame `first_shaded` on. `media` from
/// [`check_materials`].
#[allow(clippy::too_many_arguments)]
pub fn run<T>(
    scene: &Scene,
    media: &[Option<Medium>],
    reuse: &ReuseSettings,
    seed: u64,
    frames: u32,
    first_shaded: u32,
    shift: &T,
    mut shade: impl FnMut(&GBuffer, &[Option<BoundaryDomain>], &[Reservoir<BoundarySample>]),
) -> Result<(), ReuseError>
where
    T: for<'a> Shift<BoundaryDomain<'a>>,
{
    let mut previous: Option<FrameState> = None;
    for frame in 0..frames {
        let state = reuse_frame(scene, media, reuse, seed, frame, previous.as_ref(), shift)?;
        if frame >= first_shaded {
            shade(&state.gbuffer, &state.domains, &state.reservoirs);
        }
        previous = Some(state);
    }
    Ok(())
}

/// `f(Y)·W_Y` per pixel (0 off diffuse translucent objects), and how many values were not
/// finite (written as 0).
pub fn shade_boundary(
    domains: &[Option<BoundaryDomain>],
    reservoirs: &[Reservoir<BoundarySample>],
) -> (Vec<Vec3>, u64) {
    let nonfinite = AtomicU64::new(0);
    let image = domains
        .par_iter()
        .zip(reservoirs)
        .map(|(domain, r)| {
            let value = match (domain, r.y) {
                (Some(domain), Some(y)) => domain.contribution(&y) * r.ucw,
                _ => Vec3::ZERO,
            };
            if value.is_finite() {
                value
            } else {
                nonfinite.fetch_add(1, Ordering::Relaxed);
                Vec3::ZERO
            }
        })
        .collect();
    (image, nonfinite.into_inner())
}

/// Candidates, temporal and spatial reuse of one frame (module doc).
fn reuse_frame<'a, T>(
    scene: &'a Scene,
    media: &[Option<Medium>],
    reuse: &ReuseSettings,
    seed: u64,
    frame: u32,
    previous: Option<&FrameState<'a>>,
    shift: &T,
) -> Result<FrameState<'a>, ReuseError>
where
    T: for<'b> Shift<BoundaryDomain<'b>>,
{
    let gbuffer = GBuffer::render(scene, frame);
    let domains: Vec<Option<BoundaryDomain>> = gbuffer
        .pixels
        .iter()
        .map(|g| {
            g.as_ref()
                .and_then(|g| BoundaryDomain::new(scene, media, g))
        })
        .collect();
    let stream = |pixel: usize, pass: u32, purpose: u32| {
        StreamKey {
            pixel: pixel as u32,
            frame,
            pass,
            purpose,
        }
        .stream(seed)
    };
    let fail = |pixel: usize| {
        move |error| ReuseError::Resample {
            pixel: pixel as u32,
            frame,
            error,
        }
    };
    let candidates: Vec<Reservoir<BoundarySample>> = (0..domains.len())
        .into_par_iter()
        .map(|p| match &domains[p] {
            Some(domain) => {
                let mut rng = stream(p, 0, PURPOSE_BOUNDARY_CANDIDATES);
                generate_candidates(domain, &Candidates, reuse.candidates, &mut rng)
                    .map_err(fail(p))
            }
            None => Ok(Reservoir::empty()),
        })
        .collect::<Result<_, _>>()?;
    let temporal: Vec<Reservoir<BoundarySample>> = (0..domains.len())
        .into_par_iter()
        .map(|p| {
            let canonical = candidates[p];
            let (Some(domain), Some(g), Some(prev)) = (&domains[p], &gbuffer.pixels[p], previous)
            else {
                return Ok(canonical);
            };
            let Some(q) = prev.gbuffer.reproject(&scene.camera, g) else {
                return Ok(canonical);
            };
            let Some(prev_domain) = &prev.domains[q as usize] else {
                return Ok(canonical);
            };
            let mut history = prev.reservoirs[q as usize];
            history.confidence =
                cap_confidence(history.confidence, canonical.confidence, reuse.cap);
            let mut rng = stream(p, 1, PURPOSE_BOUNDARY_TEMPORAL);
            resample(
                Source {
                    domain,
                    reservoir: &canonical,
                },
                &[Source {
                    domain: prev_domain,
                    reservoir: &history,
                }],
                shift,
                &Gbh,
                &mut rng,
            )
            .map_err(fail(p))
        })
        .collect::<Result<_, _>>()?;
    let width = gbuffer.width as i64;
    let height = gbuffer.height as i64;
    let reservoirs: Vec<Reservoir<BoundarySample>> = (0..domains.len())
        .into_par_iter()
        .map(|p| {
            let Some(domain) = &domains[p] else {
                return Ok(temporal[p]);
            };
            let (px, py) = (p as i64 % width, p as i64 / width);
            let neighbours: Vec<Source<BoundaryDomain>> = (-1..=1)
                .flat_map(|dy| (-1..=1).map(move |dx| (px + dx, py + dy)))
                .filter(|&(x, y)| (x, y) != (px, py) && x >= 0 && y >= 0 && x < width && y < height)
                .filter_map(|(x, y)| {
                    let q = (y * width + x) as usize;
                    let other = domains[q].as_ref()?;
                    let similar = other.object == domain.object
                        && other.n1.dot(domain.n1) >= REPROJECTION_NORMAL_COSINE;
                    similar.then_some(Source {
                        domain: other,
                        reservoir: &temporal[q],
                    })
                })
                .collect();
            let mut rng = stream(p, 2, PURPOSE_BOUNDARY_SPATIAL);
            resample(
                Source {
                    domain,
                    reservoir: &temporal[p],
                },
                &neighbours,
                shift,
                &DefensivePairwise,
                &mut rng,
            )
            .map_err(fail(p))
        })
        .collect::<Result<_, _>>()?;
    Ok(FrameState {
        gbuffer,
        domains,
        reservoirs,
    })
}

/// One frame of [`render`].
#[derive(Clone, Debug, PartialEq)]
pub struct Rendered {
    /// The method's image: the reservoir's boundary term plus the mean of the plain
    /// estimator's single and multiple scattering (Lambert pixels: the path tracer).
    pub image: SampleMeans,
    /// The boundary term alone, `f(Y)·W_Y` per pixel.
    pub boundary: Vec<Vec3>,
    /// Chains cut at `max_segments` in the plain part.
    pub truncated: u64,
}

/// [`single_scatter::render`](sss::integrator::single_scatter::render) of frames `first_shaded..frames`
/// with the boundary term of every diffuse translucent pixel replaced by the reservoir's
/// ([`run`], `reuse.candidates` candidates per frame); `lighting_for(pixel, frame)` lights the
/// exits of the plain part, which draws the same streams as the plain method.
#[allow(clippy::too_many_arguments)]
pub fn render<L, F, T>(
    scene: &Scene,
    settings: &SingleScatterSettings,
    reuse: &ReuseSettings,
    seed: u64,
    frames: u32,
    first_shaded: u32,
    spp: u32,
    lighting_for: F,
    shift: &T,
) -> Result<Vec<Rendered>, ReuseError>
where
    L: ExitLighting,
    F: Fn(u32, u32) -> L + Sync,
    T: for<'a> Shift<BoundaryDomain<'a>>,
{
    let media = check_materials(scene)?;
    let mut out = Vec::new();
    run(
        scene,
        &media,
        reuse,
        seed,
        frames,
        first_shaded,
        shift,
        |gbuffer, domains, reservoirs| {
            let (boundary, nonfinite) = shade_boundary(domains, reservoirs);
            let truncated = AtomicU64::new(0);
            let frame = gbuffer.frame;
            let mut image = pt::render_pixels(
                gbuffer,
                0..spp,
                |pixel, x1| {
                    let reused = domains[pixel as usize].is_some();
                    (
                        Shading::new(scene, &media, x1),
                        lighting_for(pixel, frame),
                        reused,
                    )
                },
                |(shading, lighting, reused), pixel, sample, hits| {
                    let mut rng = sample_stream(pixel, frame, sample, seed);
                    let orders = estimate(scene, shading, settings, lighting, &mut rng, hits);
                    if orders.truncated {
                        truncated.fetch_add(1, Ordering::Relaxed);
                    }
                    if *reused {
                        orders.single + orders.multiple
                    } else {
                        orders.total()
                    }
                },
            );
            for (pixel, b) in image.pixels.iter_mut().zip(&boundary) {
                *pixel += b.as_dvec3();
            }
            image.nonfinite += nonfinite;
            out.push(Rendered {
                image,
                boundary,
                truncated: truncated.into_inner(),
            });
        },
    )?;
    Ok(out)
}

#[cfg(test)]
mod tests;
