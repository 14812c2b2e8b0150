//! Reconnection with a distance threshold: reconnection [001 §3.2.1] restricted to paths whose
//! entry point x2 lies at least `min_distance` from the exit point on both sides of the shift —
//! where the hybrid shift [001 §4.1] prefers reconnection because the profile varies slowly.
//! Elsewhere it fails, and the canonical sample and the MIS weights cover those paths.
//!
//! The worked example of `docs/adding-a-shift.md`: this file, its twin
//! `shifts/glsl/distant.glsl` and one line of `registry.rs`.

use restir::shift::{Fail, Shift, Shifted};
use sss::material::Translucent;

use crate::domain::SssDomain;
use crate::numbers::{Cell, DeclaresNumbers, Effect, Interval, Numbers, Outcome, Region};
use crate::reconnection::reconnect_shifted;
use crate::sample::SssSample;

/// Reconnection where `‖x2 − x1‖ ≥ min_distance` for the exit points x1 of both domains.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DistantReconnection {
    pub min_distance: f32,
}

impl DistantReconnection {
    /// The hybrid shift's distance threshold `κ_dist = 2 · max_c d_c` [001 §5.1].
    pub fn for_material(material: &Translucent) -> DistantReconnection {
        DistantReconnection {
            min_distance: MIN_DISTANCE_PER_MAX_D * material.d().max_element(),
        }
    }
}

/// `min_distance / max_c d_c`.
const MIN_DISTANCE_PER_MAX_D: f32 = 2.0;

/// It keeps the numbers of the paths it moves, all far from the destination's x1.
impl DeclaresNumbers for DistantReconnection {
    const NUMBERS: Numbers = Numbers(&[Outcome {
        effect: Effect::Kept,
        paths: Region(&[Cell::distance(Interval::at_least(MIN_DISTANCE_PER_MAX_D))]),
    }]);
}

/// `J = 1` (reconnection; across two poses of a moving object, the light factor of
/// `reconnect_shifted`). The rule reads x2 and both exit points, which a round trip exchanges,
/// so the shift fails in one direction exactly when it fails in the other.
impl Shift<SssDomain<'_>> for DistantReconnection {
    fn shift(
        &self,
        x: &SssSample,
        src: &SssDomain,
        dst: &SssDomain,
    ) -> Result<Shifted<SssSample>, Fail> {
        let far = |d: &SssDomain| {
            d.entry_point(x)
                .is_some_and(|x2| (x2.position - d.x1().position).length() >= self.min_distance)
        };
        if !(far(src) && far(dst)) {
            return Err(Fail::Rejected);
        }
        reconnect_shifted(x, src, dst)
    }
}
