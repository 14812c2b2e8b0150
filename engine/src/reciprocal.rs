//! Reciprocal neighbour selection for a spatial pass (`restir:<preset>/pairs=reciprocal`;
//! ReSTIR PT Enhanced, Lin, Kettunen, Wyman 2025): per neighbour slot, pixels are matched in
//! pairs that take each other, so each pair's two shifts are evaluated once and used by both.
//!
//! **What a neighbour costs.** With streaming (defensive) pairwise MIS (DESIGN §9) a receiver
//! `p` that takes neighbour `q` needs `T_{q→p}(x_q)` with `p̂_p(y_q)`, `J` and `p̂_q(x_q)` (its
//! forward shift and `m_q`), and `p̂_{←q}(y_p) = p̂_q(T_{p→q}(y_p)) · |T'_{p→q}|` (the back-shift
//! of its canonical sample in `m_p`). When `q` takes `p` in turn it needs the same two shifts
//! with their roles swapped. So a pass in two phases: [`shift_to_partners`] shifts every pixel's
//! sample into its partner of every slot ([`Shift::shifts_with_targets`], one shift per pixel
//! and slot instead of two), and [`combine`] resamples each pixel from the stored values
//! ([`resample_exchanged`]).
//!
//! **Pairs.** Slot `s` draws one offset `o` uniformly in the disk of the frame's mean radius
//! ([`frame_radius`]; pixel offsets `floor(o + ½)` like the independent pass's
//! `floor(centre + o)`) and a phase: [`Pairing::partner`] sends `p` to `p + o` or `p − o` by the
//! parity of its stripe along the offset's axis, an involution (`partner(partner(p)) = p`). A
//! pair is taken when the partner is in the image and shows the same translucent object
//! (a rule symmetric in both pixels); otherwise neither takes the other in that slot.
//!
//! **Unbiased.** Which pairs exist depends only on the seed, the frame, the pass and the
//! G-buffer, never on a reservoir, so each pixel's step is the GRIS estimator [001 Eq. 6] over
//! the domains it takes, with the pairwise weights of DESIGN §9, which sum to one for every `y`
//! over those domains and vanish where a shift fails. The stored values are the ones the shift
//! gives (a shift is deterministic given its two domains), so the step equals the independent
//! step over the same neighbours (`reciprocal_step_is_the_step_over_its_partners`); only the
//! choice of neighbours differs, and it selects domains without entering any weight (like the
//! disk radius, `RadiusRule`). The disk's radius is the frame's mean rather than each pixel's.

use glam::{IVec2, Vec2};
use rayon::prelude::*;
use restir::mis::{MAX_DOMAINS, MisScheme};
use restir::resample::{Exchange, ResampleError, resample_exchanged};
use restir::reservoir::{Reservoir, cap_confidence};
use restir::rng::StreamKey;
use restir::shift::{Domain, Evaluated, Fail, Shifted};
use shifts::preset::{RadiusRule, Shade};
use shifts::{ShiftKind, SssDomain, SssSample};
use sss::sampling::sample_uniform_disk;

use crate::purpose;
use crate::reuse::{Counted, PassInput, Reused, ShiftCounts, Step, max_d};

/// One slot's matching of the frame's pixels: the offset and the stripes that give its sign.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Pairing {
    /// `floor(o + ½)`, never zero.
    offset: IVec2,
    /// 0: stripes across x (`offset.x ≠ 0`); 1: across y.
    axis: usize,
    /// The stripes' phase, in `0..|offset[axis]|`.
    phase: i32,
}

