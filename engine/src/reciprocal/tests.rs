use glam::IVec2;
use restir::mis::MisKind;
use shifts::preset::{RadiusRule, Shade};
use shifts::{PixelReservoir, ShiftKind, Target};
use sss::scene::{GBuffer, Scene};

use super::*;
use crate::reuse::tests::canonical;

/// Every pairing is an involution without fixed points that moves each pixel by its offset
/// (50 pairings, radii 1.5–40 px, on 96 × 96 pixels around and across the image's corner).
/// Control: the same offsets without the stripes (always `p + o`) are no involution.
#[test]
fn pairings_match_every_pixel_with_one_partner() {
    let mut drawn = 0;
    for slot in 0..50 {
        let radius = 1.5 + slot as f32 * 0.8;
        let Some(pairing) = Pairing::draw(radius, slot, 3, 2, 7) else {
            continue;
        };
        drawn += 1;
        assert!(pairing.offset.as_vec2().length() <= radius + 1.0);
        for y in -16..80 {
            for x in -16..80 {
                let p = IVec2::new(x, y);
                let q = pairing.partner(p);
                assert_ne!(q, p);
                assert_eq!((q - p).abs(), pairing.offset.abs());
                assert_eq!(pairing.partner(q), p, "{pairing:?} at {p}");
            }
        }
        let forward = |p: IVec2| p + pairing.offset;
        assert_ne!(forward(forward(IVec2::ZERO)), IVec2::ZERO, "control");
    }
    assert!(drawn >= 45, "{drawn} of 50 slots drawn");
}

/// The offsets are uniform in the disk: the fraction of N = 20 000 slots' offsets (radius
/// 1000 px, where rounding to pixels is negligible) inside half the radius is 1/4 (binomial z,
/// two-sided α = 1e-3). Control: the offsets' x component alone (`|o_x| < R/2`: 0.609) is
/// rejected as 1/4.
#[test]
fn offsets_are_uniform_in_the_disk() {
    let n = 20_000;
    let radius = 1000.0;
    let (mut inner, mut narrow) = (0u32, 0u32);
    for slot in 0..n {
        let pairing = Pairing::draw(radius, slot, 0, 1, 5).expect("a 1000 px disk");
        let o = pairing.offset.as_vec2();
        assert!(o.length() <= radius + 1.0);
        inner += (o.length() < 0.5 * radius) as u32;
        narrow += (o.x.abs() < 0.5 * radius) as u32;
    }
    let z = |k: u32| (k as f64 / n as f64 - 0.25) / (0.25f64 * 0.75 / n as f64).sqrt();
    assert!(
        z(inner).abs() < 3.2905,
        "α = 1e-3, N = {n}: z = {}",
        z(inner)
    );
    assert!(z(narrow).abs() > 3.2905, "control: z = {}", z(narrow));
}

fn scene(size: u32) -> Scene {
    let mut scene = Scene::builtin("bumpy").unwrap();
    scene.camera = scene.camera.with_resolution(size, size);
    scene
}

