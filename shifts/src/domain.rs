//! One integration domain of ReSTIR SSS: a pixel at a frame, with its exit point x1 (DESIGN §4,
//! §9). It evaluates the unshadowed contribution `f` and the target `p̂ = luminance(f)`, tests the
//! x2–x3 segment, and keys the random streams that some shifts need.

use std::fmt;
use std::sync::Arc;

use geometry::Ray;
use glam::{Vec3, Vec3A};
use restir::rng::{Stream, StreamKey};
use restir::shift::{Domain, LocalCoords};
use sss::bssrdf::{self, EntryPoint, ExitPoint, TechniqueSelection};
use sss::material::{Material, Translucent};
use sss::scene::{DIRECTIONAL_DISTANCE, GPixel, Light, Scene};

use crate::contract::{PARTNER_PIXEL_MASK, SHADOW_EPSILON};
pub(crate) use crate::contract::{PURPOSE_INVERSION, PURPOSE_PICK};
use crate::sample::SssSample;
use crate::target::Target;

/// The direction toward the light vertex seen from x2, and what the light sends along it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightPath {
    /// Unit direction x2 → x3 (ωi).
    pub wi: Vec3,
    /// `L_e` toward x2 (for delta lights the quantity that replaces it, see `sss::scene`).
    pub radiance: Vec3,
    /// The end of the shadow segment (x3, or a far point along ωi for a directional light).
    pub shadow_target: Vec3,
}

/// What of a sample does not depend on the domain it is evaluated in, among domains that share
/// a pose of the scene ([`SssDomain::locate`], [`SssDomain::shares_pose`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Located {
    /// x2.
    pub x2: EntryPoint,
    /// From x2 toward the light vertex; `None` for an unknown light or x3 = x2.
    pub light: Option<LightPath>,
}

/// One domain Ω: the pixel `pixel` (linear index) of frame `frame`, receiving in pass `pass`,
/// under the run seed `seed`.
///
/// Shifts that need randomness draw it from the stream of the domain where it is used, keyed by
/// the other domain of the pair:
/// `StreamKey { pixel, frame, pass, purpose: TAG | (partner pixel & 0x3FFF_FFFF) }.stream(seed)`,
/// with `TAG = 0b10 << 30` for probabilistic inversion's γ and `0b11 << 30` for the uniform hit
/// pick of an unknown intersection index (the pipeline's own purposes stay below 2³⁰). The
/// receiver's stream serves `T_{src→dst}` (inversion at y1, the pick); the exact index policy
/// also inverts at the source, with the source's stream, which is the γ its back-shift
/// `T_{dst→src}` draws (`crate::InvertingReconnection`). A shift is then deterministic given
/// `(src, dst)`, and independent across receivers, passes and sources (for images of up to 2³⁰
/// pixels).
#[derive(Clone, Copy)]
pub struct SssDomain<'s> {
    scene: &'s Scene,
    material: Translucent,
    x1: ExitPoint,
    selection: TechniqueSelection,
    target: Target,
    pixel: u32,
    frame: u32,
    pass: u32,
    seed: u64,
}

impl<'s> SssDomain<'s> {
    /// The domain of G-buffer pixel `gpixel`; `None` if x1 is not on a translucent object.
    /// BSSRDF IS uses paper 001's technique selection ([`TechniqueSelection::default`]).
    pub fn new(
        scene: &'s Scene,
        gpixel: &GPixel,
        pixel: u32,
        frame: u32,
        pass: u32,
        seed: u64,
    ) -> Option<Self> {
        let object = scene.objects.get(gpixel.object as usize)?;
        let Material::Translucent(material) = *scene.materials.get(object.material as usize)?
        else {
            return None;
        };
        let x1 = ExitPoint::new(
            gpixel.position,
            gpixel.geometric_normal,
            gpixel.shading_normal,
            gpixel.view,
            gpixel.object,
            &material,
        );
        let selection = TechniqueSelection::default();
        Some(SssDomain {
            scene,
            material,
            x1,
            selection,
            target: Target::Luminance,
            pixel,
            frame,
            pass,
            seed,
        })
    }

    /// The same domain with another technique selection (e.g. the channel CDF of paper 000).
    pub fn with_selection(self, selection: TechniqueSelection) -> Self {
        SssDomain { selection, ..self }
    }

    /// The same domain with another target function `p̂`.
    pub fn with_target(self, target: Target) -> Self {
        SssDomain { target, ..self }
    }

