//! The sequential scheme's reconnection pass: reconnection followed by probabilistic inversion
//! [001 §4.2, Alg. 4], which re-draws the BSSRDF IS random numbers for the receiving pixel so a
//! later delayed-reconnection pass can replay them.

use restir::shift::{Fail, Shift, Shifted};
use sss::bssrdf::{BssrdfSample, find_index, invert_random_numbers};

use crate::domain::{PURPOSE_INVERSION, SssDomain};
use crate::reconnection::reconnect;
use crate::sample::SssSample;

pub use crate::contract::IndexPolicy;

/// Reconnection (`J = 1`, same failures as [`crate::Reconnection`]) followed by probabilistic
/// inversion of x2 for y1 [001 Alg. 4]: the technique is drawn from its posterior
/// `P(a)P(c) p_{d_c}(r_a)|n2·axis_a| 1[…] / p_disk(x2 | y1)` with `γ`, then
/// `u_radius = CDF_{d_c}(r_a)`, `u_angle = atan2 / 2π` wrapped to [0, 1), and `p_disk(x2 | y1)` is
/// cached.
///
/// `γ` is the first number of the receiver's stream `(dst.pixel, dst.frame, dst.pass,
/// PURPOSE_INVERSION | src.pixel)` (see [`SssDomain`]), so the shift is deterministic given
/// `(src, dst)`.
///
/// Round trips are equal in path space (x2, x3), `J = 1` in both directions: the random numbers
/// are an auxiliary variable re-sampled from its conditional distribution given the path
/// [001 §4.2, App. A], not a coordinate of the path, and the round trip re-draws them for the
/// source pixel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct InvertingReconnection {
    pub policy: IndexPolicy,
}

impl Shift<SssDomain<'_>> for InvertingReconnection {
    fn shift(
        &self,
        x: &SssSample,
        src: &SssDomain,
        dst: &SssDomain,
    ) -> Result<Shifted<SssSample>, Fail> {
        let y = reconnect(x, dst)?;
        let x2 = dst.entry_point(&y).ok_or(Fail::Rejected)?;
        let gamma = dst.shift_stream(PURPOSE_INVERSION, src).next_f32();
        let (probe, p_disk) = invert_random_numbers(dst.x1(), dst.selection(), &x2, gamma)
            .map_err(|_| Fail::OutOfSupport)?;
        let index = match self.policy {
            IndexPolicy::Exact => {
                let mut hits = Vec::new();
                let index = find_index(&dst.scene().geometry, dst.x1(), &probe, &x2, &mut hits);
                Some(index.ok_or(Fail::NotInvertible)?)
            }
            IndexPolicy::Deferred => None,
        };
        let y = y.with_bssrdf(&BssrdfSample::new(&probe, index, &x2, p_disk));
        Ok(Shifted { y, jacobian: 1.0 })
    }
}

/// The deferred policy's second half: for the sample selected after a pass, re-trace its chord at
/// `domain`'s x1 and store x2's rank; the index stays unknown if x2 is not found (then delayed
/// reconnection picks a hit uniformly). A sample whose index is known is left as it is.
pub fn resolve_deferred_index(domain: &SssDomain, y: &mut SssSample) {
    if y.index().is_some() {
        return;
    }
    let (Some(stored), Some(x2)) = (y.bssrdf(), domain.entry_point(y)) else {
        return;
    };
    let mut hits = Vec::new();
    let index = find_index(
        &domain.scene().geometry,
        domain.x1(),
        &stored.probe(),
        &x2,
        &mut hits,
    );
    *y = y.with_index(index);
}
