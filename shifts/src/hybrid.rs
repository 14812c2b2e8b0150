//! The hybrid shift [001 §4.1]: reconnection where x1 and x2 are far apart or differently
//! oriented, delayed reconnection elsewhere, made bijective by testing the criterion on both
//! paths (DESIGN §9 "Hybrid bijectivity").

use restir::shift::{Fail, Shift, Shifted};
use sss::bssrdf::{EntryPoint, ExitPoint};
use sss::material::Translucent;

use crate::delayed::{Checks, Wanted, replay};
use crate::domain::SssDomain;
use crate::numbers::{Cell, DeclaresNumbers, Effect, Interval, Numbers, Outcome, Region};
use crate::reconnection::reconnect_shifted;
use crate::sample::SssSample;

/// Hybrid shift with thresholds `κ_dist` (scene units) and `κ_orient` (cosine).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hybrid {
    pub kappa_dist: f32,
    pub kappa_orient: f32,
}

/// Paper 001's `κ_dist / max_c d_c` [001 §5.1].
const KAPPA_DIST_PER_MAX_D: f32 = 2.0;
/// Paper 001's `κ_orient` [001 §5.1].
const KAPPA_ORIENT: f32 = 0.5;

impl Hybrid {
    /// Paper 001's defaults [001 §5.1]: `κ_dist = 2 · max_c d_c`, `κ_orient = 0.5`.
    pub fn for_material(material: &Translucent) -> Hybrid {
        Hybrid {
            kappa_dist: KAPPA_DIST_PER_MAX_D * material.d().max_element(),
            kappa_orient: KAPPA_ORIENT,
        }
    }

    /// `connectable(x1, x2) ⇔ ‖x2 − x1‖ ≥ κ_dist ∨ n1·n2 ≤ κ_orient` (geometric normals; n1
    /// faces the camera) [001 §4.1].
    pub fn connectable(&self, x1: &ExitPoint, x2: &EntryPoint) -> bool {
        (x2.position - x1.position).length() >= self.kappa_dist
            || x1.frame.n.dot(x2.geometric_normal) <= self.kappa_orient
    }

    /// Whether the shift of `x` out of `src` uses reconnection (the diagnostic of paper 001
    /// Fig. 4); `None` if x2 is not on `src`'s object.
    pub fn uses_reconnection(&self, x: &SssSample, src: &SssDomain) -> Option<bool> {
        src.entry_point(x).map(|x2| self.connectable(src.x1(), &x2))
    }

    /// The hybrid shift for a caller that uses the samples `wanted`; `respect_offset = false` is
    /// the negative control that skips the test on the offset path.
    pub(crate) fn shift_checked(
        &self,
        x: &SssSample,
        src: &SssDomain,
        dst: &SssDomain,
        respect_offset: bool,
        wanted: Wanted,
    ) -> Result<Shifted<SssSample>, Fail> {
        let x2 = src.entry_point(x).ok_or(Fail::Rejected)?;
        if self.connectable(src.x1(), &x2) {
            let shifted = reconnect_shifted(x, src, dst)?;
            // x2 where `dst` sees it (a moving object carries it between poses).
            let y2 = match src.shares_pose(dst) {
                true => x2,
                false => dst.entry_point(&shifted.y).ok_or(Fail::Rejected)?,
            };
            if respect_offset && !self.connectable(dst.x1(), &y2) {
                return Err(Fail::Rejected);
            }
            Ok(shifted)
        } else {
            let replayed = replay(x, src, dst, Checks::ALL)?;
            let rejected = respect_offset && self.connectable(dst.x1(), &replayed.y2);
            replayed.finish(dst, rejected, wanted)
        }
    }
}

/// Reconnection keeps the numbers of paths connectable at both ends; delayed reconnection
/// replays those of paths not connectable at the source. The two regions are disjoint, so a
/// hybrid may follow a hybrid.
impl DeclaresNumbers for Hybrid {
    const NUMBERS: Numbers = Numbers(&[
        Outcome {
            effect: Effect::Kept,
            paths: Region(&[
                Cell::distance(Interval::at_least(KAPPA_DIST_PER_MAX_D)),
                Cell {
                    distance: Interval::ALL,
                    cosine: Interval::at_most(KAPPA_ORIENT),
                },
            ]),
        },
        Outcome {
            effect: Effect::Replayed,
            paths: Region(&[Cell {
                distance: Interval::below(KAPPA_DIST_PER_MAX_D),
                cosine: Interval::above(KAPPA_ORIENT),
            }]),
        },
    ]);
}

/// Base connectable → reconnection, failing unless `connectable(y1, x2)`; base not connectable →
/// delayed reconnection, failing if `connectable(y1, y2)`. Both paths of a pair then take the
/// same branch, so the shift is a bijection.
impl Shift<SssDomain<'_>> for Hybrid {
    fn shift(
        &self,
        x: &SssSample,
        src: &SssDomain,
        dst: &SssDomain,
    ) -> Result<Shifted<SssSample>, Fail> {
        self.shift_checked(x, src, dst, true, Wanted::Every)
    }

    /// The offset path's criterion and whether light reaches y2 at all ([`SssDomain::visible_if_lit`])
    /// before the shadow ray.
    fn shift_supported(
        &self,
        x: &SssSample,
        src: &SssDomain,
        dst: &SssDomain,
    ) -> Result<Shifted<SssSample>, Fail> {
        self.shift_checked(x, src, dst, true, Wanted::Supported)
    }
}