/// The reciprocal step at every pixel is the independent step ([`Step::run`], the shift
/// evaluated by the resampling itself) over the same partners, bit for bit, for every
/// registered shift family (reconnection, with its batched override; delayed and hybrid, which
/// trace rays; inverting, which draws numbers), with and without a spatial cap: sharing a pair's shifts changes no value. Also every pixel's pairs are mutual (it takes `q`
/// in slot `s` exactly when `q` takes it), and most translucent pixels take a partner.
/// Control: the same comparison with the stored back-shifts scaled by 1.01 differs.
#[test]
fn reciprocal_step_is_the_step_over_its_partners() {
    let scene = scene(24);
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
    let slots = 4;
    let domains = domains(&input);
    let radius = frame_radius(&input, &domains, RadiusRule::Clamped);
    assert!((5.0..=30.0).contains(&radius), "{radius}");
    let pairings = pairings(&input, radius, slots);
    let n = reservoirs.len();
    for (shift, cap) in [
        (ShiftKind::Reconnection, None),
        (ShiftKind::DelayedReconnection, Some(2.0)),
        (ShiftKind::Hybrid, None),
        (ShiftKind::InvertingExact, Some(1.0)),
    ] {
        let mut exchanged = vec![Exchanged::Untaken; n * slots as usize];
        for (pixel, out) in exchanged.chunks_mut(slots as usize).enumerate() {
            shift_to_partners(&input, &domains, &pairings, shift, pixel as u32, out);
        }
        let mis = MisKind::DefensivePairwise.scheme();
        let pass = Combine {
            domains: &domains,
            pairings: &pairings,
            exchanged: &exchanged,
            shift,
            mis,
            cap,
            shade: Shade::AllInputs,
        };
        let (mut translucent, mut paired, mut moved) = (0, 0, 0);
        for pixel in 0..n as u32 {
            let got = combine(&input, &pass, pixel).unwrap();
            let Some((receiver, g)) = input.domain(pixel) else {
                assert_eq!(got.reservoir, reservoirs[pixel as usize]);
                continue;
            };
            translucent += 1;
            let canonical = reservoirs[pixel as usize].get();
            let mut taken = Vec::new();
            for (slot, pairing) in pairings.iter().enumerate() {
                let entry = exchanged[pixel as usize * slots as usize + slot];
                let Some(domain) = partner(&input, &domains, pairing, pixel, g.object) else {
                    assert!(matches!(entry, Exchanged::Untaken));
                    continue;
                };
                let q = domain.pixel() as usize;
                let back = exchanged[q * slots as usize + slot];
                assert!(!matches!(entry, Exchanged::Untaken));
                assert!(!matches!(back, Exchanged::Untaken), "pair {pixel}–{q}");
                let mut reservoir = reservoirs[q].get();
                if let Some(cap) = cap {
                    reservoir.confidence =
                        cap_confidence(reservoir.confidence, canonical.confidence, cap);
                }
                taken.push((*domain, reservoir));
            }
            paired += !taken.is_empty() as u32;
            let step = Step {
                input: &input,
                receiver,
                canonical,
                shift,
                mis,
                shade: Shade::AllInputs,
            };
            let want = step.run(&taken).unwrap();
            assert_eq!(got, want, "{} at pixel {pixel}", shift.name());
            moved += (got.reservoir.y != reservoirs[pixel as usize].y) as u32;
        }
        println!(
            "{}: {translucent} translucent pixels, {paired} paired, {moved} took a partner's sample",
            shift.name()
        );
        assert!(paired * 10 > translucent * 9, "{paired} of {translucent}");
        assert!(moved > 20, "{moved}");
        let mut skewed = exchanged.clone();
        for e in &mut skewed {
            if let Exchanged::Sent { target, .. } = e {
                *target *= 1.01;
            }
        }
        let control = Combine {
            exchanged: &skewed,
            ..pass
        };
        let differs = (0..n as u32).any(|pixel| {
            combine(&input, &control, pixel).unwrap() != combine(&input, &pass, pixel).unwrap()
        });
        assert!(differs, "control: {}", shift.name());
    }
}

/// A pixel without a translucent primary hit keeps its reservoir and takes no pair.
#[test]
fn opaque_pixels_take_no_pair() {
    let scene = scene(16);
    let gbuffer = GBuffer::render(&scene, 0);
    let reservoirs = vec![PixelReservoir::empty(); gbuffer.pixels.len()];
    let input = PassInput {
        scene: &scene,
        gbuffer: &gbuffer,
        reservoirs: &reservoirs,
        pass: 1,
        seed: 0,
        collect_diagnostics: false,
        target: Target::Luminance,
    };
    let pairings = pairings(&input, 6.0, 2);
    let domains = domains(&input);
    let opaque = (0..reservoirs.len() as u32)
        .find(|&p| input.domain(p).is_none())
        .expect("the floor");
    let mut out = [Exchanged::Sent {
        shifted: Shifted {
            y: PixelReservoir::empty().y,
            jacobian: 1.0,
        },
        target: 1.0,
        source_target: 1.0,
    }; 2];
    shift_to_partners(
        &input,
        &domains,
        &pairings,
        ShiftKind::Hybrid,
        opaque,
        &mut out,
    );
    assert!(out.iter().all(|e| matches!(e, Exchanged::Untaken)));
}