    pub fn scene(&self) -> &'s Scene {
        self.scene
    }

    /// Whether `other` sees the scene's objects where this domain does (the same geometry: the
    /// same frame, or a scene where nothing moves), so that what [`SssDomain::locate`] finds here
    /// holds there.
    pub fn shares_pose(&self, other: &SssDomain) -> bool {
        Arc::ptr_eq(&self.scene.geometry, &other.scene.geometry)
    }

    pub fn material(&self) -> &Translucent {
        &self.material
    }

    /// The exit point x1.
    pub fn x1(&self) -> &ExitPoint {
        &self.x1
    }

    pub fn selection(&self) -> &TechniqueSelection {
        &self.selection
    }

    pub fn pixel(&self) -> u32 {
        self.pixel
    }

    pub fn frame(&self) -> u32 {
        self.frame
    }

    pub fn pass(&self) -> u32 {
        self.pass
    }

    /// x2 of `y`; `None` if its triangle does not exist or lies on another object than x1.
    pub fn entry_point(&self, y: &SssSample) -> Option<EntryPoint> {
        (y.object() == self.x1.object)
            .then(|| self.locate_x2(y))
            .flatten()
    }

    /// x2 of `y` wherever it lies (no check against x1's object); `None` if its triangle does
    /// not exist or is not on `y`'s object.
    pub(crate) fn locate_x2(&self, y: &SssSample) -> Option<EntryPoint> {
        let geometry = &self.scene.geometry;
        if y.prim() >= geometry.triangle_count() || geometry.object_of(y.prim()) != y.object() {
            return None;
        }
        Some(EntryPoint::new(geometry, y.prim(), y.bary()))
    }

    /// What of `y` does not depend on the domain: its x2 and light path ([`Located`]), for
    /// evaluating it in several domains of one pose ([`SssDomain::target_located`]).
    pub fn locate(&self, y: &SssSample) -> Option<Located> {
        let x2 = self.locate_x2(y)?;
        Some(Located {
            x2,
            light: self.light_path(x2.position, y),
        })
    }

    /// `p_disk(x2 | x1)` of this domain's x1 [`bssrdf::p_disk`].
    pub fn p_disk(&self, x2: &EntryPoint) -> f32 {
        bssrdf::p_disk(&self.x1, &self.selection, x2.position, x2.geometric_normal)
    }

    /// Direction and radiance from x2 toward the light vertex of `y`; `None` for an unknown light
    /// or x3 = x2.
    pub fn light_path(&self, x2: Vec3, y: &SssSample) -> Option<LightPath> {
        let lights = &self.scene.lights;
        if y.light() as usize >= lights.len() {
            return None;
        }
        if let Light::Directional {
            direction,
            irradiance,
        } = *lights.get(y.light())
        {
            let wi = -direction;
            return Some(LightPath {
                wi,
                radiance: irradiance,
                shadow_target: x2 + DIRECTIONAL_DISTANCE * wi,
            });
        }
        let x3 = y.x3();
        let wi = (x3 - x2).try_normalize()?;
        let radiance = lights.radiance(y.light(), x3, x2);
        Some(LightPath {
            wi,
            radiance,
            shadow_target: x3,
        })
    }

    /// `f(ȳ) = S · max(0, n2·ωi) · L_e`, unshadowed, RGB (DESIGN §9); 0 outside the support.
    pub fn contribution(&self, y: &SssSample) -> Vec3 {
        match self.entry_point(y) {
            Some(x2) => self.contribution_at(&x2, y),
            None => Vec3::ZERO,
        }
    }

    /// [`SssDomain::contribution`] of `y` whose entry point `x2` the caller has located.
    pub fn contribution_at(&self, x2: &EntryPoint, y: &SssSample) -> Vec3 {
        self.contribution_lit(x2, self.light_path(x2.position, y))
    }

    /// `f` at x2 lit along `light` (`None`: no light path, `f = 0`).
    fn contribution_lit(&self, x2: &EntryPoint, light: Option<LightPath>) -> Vec3 {
        let Some(light) = light else {
            return Vec3::ZERO;
        };
        let f = bssrdf::contribution(&self.material, &self.x1, x2, light.wi, light.radiance);
        if f.is_finite() { f } else { Vec3::ZERO }
    }

    /// Whether the segment x2–x3 of `y` is unoccluded (the shadow test of the canonical sample
    /// and of delayed reconnection, DESIGN §9 "Visibility"). `false` outside the support.
    pub fn visible(&self, y: &SssSample) -> bool {
        self.segment(y)
            .is_some_and(|(x2, light)| self.unoccluded(&x2, &light))
    }

    /// [`SssDomain::visible`] for a sample that counts only where `f(y) > 0`: `None`, without
    /// the shadow ray, where `f(y) = 0` for want of light (no x2 or light path, `n2·ωi ≤ 0`, no
    /// emitted radiance: the test [`sss::bssrdf::contribution`] makes before the BSSRDF).
    pub fn visible_if_lit(&self, y: &SssSample) -> Option<bool> {
        let (x2, light) = self.segment(y)?;
        let lit = x2.shading_normal.dot(light.wi) > 0.0 && light.radiance != Vec3::ZERO;
        lit.then(|| self.unoccluded(&x2, &light))
    }

    /// x2 of `y` and the light path from it; `None` outside the support.
    fn segment(&self, y: &SssSample) -> Option<(EntryPoint, LightPath)> {
        let x2 = self.entry_point(y)?;
        let light = self.light_path(x2.position, y)?;
        Some((x2, light))
    }

    /// The shadow ray from x2 toward the light.
    fn unoccluded(&self, x2: &EntryPoint, light: &LightPath) -> bool {
        let n = x2.geometric_normal;
        let side = if n.dot(light.wi) < 0.0 { -1.0 } else { 1.0 };
        let from = x2.position + side * SHADOW_EPSILON * n;
        // Stop short of x3 too, so geometry a scene places on an emitter does not shadow it.
        let to = light.shadow_target - SHADOW_EPSILON * light.wi;
        !self
            .scene
            .geometry
            .occluded(&Ray::segment(Vec3A::from(from), Vec3A::from(to)))
    }

    /// The stream of a shift's random numbers used at this domain when it is paired with
    /// `partner` (key in [`SssDomain`]).
    pub(crate) fn shift_stream(&self, purpose: u32, partner: &SssDomain) -> Stream {
        let purpose = purpose | (partner.pixel & PARTNER_PIXEL_MASK);
        StreamKey::new(self.pixel, self.frame, self.pass, purpose).stream(self.seed)
    }
}