impl Pairing {
    /// The pairing of neighbour slot `slot` of pass `pass` at `frame`: the offset uniform in the
    /// disk of `radius` pixels and the stripes' phase, from the stream
    /// `(slot, frame, pass, PAIRS)`. `None` when the offset rounds to zero (the slot is empty
    /// for every pixel, as an independent neighbour in the receiver's own pixel is skipped).
    pub fn draw(radius: f32, slot: u32, frame: u32, pass: u32, seed: u64) -> Option<Pairing> {
        let mut rng = StreamKey::new(slot, frame, pass, purpose::PAIRS).stream(seed);
        let o = sample_uniform_disk(radius, rng.next_f32(), rng.next_f32());
        let offset = (o + Vec2::splat(0.5)).floor().as_ivec2();
        let axis = if offset.x != 0 {
            0
        } else if offset.y != 0 {
            1
        } else {
            return None;
        };
        let stride = offset[axis].abs();
        let phase = ((rng.next_f32() * stride as f32) as i32).min(stride - 1);
        Some(Pairing {
            offset,
            axis,
            phase,
        })
    }

    /// The partner of pixel `p` (which may lie outside the image): `p + offset` where the
    /// stripe `floor((p[axis] + phase) / |offset[axis]|)` is even, `p − offset` where it is
    /// odd. Moving by `±offset` moves to the next or previous stripe, of the other parity, whose
    /// sign brings it back: `partner(partner(p)) = p`.
    pub fn partner(&self, p: IVec2) -> IVec2 {
        let stripe = (p[self.axis] + self.phase).div_euclid(self.offset[self.axis].abs());
        if stripe.rem_euclid(2) == 0 {
            p + self.offset
        } else {
            p - self.offset
        }
    }
}

/// The pairings of a pass's `slots` neighbour slots.
pub fn pairings(input: &PassInput, radius: f32, slots: u32) -> Vec<Option<Pairing>> {
    let frame = input.gbuffer.frame;
    (0..slots)
        .map(|slot| Pairing::draw(radius, slot, frame, input.pass, input.seed))
        .collect()
}

/// The domain of every pixel of the pass (`None` off translucent objects), built once per pass
/// and read by both phases: a pixel's domain is its partners' destination in every slot and
/// their receiver. Rows in parallel, collected in pixel order.
pub fn domains<'a>(input: &PassInput<'a>) -> Vec<Option<SssDomain<'a>>> {
    let (width, height) = (input.gbuffer.width, input.gbuffer.height);
    (0..height)
        .into_par_iter()
        .flat_map_iter(|row| (row * width..(row + 1) * width).map(|p| Some(input.domain(p)?.0)))
        .collect()
}

/// The mean of `rule`'s disk radius over the pixels that show a translucent object (`domains`;
/// 0 where none does): the frame-wide radius of the pairs' offsets. Summed in pixel order, so
/// it does not depend on the thread count.
pub fn frame_radius(input: &PassInput, domains: &[Option<SssDomain>], rule: RadiusRule) -> f32 {
    let camera = &input.scene.camera;
    let frame = input.gbuffer.frame;
    let (mut sum, mut count) = (0.0f64, 0u32);
    for domain in domains.iter().flatten() {
        let radius = rule.radius_px(camera, frame, domain.x1().position, max_d(domain));
        sum += f64::from(radius);
        count += 1;
    }
    if count == 0 {
        0.0
    } else {
        (sum / f64::from(count)) as f32
    }
}

/// What a pixel sent its partner of one slot.
#[derive(Clone, Copy, Debug, Default)]
pub enum Exchanged {
    /// No pair in this slot (the partner is outside the image, not translucent or another
    /// object, or the slot is empty).
    #[default]
    Untaken,
    /// A pair, and the pixel's reservoir has no sample with `W > 0`: nothing to shift.
    Unshifted,
    /// A pair, and the pixel's sample shifted into the partner failed.
    Failed(Fail),
    /// A pair, and the pixel's sample in the partner: `y`, `J`, `p̂_partner(y)`, `p̂_own(x)`.
    Sent {
        shifted: Shifted<SssSample>,
        target: f32,
        source_target: f32,
    },
}

/// The partner of `pixel` in `pairing`, if it lies inside the image.
fn partner_pixel(input: &PassInput, pairing: &Option<Pairing>, pixel: u32) -> Option<u32> {
    let (width, height) = (input.gbuffer.width as i32, input.gbuffer.height as i32);
    let p = IVec2::new(pixel as i32 % width, pixel as i32 / width);
    let q = pairing.as_ref()?.partner(p);
    let inside = q.x >= 0 && q.y >= 0 && q.x < width && q.y < height;
    inside.then_some((q.y * width + q.x) as u32)
}

