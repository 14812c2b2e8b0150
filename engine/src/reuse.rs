//! The reuse passes as pure per-pixel kernels (DESIGN §6, §9): temporal reuse of the previous
//! frame's final reservoir at the reprojected pixel (GBH over two reservoirs), and spatial reuse
//! of k neighbours in a disk (streaming defensive pairwise MIS). Each kernel reads the previous
//! buffers and returns the pixel's new reservoir; it draws every random number from streams keyed
//! by the receiving pixel, so the result does not depend on scheduling.

use bytemuck::Zeroable;
use glam::{Vec2, Vec3};
use restir::mis::{MAX_DOMAINS, MisScheme};
use restir::resample::{Observed, ResampleError, Source, resample_observed};
use restir::reservoir::{Reservoir, cap_confidence};
use restir::rng::{Stream, StreamKey};
use restir::shift::{Domain, Fail, Shift};
use shifts::{SssDomain, SssSample, Target, resolve_deferred_index};
use sss::sampling::sample_uniform_disk;
use sss::scene::{GBuffer, GPixel, Scene};

use crate::purpose;
use shifts::PixelReservoir;
use shifts::ShiftKind;
use shifts::preset::{Pairs, PassSpec, RadiusRule, Shade};

/// Reprojection checks of temporal reuse ([`GBuffer::reproject`]).
pub use sss::scene::{
    REPROJECTION_DEPTH_TOLERANCE as TEMPORAL_DEPTH_TOLERANCE,
    REPROJECTION_NORMAL_COSINE as TEMPORAL_NORMAL_COSINE,
};

/// Counters of one pixel in one reuse pass (the shift diagnostics, only when collected).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ShiftCounts {
    /// Neighbour samples the shift was applied to.
    pub shifted: u32,
    /// Of these, how many failed.
    pub failed: u32,
    /// Of the successful ones, how many have `p̂_r(T(x)) > p̂_r(canonical)` [001 Fig. 5].
    pub improved: u32,
}

/// What the reuse telemetry records of one pixel in one reuse pass
/// ([`crate::diagnostics::Telemetry`]); observing draws no random number.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StepTelemetry {
    /// The input the pass selected: 0 the pixel's own reservoir, `i` neighbour `i − 1`; `None`
    /// when nothing was selected or the pass left the reservoir unchanged.
    pub selected: Option<usize>,
    /// The MIS weight `m_0(y_0)` of the pixel's own sample, when it had a positive weight.
    pub canonical_mis: Option<f32>,
    /// Failed shifts by [`Fail`] kind (index `code − 1`), only when diagnostics are collected.
    pub failed_by: [u32; Fail::ALL.len()],
}

/// One pixel's output of a reuse pass.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Reused {
    pub reservoir: PixelReservoir,
    pub shifts: ShiftCounts,
    pub telemetry: StepTelemetry,
    /// For [`Shade::AllInputs`], the step's Rao-Blackwellised value `Σ_i f(y_i)·m_i·W_i·J_i`
    /// over its inputs (`restir::resample::resample_observed`); `None` for [`Shade::Selected`]
    /// and where the pass left the reservoir unchanged.
    pub rao_blackwellised: Option<Vec3>,
}

impl Reused {
    /// The reservoir passed on unchanged.
    fn unchanged(reservoir: PixelReservoir) -> Reused {
        Reused {
            reservoir,
            ..Reused::default()
        }
    }
}

/// The frame one reuse pass works on.
pub struct PassInput<'a> {
    pub scene: &'a Scene,
    pub gbuffer: &'a GBuffer,
    /// The reservoirs written by the previous pass of this frame.
    pub reservoirs: &'a [PixelReservoir],
    /// Index of the pass in its preset (the `pass` of every stream key).
    pub pass: u32,
    pub seed: u64,
    pub collect_diagnostics: bool,
    /// The preset's target function `p̂` of every domain of the pass.
    pub target: Target,
}

impl<'a> PassInput<'a> {
    /// The domain of `pixel` in this pass's frame, `None` off translucent objects.
    pub fn domain(&self, pixel: u32) -> Option<(SssDomain<'a>, &'a GPixel)> {
        let g = self.gbuffer.pixels[pixel as usize].as_ref()?;
        Some((self.domain_at(pixel, g)?, g))
    }

    /// [`PassInput::domain`] of `pixel` from its G-buffer pixel `g`, read by the caller.
    pub fn domain_at(&self, pixel: u32, g: &GPixel) -> Option<SssDomain<'a>> {
        let domain = SssDomain::new(
            self.scene,
            g,
            pixel,
            self.gbuffer.frame,
            self.pass,
            self.seed,
        )?;
        Some(domain.with_target(self.target))
    }
}

