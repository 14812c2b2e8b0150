//! What a shift declares it does with the BSSRDF random numbers `(u_radius, u_angle, technique)`
//! a sample stores [001 §3.2.2, §4.3], and the rule derived from those declarations alone:
//! which pass may replay them.
//!
//! Delayed reconnection replays a sample's numbers at the receiver's x1 [001 Eq. 11], which is
//! unbiased only if they are the numbers of the x1 of the pixel the sample sits in. Each shift
//! declares, per outcome, what its output's numbers are ([`Effect`]) and on which paths that
//! outcome can happen ([`Region`], in the terms `‖x2 − x1‖ / max d` and `n1·n2` that the SSS
//! shifts' criteria use). A pass replays numbers an earlier pass may have left foreign exactly
//! when a region where the later shift replays meets a region where the earlier one keeps the
//! source's numbers while moving the sample ([`Numbers::replays_foreign_of`]); no shift kind and
//! no shift's criterion is named by the rule.

use std::fmt;
use std::ops::{Bound, RangeBounds};

/// A shift's declaration, given by its type (`impl DeclaresNumbers for MyShift`).
pub trait DeclaresNumbers {
    const NUMBERS: Numbers;
}

/// The outcomes of a shift that move a sample, each with what it does to the stored numbers.
/// Outcomes not listed (failure, a shift onto the same pixel) leave no sample to replay.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Numbers(pub &'static [Outcome]);

/// One outcome: the numbers of its output, and a region containing every path it happens on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Outcome {
    pub effect: Effect,
    /// For [`Effect::Kept`] the output path at the destination (where the kept numbers then
    /// sit); for [`Effect::Replayed`] the input path at the source (where they are read); unused
    /// for [`Effect::Inverted`].
    pub paths: Region,
}

/// What an outcome's output carries as stored numbers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Effect {
    /// The source's numbers, unchanged (reconnection): drawn at another pixel's x1 once the
    /// sample has moved, so foreign at the destination.
    Kept,
    /// Replayed at the destination (delayed reconnection): they must be the source's, and are
    /// the destination's afterwards.
    Replayed,
    /// Re-derived for the destination (probabilistic inversion [001 Alg. 4]): the destination's.
    Inverted,
}

/// A set of paths `[x0, x1, x2, x3]` as a union of [`Cell`]s over `‖x2 − x1‖ / max d` (max d of
/// the receiver's material) and `n1·n2` (the geometric normals at x1 and x2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Region(pub &'static [Cell]);

/// A box of a [`Region`]: both coordinates in their intervals.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cell {
    pub distance: Interval,
    pub cosine: Interval,
}

/// An interval of the real line; either end open, closed or unbounded.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interval(pub Bound<f32>, pub Bound<f32>);

impl Interval {
    pub const ALL: Interval = Interval(Bound::Unbounded, Bound::Unbounded);

    /// `[k, ∞)`.
    pub const fn at_least(k: f32) -> Interval {
        Interval(Bound::Included(k), Bound::Unbounded)
    }

    /// `(k, ∞)`.
    pub const fn above(k: f32) -> Interval {
        Interval(Bound::Excluded(k), Bound::Unbounded)
    }

    /// `(−∞, k]`.
    pub const fn at_most(k: f32) -> Interval {
        Interval(Bound::Unbounded, Bound::Included(k))
    }

    /// `(−∞, k)`.
    pub const fn below(k: f32) -> Interval {
        Interval(Bound::Unbounded, Bound::Excluded(k))
    }

    /// Whether the two intervals share a point.
    pub fn meets(self, other: Interval) -> bool {
        let lo = tighter(self.0, other.0, |a, b| a > b);
        let hi = tighter(self.1, other.1, |a, b| a < b);
        match (lo, hi) {
            (Bound::Unbounded, _) | (_, Bound::Unbounded) => true,
            (Bound::Included(a), Bound::Included(b)) => a <= b,
            (Bound::Included(a) | Bound::Excluded(a), Bound::Included(b) | Bound::Excluded(b)) => {
                a < b
            }
        }
    }
}

/// The tighter of two bounds on the same side: `tighter_than(a, b)` says whether value `a`
/// bounds tighter than `b`; at equal values the excluded bound is the tighter.
fn tighter(a: Bound<f32>, b: Bound<f32>, tighter_than: fn(f32, f32) -> bool) -> Bound<f32> {
    match (a, b) {
        (Bound::Unbounded, x) | (x, Bound::Unbounded) => x,
        (Bound::Included(u) | Bound::Excluded(u), Bound::Included(v) | Bound::Excluded(v)) => {
            if tighter_than(u, v) || (u == v && matches!(a, Bound::Excluded(_))) {
                a
            } else {
                b
            }
        }
    }
}

impl Cell {
    pub const EVERY: Cell = Cell {
        distance: Interval::ALL,
        cosine: Interval::ALL,
    };

    /// Paths whose `‖x2 − x1‖ / max d` lies in `distance`, any orientation.
    pub const fn distance(distance: Interval) -> Cell {
        Cell {
            distance,
            cosine: Interval::ALL,
        }
    }

    /// Whether the two cells share a path.
    pub fn meets(self, other: Cell) -> bool {
        self.distance.meets(other.distance) && self.cosine.meets(other.cosine)
    }
}

impl Region {
    pub const EVERY: Region = Region(&[Cell::EVERY]);

    /// Whether the region holds a path with `‖x2 − x1‖ / max d = distance` and `n1·n2 = cosine`.
    pub fn contains(self, distance: f32, cosine: f32) -> bool {
        self.0.iter().any(|c| {
            (c.distance.0, c.distance.1).contains(&distance)
                && (c.cosine.0, c.cosine.1).contains(&cosine)
        })
    }