/// The domain of `pixel`'s partner in `pairing`, if the pair is taken: inside the image and on
/// the same translucent object `object` as `pixel`. Symmetric in both pixels.
fn partner<'d, 'a>(
    input: &PassInput,
    domains: &'d [Option<SssDomain<'a>>],
    pairing: &Option<Pairing>,
    pixel: u32,
    object: u32,
) -> Option<&'d SssDomain<'a>> {
    let q = partner_pixel(input, pairing, pixel)?;
    domains[q as usize]
        .as_ref()
        .filter(|d| d.x1().object == object)
}

/// Phase 1 at `pixel`: its sample shifted into its partner of every slot (`out[s]`, one entry
/// per slot), with the shift `shift` of the pass; `domains` from [`domains`].
pub fn shift_to_partners(
    input: &PassInput,
    domains: &[Option<SssDomain>],
    pairings: &[Option<Pairing>],
    shift: ShiftKind,
    pixel: u32,
    out: &mut [Exchanged],
) {
    out.fill(Exchanged::Untaken);
    let Some(source) = &domains[pixel as usize] else {
        return;
    };
    let object = source.x1().object;
    let mut slots = [0; MAX_DOMAINS];
    let mut dsts = Vec::with_capacity(pairings.len());
    for (slot, pairing) in pairings.iter().enumerate() {
        if let Some(domain) = partner(input, domains, pairing, pixel, object) {
            out[slot] = Exchanged::Unshifted;
            slots[dsts.len()] = slot;
            dsts.push(domain);
        }
    }
    let stored = input.reservoirs[pixel as usize].get();
    let Some(x) = stored.y.filter(|_| stored.ucw > 0.0) else {
        return;
    };
    let mut sent = [Err(Fail::Rejected); MAX_DOMAINS];
    let sent = &mut sent[..dsts.len()];
    shift.with_shift(source.material(), |s| {
        s.shifts_with_targets(&x, source, &dsts, sent)
    });
    for (&slot, result) in slots.iter().zip(sent.iter()) {
        out[slot] = match *result {
            Ok(e) => Exchanged::Sent {
                shifted: e.shifted,
                target: e.target,
                source_target: e.source_target,
            },
            Err(fail) => Exchanged::Failed(fail),
        };
    }
}

/// The [`Exchange`] of one receiver: what its partners sent it (their forward shifts) and
/// `p̂_{←q}` of its canonical sample from what it sent them.
struct Received {
    forward: [Exchanged; MAX_DOMAINS],
    back: [f32; MAX_DOMAINS],
}

impl<'a> Exchange<SssDomain<'a>> for Received {
    fn forward(&self, i: usize, _x: &SssSample) -> Result<Evaluated<SssDomain<'a>>, Fail> {
        match self.forward[i - 1] {
            Exchanged::Sent {
                shifted,
                target,
                source_target,
            } => Ok(Evaluated {
                shifted,
                target,
                source_target,
            }),
            Exchanged::Failed(fail) => Err(fail),
            Exchanged::Untaken | Exchanged::Unshifted => Err(Fail::Rejected),
        }
    }

    /// Only the canonical sample's back-shifts are shared by the pairs; `Preset::validate`
    /// admits reciprocal pairs only with schemes that read no other (`needs_all_targets(i ≥ 1)`
    /// is false), so `i` is 0.
    fn back(&self, i: usize, _y: &SssSample, js: std::ops::Range<usize>, out: &mut [f32]) {
        debug_assert_eq!(
            i, 0,
            "a pairwise scheme reads only the canonical back-shifts"
        );
        out.copy_from_slice(&self.back[js.start - 1..js.end - 1]);
    }
}