impl fmt::Debug for SssDomain<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("SssDomain")
            .field("scene", &self.scene.name)
            .field("pixel", &self.pixel)
            .field("frame", &self.frame)
            .field("pass", &self.pass)
            .field("x1", &self.x1.position)
            .field("object", &self.x1.object)
            .finish()
    }
}

impl Domain for SssDomain<'_> {
    type Sample = SssSample;

    /// `p̂` of the unshadowed `f` (DESIGN §9), luminance unless [`SssDomain::with_target`].
    fn target(&self, y: &SssSample) -> f32 {
        self.target.of(self.contribution(y)).max(0.0)
    }
}

impl SssDomain<'_> {
    /// [`Domain::target`] of `y` whose entry point `x2` the caller has located.
    pub fn target_at(&self, x2: &EntryPoint, y: &SssSample) -> f32 {
        self.target.of(self.contribution_at(x2, y)).max(0.0)
    }

    /// [`Domain::target`] of `y` from what [`SssDomain::locate`] found of it (in any domain of
    /// this scene): the same value, without locating `y` again.
    pub fn target_located(&self, located: &Located, y: &SssSample) -> f32 {
        let f = if y.object() == self.x1.object {
            self.contribution_lit(&located.x2, located.light)
        } else {
            Vec3::ZERO
        };
        self.target.of(f).max(0.0)
    }
}

/// Path-space coordinates for the conformance kit: x2's position and the stored x3 (6 numbers).
/// Round trips compare these, so a shift that re-draws the random numbers (probabilistic
/// inversion, [001 §4.2]) is checked on the path, not on its auxiliary random numbers.
/// A position does not name a triangle, so [`LocalCoords::sample_at_local`] cannot rebuild a sample
/// and returns `None`; the finite-difference Jacobian test uses a per-triangle chart instead
/// (`shifts/tests`).
impl LocalCoords for SssDomain<'_> {
    fn dim(&self) -> usize {
        6
    }

    /// NaN coordinates for a sample whose triangle does not exist.
    fn to_local(&self, x: &SssSample, out: &mut [f64]) {
        let geometry = &self.scene.geometry;
        if x.prim() >= geometry.triangle_count() {
            out.fill(f64::NAN);
            return;
        }
        let x2 = geometry.position(x.prim(), x.bary());
        for (o, v) in out
            .iter_mut()
            .zip(x2.to_array().into_iter().chain(x.x3().to_array()))
        {
            *o = v as f64;
        }
    }

    fn sample_at_local(&self, _coords: &[f64]) -> Option<SssSample> {
        None
    }
}