/// The previous frame, for temporal reuse.
pub struct Previous<'a> {
    /// The scene posed at the previous frame (`Scene::at_frame`): where objects move, the
    /// history's domains and the MIS back-shifts into them are evaluated there.
    pub scene: &'a Scene,
    pub gbuffer: &'a GBuffer,
    /// The previous frame's final reservoirs.
    pub reservoirs: &'a [PixelReservoir],
    /// With `restir:<preset>/duplication=divides`, the previous frame's duplication map
    /// (`crate::duplication::sharing` of `reservoirs`), which divides a history's confidence.
    pub sharing: Option<&'a [u32]>,
}

/// A reuse step's shared tail: resample, resolve a deferred index, collect diagnostics, sum the
/// Rao-Blackwellised value for [`Shade::AllInputs`].
pub(crate) struct Step<'d, 'a> {
    pub(crate) input: &'d PassInput<'a>,
    pub(crate) receiver: SssDomain<'a>,
    pub(crate) canonical: Reservoir<SssSample>,
    pub(crate) shift: ShiftKind,
    pub(crate) mis: &'d dyn MisScheme,
    pub(crate) shade: Shade,
}

/// A step's shift counters and failures by [`Fail`] kind (zero unless diagnostics are collected).
pub(crate) type Counted = (ShiftCounts, [u32; Fail::ALL.len()]);