/// `p̂_{←q}(y_p) = p̂_q(T_{p→q}(y_p)) · |T'_{p→q}(y_p)|` from what `p` sent `q` (DESIGN §9);
/// 0 where the shift failed.
fn back_target(sent: &Exchanged) -> f32 {
    match *sent {
        Exchanged::Sent {
            shifted, target, ..
        } => target * shifted.jacobian,
        _ => 0.0,
    }
}

/// The pass's parameters that phase 2 reads.
pub struct Combine<'d, 'a> {
    /// Every pixel's domain ([`domains`]).
    pub domains: &'d [Option<SssDomain<'a>>],
    pub pairings: &'d [Option<Pairing>],
    /// Phase 1's output: `slots` entries per pixel, in pixel order.
    pub exchanged: &'d [Exchanged],
    pub shift: ShiftKind,
    pub mis: &'d dyn MisScheme,
    pub cap: Option<f32>,
    pub shade: Shade,
}

/// Phase 2 at `pixel`: its canonical reservoir and the reservoirs of its partners (capped at
/// `cap` × its confidence when given), resampled with the stored shifts.
pub fn combine(input: &PassInput, pass: &Combine, pixel: u32) -> Result<Reused, ResampleError> {
    let stored = input.reservoirs[pixel as usize];
    let Some(receiver) = pass.domains[pixel as usize] else {
        return Ok(Reused {
            reservoir: stored,
            ..Reused::default()
        });
    };
    let canonical = stored.get();
    let slots = pass.pairings.len();
    let own = &pass.exchanged[pixel as usize * slots..][..slots];
    let mut received = Received {
        forward: [Exchanged::Untaken; MAX_DOMAINS],
        back: [0.0; MAX_DOMAINS],
    };
    let mut neighbours = [Reservoir::<SssSample>::empty(); MAX_DOMAINS];
    let mut taken = 0;
    for (slot, sent) in own.iter().enumerate() {
        if matches!(sent, Exchanged::Untaken) {
            continue;
        }
        // Phase 1 took the pair, so the partner is inside the image and on the same object.
        let Some(q) = partner_pixel(input, &pass.pairings[slot], pixel) else {
            continue;
        };
        let mut reservoir = input.reservoirs[q as usize].get();
        if let Some(cap) = pass.cap {
            reservoir.confidence = cap_confidence(reservoir.confidence, canonical.confidence, cap);
        }
        neighbours[taken] = reservoir;
        received.forward[taken] = pass.exchanged[q as usize * slots + slot];
        received.back[taken] = back_target(sent);
        taken += 1;
    }
    let step = Step {
        input,
        receiver,
        canonical,
        shift: pass.shift,
        mis: pass.mis,
        shade: pass.shade,
    };
    let counts = if input.collect_diagnostics {
        count(&step, &received.forward[..taken])
    } else {
        Counted::default()
    };
    let refs: Vec<&Reservoir<SssSample>> = neighbours[..taken].iter().collect();
    step.finish(counts, |receiver, rng, observe| {
        resample_exchanged(receiver, &refs, &received, pass.mis, rng, observe)
    })
}

/// The shift counters of a step from what its partners sent it: the shifts resampling used
/// (samples with `W > 0`; a failure where `p̂_dst = 0` may be reported by `shift_supported`'s
/// cheaper check, `Shift::shift_supported`), where the independent pass re-applies `shift` to
/// every sample.
fn count(step: &Step, forward: &[Exchanged]) -> Counted {
    let canonical_target = step.canonical.y.map_or(0.0, |y| step.receiver.target(&y));
    let mut counts = ShiftCounts::default();
    let mut failed_by = [0; Fail::ALL.len()];
    for sent in forward {
        match *sent {
            Exchanged::Sent { target, .. } => {
                counts.shifted += 1;
                counts.improved += (target > canonical_target) as u32;
            }
            Exchanged::Failed(fail) => {
                counts.shifted += 1;
                counts.failed += 1;
                failed_by[fail.code() as usize - 1] += 1;
            }
            Exchanged::Untaken | Exchanged::Unshifted => {}
        }
    }
    (counts, failed_by)
}

#[cfg(test)]
mod tests;
