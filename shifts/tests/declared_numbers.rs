//! Every registered shift does with stored random numbers what its type declares
//! (`shifts::numbers`): on spatial and temporal pairs of two built-in scenes, each shifted sample
//! that moved to another x1 is classified by what it carries (the source's numbers and x2: kept;
//! the source's numbers and another x2: replayed; other numbers: inverted) and its path must lie
//! in a region the declaration gives that effect (kept: the output at the destination; replayed:
//! the input at the source). The negative control, the hybrid that skips the offset path's
//! test, keeps numbers outside its declared region and is caught.

mod common;

use common::{SCENES, SEED, UNSHADOWED, fixture};
use restir::rng::StreamKey;
use restir::shift::CandidateSampler;
use shifts::numbers::{Effect, Numbers};
use shifts::{ShiftKind, SssDomain, SssSample};

const PAIRS: usize = 24;
const POINTS: usize = 32;

/// Whether the declaration gives `effect` to the path `(x1 of domain, x2 of sample)`.
fn declared(numbers: Numbers, effect: Effect, domain: &SssDomain, sample: &SssSample) -> bool {
    let Some(x2) = domain.entry_point(sample) else {
        return false;
    };
    let x1 = domain.x1();
    let distance = (x2.position - x1.position).length() / domain.material().d().max_element();
    let cosine = x1.frame.n.dot(x2.geometric_normal);
    numbers
        .0
        .iter()
        .any(|o| o.effect == effect && o.paths.contains(distance, cosine))
}

/// The outcomes of `kind` outside its declaration, e.g. `kept at the destination, x2 at …`, and
/// how many moved samples were classified.
fn violations(kind: ShiftKind) -> (Vec<String>, usize) {
    let numbers = kind.numbers();
    let mut found = Vec::new();
    let mut moved = 0;
    for scene in SCENES {
        let fx = fixture(scene);
        for (pairs, purpose) in [
            (fx.spatial_pairs(PAIRS, 11), 11),
            (fx.temporal_pairs(PAIRS, 12), 12),
        ] {
            let mut rng = StreamKey::new(0, 0, 0, purpose).stream(SEED);
            for (src, dst) in &pairs {
                if src.x1().position == dst.x1().position {
                    continue;
                }
                for _ in 0..POINTS {
                    let Some((x, _)) = UNSHADOWED.sample(src, &mut rng) else {
                        continue;
                    };
                    let Ok(shifted) = kind.with_shift(dst.material(), |s| s.shift(&x, src, dst))
                    else {
                        continue;
                    };
                    let (a, b) = (x.bssrdf().unwrap(), shifted.y.bssrdf().unwrap());
                    let same_numbers = (a.u_radius, a.u_angle, a.technique)
                        == (b.u_radius, b.u_angle, b.technique);
                    let same_x2 = (a.prim, a.bary) == (b.prim, b.bary);
                    moved += 1;
                    let (effect, ok) = match (same_numbers, same_x2) {
                        (true, true) => ("kept", declared(numbers, Effect::Kept, dst, &shifted.y)),
                        (true, false) => ("replayed", declared(numbers, Effect::Replayed, src, &x)),
                        (false, _) => (
                            "inverted",
                            numbers.0.iter().any(|o| o.effect == Effect::Inverted),
                        ),
                    };
                    if !ok {
                        found.push(format!("{scene}: {effect}, not declared ({numbers})"));
                    }
                }
            }
        }
    }
    (found, moved)
}

#[test]
fn every_registered_shift_does_what_it_declares() {
    for kind in ShiftKind::ALL {
        if kind == ShiftKind::HybridIgnoringCriterion {
            continue;
        }
        let (found, moved) = violations(kind);
        assert!(moved > 0, "{}: no sample moved", kind.name());
        assert!(found.is_empty(), "{}: {found:#?}", kind.name());
    }
}

#[test]
fn the_hybrid_ignoring_its_criterion_keeps_numbers_it_does_not_declare() {
    let (found, _) = violations(ShiftKind::HybridIgnoringCriterion);
    assert!(found.iter().any(|v| v.contains("kept")), "{found:#?}");
}