impl<'a> Step<'_, 'a> {
    pub(crate) fn run(
        &self,
        neighbours: &[(SssDomain<'a>, Reservoir<SssSample>)],
    ) -> Result<Reused, ResampleError> {
        let sources: Vec<Source<'_, SssDomain<'a>>> = neighbours
            .iter()
            .map(|(domain, reservoir)| Source { domain, reservoir })
            .collect();
        self.shift.with_shift(self.receiver.material(), |shift| {
            let counts = if self.input.collect_diagnostics {
                self.count_shifts(shift, neighbours)
            } else {
                Counted::default()
            };
            self.finish(counts, |receiver, rng, observe| {
                resample_observed(receiver, &sources, shift, self.mis, rng, observe)
            })
        })
    }

    /// The step with its resampling given by `resample(receiver, rng, observe)` (the canonical
    /// reservoir in the receiver, the selection stream, the observer of the inputs), and the
    /// shift counters `counts`.
    pub(crate) fn finish(
        &self,
        counts: Counted,
        resample: impl FnOnce(
            Source<'_, SssDomain<'a>>,
            &mut Stream,
            &mut dyn FnMut(Observed<'_, SssSample>),
        ) -> Result<Reservoir<SssSample>, ResampleError>,
    ) -> Result<Reused, ResampleError> {
        let receiver = &self.receiver;
        let all_inputs = self.shade == Shade::AllInputs;
        let mut sum = Vec3::ZERO;
        let mut telemetry = StepTelemetry::default();
        let mut observe = |o: Observed<'_, SssSample>| {
            // Σ_i f(y_i) · m_i W_i J_i = E[f(Y)·W | inputs]   [001 Eq. 6]
            if all_inputs {
                sum += receiver.contribution(o.y) * o.factor;
            }
            if o.selected {
                telemetry.selected = Some(o.source);
            }
            if o.source == 0 {
                telemetry.canonical_mis = Some(o.mis_weight);
            }
        };
        let mut rng = StreamKey::new(
            receiver.pixel(),
            receiver.frame(),
            self.input.pass,
            purpose::SELECT,
        )
        .stream(self.input.seed);
        let canonical = Source {
            domain: receiver,
            reservoir: &self.canonical,
        };
        let mut out = resample(canonical, &mut rng, &mut observe)?;
        if self.shift.resolves_deferred_index()
            && let Some(y) = &mut out.y
        {
            resolve_deferred_index(receiver, y);
        }
        let (shifts, failed_by) = counts;
        if out.y.is_none() {
            telemetry.selected = None;
        }
        Ok(Reused {
            reservoir: PixelReservoir::from(&out),
            shifts,
            telemetry: StepTelemetry {
                failed_by,
                ..telemetry
            },
            rao_blackwellised: all_inputs.then_some(sum),
        })
    }

    /// Re-applies the shift to each neighbour sample to count failures (also by [`Fail`] kind)
    /// and improvements (only when diagnostics are collected; the resampling itself is not
    /// affected).
    fn count_shifts(
        &self,
        shift: &dyn for<'s> Shift<SssDomain<'s>>,
        neighbours: &[(SssDomain<'a>, Reservoir<SssSample>)],
    ) -> Counted {
        let canonical_target = self.canonical.y.map_or(0.0, |y| self.receiver.target(&y));
        let mut counts = ShiftCounts::default();
        let mut failed_by = [0; Fail::ALL.len()];
        for (domain, reservoir) in neighbours {
            let Some(x) = &reservoir.y else { continue };
            counts.shifted += 1;
            match shift.shift(x, domain, &self.receiver) {
                Ok(s) => counts.improved += (self.receiver.target(&s.y) > canonical_target) as u32,
                Err(fail) => {
                    counts.failed += 1;
                    failed_by[fail.code() as usize - 1] += 1;
                }
            }
        }
        (counts, failed_by)
    }
}

/// Temporal reuse of `pixel` [001 §5.1]: reproject x1 into the previous frame
/// (`floor(Camera::project(frame − 1, x1))`), accept the previous pixel if it shows the same
/// object at a similar depth and normal, cap its confidence at `cap` × the current one, and
/// combine the two reservoirs with `mis` (GBH in the presets, DESIGN §9 temporal formulas).
/// Without a previous frame or an accepted pixel the canonical reservoir passes unchanged.
pub fn temporal(
    input: &PassInput,
    previous: Option<&Previous>,
    pixel: u32,
    shift: ShiftKind,
    mis: &dyn MisScheme,
    cap: f32,
    shade: Shade,
) -> Result<Reused, ResampleError> {
    let stored = input.reservoirs[pixel as usize];
    let Some((receiver, g)) = input.domain(pixel) else {
        return Ok(Reused::unchanged(stored));
    };
    let canonical = stored.get();
    let history = previous.and_then(|prev| {
        let q = prev.gbuffer.reproject(&input.scene.camera, g)?;
        let g_prev = prev.gbuffer.pixels[q as usize].as_ref()?;
        let frame = prev.gbuffer.frame;
        let domain = SssDomain::new(prev.scene, g_prev, q, frame, input.pass, input.seed)?
            .with_target(input.target);
        let mut reservoir = prev.reservoirs[q as usize].get();
        reservoir.confidence = cap_confidence(reservoir.confidence, canonical.confidence, cap);
        // The duplication map [PTE]: a history held by k pixels counts 1/k.
        if let Some(sharing) = prev.sharing {
            reservoir.confidence /= sharing[q as usize].max(1) as f32;
        }
        Some((domain, reservoir))
    });
    let Some(history) = history else {
        return Ok(Reused::unchanged(stored));
    };
    let step = Step {
        input,
        receiver,
        canonical,
        shift,
        mis,
        shade,
    };
    step.run(&[history])
}

/// Spatial reuse of `pixel`: `neighbours` pixels drawn uniformly in the disk of radius
/// `R = radius.radius_px(camera, frame, x1, max d)` around the pixel centre (DESIGN §9). A
/// neighbour outside the image, equal to the pixel, without a primary hit or on another object
/// is not taken (a rule symmetric in both pixels), so the MIS sees only the `v` neighbours taken.
/// Each neighbour's confidence is capped at `cap` × the receiver's when given.
pub fn spatial(
    input: &PassInput,
    pixel: u32,
    shift: ShiftKind,
    mis: &dyn MisScheme,
    neighbours: u32,
    cap: Option<f32>,
    radius: RadiusRule,
    shade: Shade,
) -> Result<Reused, ResampleError> {
    let stored = input.reservoirs[pixel as usize];
    let Some((receiver, g)) = input.domain(pixel) else {
        return Ok(Reused::unchanged(stored));
    };
    let canonical = stored.get();
    let (width, height) = (input.gbuffer.width, input.gbuffer.height);
    let frame = input.gbuffer.frame;
    let radius = radius.radius_px(&input.scene.camera, frame, g.position, max_d(&receiver));
    let centre = Vec2::new((pixel % width) as f32 + 0.5, (pixel / width) as f32 + 0.5);
    let mut rng = StreamKey::new(pixel, frame, input.pass, purpose::NEIGHBOURS).stream(input.seed);
    // The neighbours' G-buffer pixels and reservoirs are read first and their domains built
    // after: the reads of different neighbours do not depend on each other, so the CPU overlaps
    // their cache misses (a 512² frame's buffers far exceed the caches), which building a
    // domain between two reads would serialise. Same neighbours, same order.
    let mut gathered = [(0, None, PixelReservoir::zeroed()); MAX_DOMAINS];
    let mut count = 0;
    for _ in 0..neighbours {
        let offset = sample_uniform_disk(radius, rng.next_f32(), rng.next_f32());
        let q = centre + offset;
        if !(q.x >= 0.0 && q.y >= 0.0 && q.x < width as f32 && q.y < height as f32) {
            continue;
        }
        let q = q.y as u32 * width + q.x as u32;
        if q == pixel || count == MAX_DOMAINS {
            continue;
        }
        let (g_q, reservoir) = (
            input.gbuffer.pixels[q as usize],
            input.reservoirs[q as usize],
        );
        gathered[count] = (q, g_q, reservoir);
        count += 1;
    }
    let mut taken = Vec::with_capacity(count);
    for (q, g_q, stored) in &gathered[..count] {
        let Some(g_q) = g_q else {
            continue;
        };
        let Some(domain) = input.domain_at(*q, g_q) else {
            continue;
        };
        if g_q.object != g.object {
            continue;
        }
        let mut reservoir = stored.get();
        if let Some(cap) = cap {
            reservoir.confidence = cap_confidence(reservoir.confidence, canonical.confidence, cap);
        }
        taken.push((domain, reservoir));
    }
    let step = Step {
        input,
        receiver,
        canonical,
        shift,
        mis,
        shade,
    };
    step.run(&taken)
}

/// `max_c d_c` of the receiver's material.
pub(crate) fn max_d(domain: &SssDomain) -> f32 {
    domain.material().d().max_element()
}

/// The reuse pass `spec` at `pixel`: [`temporal`] or [`spatial`] with the pass's shift, MIS
/// scheme, neighbours and cap, and the preset's `shade`; `None` for candidate generation, which
/// is not a reuse pass, and for a spatial pass with reciprocal pairs, which is not a per-pixel
/// kernel (`crate::reciprocal`).
pub fn pass(
    input: &PassInput,
    previous: Option<&Previous>,
    pixel: u32,
    spec: &PassSpec,
    shade: Shade,
) -> Option<Result<Reused, ResampleError>> {
    Some(match *spec {
        PassSpec::Candidates { .. }
        | PassSpec::Spatial {
            pairs: Pairs::Reciprocal,
            ..
        } => return None,
        PassSpec::Temporal {
            shift,
            mis,
            confidence_cap,
        } => temporal(
            input,
            previous,
            pixel,
            shift,
            mis.scheme(),
            confidence_cap,
            shade,
        ),
        PassSpec::Spatial {
            shift,
            mis,
            neighbours,
            confidence_cap,
            radius,
            pairs: Pairs::Independent,
        } => spatial(
            input,
            pixel,
            shift,
            mis.scheme(),
            neighbours,
            confidence_cap,
            radius,
            shade,
        ),
    })
}

/// The shaded value `f(Y) · W` of a final reservoir (no ray: visibility is already in `W`).
pub fn shade(domain: &SssDomain, reservoir: &PixelReservoir) -> Vec3 {
    let r = reservoir.get();
    r.y.map_or(Vec3::ZERO, |y| domain.contribution(&y) * r.ucw)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::candidates;
    use restir::mis::MisKind;

    fn scene(name: &str, size: u32) -> Scene {
        let mut scene = Scene::builtin(name).unwrap();
        scene.camera = scene.camera.with_resolution(size, size);
        scene
    }

    /// Canonical reservoirs of every pixel of `gbuffer` (candidates pass 0, shadow-tested).
    pub(crate) fn canonical(scene: &Scene, gbuffer: &GBuffer, seed: u64) -> Vec<PixelReservoir> {
        let input = PassInput {
            scene,
            gbuffer,
            reservoirs: &[],
            pass: 0,
            seed,
            collect_diagnostics: false,
            target: Target::Luminance,
        };
        (0..gbuffer.pixels.len() as u32)
            .map(|pixel| {
                let Some((domain, _)) = input.domain(pixel) else {
                    return PixelReservoir::empty();
                };
                let (mut r, _) =
                    candidates::generate(&domain, 1, true, seed, &mut Vec::new()).unwrap();
                candidates::shadow_test(&domain, &mut r);
                PixelReservoir::from(&r)
            })
            .collect()
    }

    /// A spatial pass with the deferred policy resolves the index of its selected sample:
    /// none of the selected shifted samples is left unknown where the chord finds x2 again.
    /// Control: the same shift's raw output (what the pass would keep without resolving) has
    /// every index unknown.
    #[test]
    fn deferred_index_is_resolved_for_the_selected_sample() {
        let scene = scene("bumpy", 24);
        let gbuffer = GBuffer::render(&scene, 0);
        let reservoirs = canonical(&scene, &gbuffer, 4);
        let input = PassInput {
            scene: &scene,
            gbuffer: &gbuffer,
            reservoirs: &reservoirs,
            pass: 1,
            seed: 4,
            collect_diagnostics: false,
            target: Target::Luminance,
        };
        let shift = ShiftKind::InvertingDeferred;
        let (mut moved, mut unknown, mut raw_unknown) = (0, 0, 0);
        for pixel in 0..reservoirs.len() as u32 {
            let Some((receiver, _)) = input.domain(pixel) else {
                continue;
            };
            let out = spatial(
                &input,
                pixel,
                shift,
                MisKind::DefensivePairwise.scheme(),
                4,
                None,
                RadiusRule::Clamped,
                Shade::Selected,
            )
            .unwrap()
            .reservoir;
            let Some(y) = out.get().y else { continue };
            if out.y == reservoirs[pixel as usize].y {
                continue;
            }
            moved += 1;
            unknown += y.index().is_none() as u32;
            let src = reservoirs.iter().position(|r| {
                r.has_sample != 0
                    && r.y.prim() == y.prim()
                    && r.y.bary() == y.bary()
                    && r.y.x3() == y.x3()
            });
            let src = src.unwrap() as u32;
            let (src_domain, _) = input.domain(src).unwrap();
            let raw = shift.with_shift(receiver.material(), |s| {
                s.shift(&reservoirs[src as usize].y, &src_domain, &receiver)
                    .unwrap()
            });
            raw_unknown += raw.y.index().is_none() as u32;
        }
        println!(
            "deferred: {moved} moved samples, {unknown} unknown after the pass, {raw_unknown} raw"
        );
        assert!(moved > 20, "only {moved} pixels took a neighbour's sample");
        assert_eq!(unknown, 0);
        assert_eq!(
            raw_unknown, moved,
            "control: the shift itself leaves the index unknown"
        );
    }

    /// Reprojection finds the previous frame's pixel that shows x1: seen from frame 0, that
    /// pixel's primary hit and x1 fall in the same pixel (closer than √2 px; a swapped row and
    /// column or an off-by-one index breaks this), and most translucent pixels are accepted.
    #[test]
    fn reprojection_finds_the_same_surface_point() {
        let scene = scene("bumpy", 32);
        let (now, before) = (GBuffer::render(&scene, 1), GBuffer::render(&scene, 0));
        let (mut accepted, mut translucent) = (0, 0);
        for (pixel, g) in now.pixels.iter().enumerate() {
            let Some(g) = g else { continue };
            if SssDomain::new(&scene, g, pixel as u32, 1, 0, 0).is_none() {
                continue;
            }
            translucent += 1;
            let Some(q) = before.reproject(&scene.camera, g) else {
                continue;
            };
            accepted += 1;
            let seen = |p: Vec3| scene.camera.project(0, p).unwrap();
            let hit_q = before.pixels[q as usize].unwrap().position;
            let miss = (seen(hit_q) - seen(g.position)).length();
            assert!(
                miss < std::f32::consts::SQRT_2,
                "pixel {pixel} → {q}: {miss} px apart"
            );
        }
        assert!(
            accepted * 10 > translucent * 8,
            "{accepted} of {translucent} accepted"
        );
    }

    /// Uniformity of the neighbour disk: the fraction of N = 20 000 points inside radius R/2
    /// is 1/4 (binomial z, two-sided α = 1e-3); the control `r = R·u` puts 1/2 there and is
    /// rejected.
    #[test]
    fn neighbour_disk_is_uniform() {
        let n = 20_000;
        let mut rng = StreamKey::new(0, 0, 0, purpose::NEIGHBOURS).stream(5);
        let (mut inner, mut inner_linear) = (0u32, 0u32);
        for _ in 0..n {
            let (u, v) = (rng.next_f32(), rng.next_f32());
            let p = sample_uniform_disk(10.0, u, v);
            assert!(p.length() <= 10.0);
            inner += (p.length() < 5.0) as u32;
            inner_linear += (10.0 * u < 5.0) as u32;
        }
        let z = |k: u32| (k as f64 / n as f64 - 0.25) / (0.25f64 * 0.75 / n as f64).sqrt();
        assert!(
            z(inner).abs() < 3.2905,
            "α = 1e-3, N = {n}: z = {}",
            z(inner)
        );
        assert!(
            z(inner_linear).abs() > 3.2905,
            "control: z = {}",
            z(inner_linear)
        );
    }
}