    /// Whether the two regions share a path.
    pub fn meets(self, other: Region) -> bool {
        self.0.iter().any(|a| other.0.iter().any(|b| a.meets(*b)))
    }
}

impl Numbers {
    /// Keeps the source's numbers on every path (reconnection, or the identity between pixels).
    pub const KEPT: Numbers = Numbers(&[Outcome {
        effect: Effect::Kept,
        paths: Region::EVERY,
    }]);
    /// Replays them on every path (delayed reconnection).
    pub const REPLAYED: Numbers = Numbers(&[Outcome {
        effect: Effect::Replayed,
        paths: Region::EVERY,
    }]);
    /// Re-derives them for the destination on every path (probabilistic inversion).
    pub const INVERTED: Numbers = Numbers(&[Outcome {
        effect: Effect::Inverted,
        paths: Region::EVERY,
    }]);

    /// The regions of the outcomes with `effect`.
    fn regions(self, effect: Effect) -> impl Iterator<Item = Region> {
        self.0
            .iter()
            .filter(move |o| o.effect == effect)
            .map(|o| o.paths)
    }

    /// Whether an output of this shift may carry numbers of another pixel's x1.
    pub fn leaves_foreign(self) -> bool {
        self.regions(Effect::Kept).next().is_some()
    }

    /// Whether this shift replays numbers on some path that a move by `earlier` may have left
    /// foreign: a region where it replays meets a region where `earlier` keeps them. Sound for
    /// any chain of passes: a foreign sample lies, at the pixel it sits in, in the kept region of
    /// the last pass that moved it keeping its numbers, so checking every earlier pass suffices.
    pub fn replays_foreign_of(self, earlier: Numbers) -> bool {
        self.regions(Effect::Replayed)
            .any(|r| earlier.regions(Effect::Kept).any(|k| r.meets(k)))
    }
}

impl fmt::Display for Interval {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let lo = match self.0 {
            Bound::Included(a) => format!("[{a}"),
            Bound::Excluded(a) => format!("({a}"),
            Bound::Unbounded => "(-inf".into(),
        };
        let hi = match self.1 {
            Bound::Included(b) => format!("{b}]"),
            Bound::Excluded(b) => format!("{b})"),
            Bound::Unbounded => "inf)".into(),
        };
        write!(f, "{lo}, {hi}")
    }
}

impl fmt::Display for Region {
    /// `everywhere`, or its cells as `|x2-x1|/max d in [2, inf) and n1.n2 in (-inf, 0.5]`
    /// joined by `or` (an unconstrained coordinate is left out).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let cells: Vec<String> = self
            .0
            .iter()
            .map(|c| {
                let mut terms = Vec::new();
                if c.distance != Interval::ALL {
                    terms.push(format!("|x2-x1|/max d in {}", c.distance));
                }
                if c.cosine != Interval::ALL {
                    terms.push(format!("n1.n2 in {}", c.cosine));
                }
                if terms.is_empty() {
                    "everywhere".to_string()
                } else {
                    terms.join(" and ")
                }
            })
            .collect();
        write!(f, "{}", cells.join(" or "))
    }
}

impl fmt::Display for Numbers {
    /// One clause per outcome, e.g. `kept where …; replayed where …`; `reads none` without one.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.0.is_empty() {
            return write!(f, "reads none");
        }
        let clauses: Vec<String> = self
            .0
            .iter()
            .map(|o| {
                let effect = match o.effect {
                    Effect::Kept => "kept",
                    Effect::Replayed => "replayed",
                    Effect::Inverted => "inverted",
                };
                if o.paths == Region::EVERY {
                    effect.to_string()
                } else {
                    format!("{effect} where {}", o.paths)
                }
            })
            .collect();
        write!(f, "{}", clauses.join("; "))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn intervals_meet_exactly_at_shared_closed_ends() {
        assert!(Interval::at_least(2.0).meets(Interval::at_most(2.0)));
        assert!(!Interval::at_least(2.0).meets(Interval::below(2.0)));
        assert!(!Interval::above(2.0).meets(Interval::at_most(2.0)));
        assert!(Interval::above(2.0).meets(Interval::at_most(2.5)));
        assert!(Interval::ALL.meets(Interval::below(-7.0)));
        assert!(
            !Interval(Bound::Included(1.0), Bound::Excluded(2.0)).meets(Interval::at_least(2.0))
        );
        assert!(
            Interval(Bound::Included(1.0), Bound::Included(2.0)).meets(Interval::at_least(2.0))
        );
    }

    #[test]
    fn declarations_read_as_one_line() {
        const NEAR: Numbers = Numbers(&[
            Outcome {
                effect: Effect::Kept,
                paths: Region(&[Cell::distance(Interval::at_least(2.0))]),
            },
            Outcome {
                effect: Effect::Replayed,
                paths: Region(&[Cell {
                    distance: Interval::below(2.0),
                    cosine: Interval::above(0.5),
                }]),
            },
        ]);
        assert_eq!(
            NEAR.to_string(),
            "kept where |x2-x1|/max d in [2, inf); replayed where |x2-x1|/max d in (-inf, 2) and n1.n2 in (0.5, inf)"
        );
        assert_eq!(Numbers::KEPT.to_string(), "kept");
        assert_eq!(Numbers(&[]).to_string(), "reads none");
        assert!(NEAR.replays_foreign_of(Numbers::KEPT));
        assert!(!NEAR.replays_foreign_of(NEAR));
        assert!(!Numbers::INVERTED.leaves_foreign());
        assert!(!Numbers::REPLAYED.replays_foreign_of(Numbers::INVERTED));
    }
}
