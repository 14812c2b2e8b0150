//! The identity shift and reconnection `[y0, y1, x2, x3]` [001 §3.2.1] (DESIGN §5).

use restir::shift::{Domain, Fail, Shift, Shifted};

use crate::domain::SssDomain;
use crate::numbers::{DeclaresNumbers, Numbers};
use crate::sample::SssSample;

/// `T(x) = x`, `J = 1`, never fails: the shift of a domain onto itself (canonical samples). As a
/// shift between two pixels it is reconnection without its support checks (still bijective).
#[derive(Clone, Copy, Debug, Default)]
pub struct Identity;

/// Between two pixels it moves the sample keeping its numbers.
impl DeclaresNumbers for Identity {
    const NUMBERS: Numbers = Numbers::KEPT;
}

impl Shift<SssDomain<'_>> for Identity {
    fn shift(
        &self,
        x: &SssSample,
        _src: &SssDomain,
        _dst: &SssDomain,
    ) -> Result<Shifted<SssSample>, Fail> {
        Ok(Shifted {
            y: *x,
            jacobian: 1.0,
        })
    }
}

/// Reconnection: keeps x2 and x3, `J = 1` (x2 in area measure; x3 in solid angle at the unchanged
/// x2). Fires no ray: the x2–x3 segment is kept. The stored random numbers stay those of the
/// source pixel, so the cached `p_disk` stays `p_disk(x2 | x1_src)`; only
/// [`crate::InvertingReconnection`] refreshes them for the receiver.
#[derive(Clone, Copy, Debug, Default)]
pub struct Reconnection;

impl DeclaresNumbers for Reconnection {
    const NUMBERS: Numbers = Numbers::KEPT;
}

impl Shift<SssDomain<'_>> for Reconnection {
    fn shift(
        &self,
        x: &SssSample,
        _src: &SssDomain,
        dst: &SssDomain,
    ) -> Result<Shifted<SssSample>, Fail> {
        reconnect(x, dst).map(|y| Shifted { y, jacobian: 1.0 })
    }
}

/// The support checks of reconnection into `dst`: x2 on y1's object (`Rejected`), within
/// `r_max` of the widest channel and with `p̂_dst > 0` (`OutOfSupport`). All depend only on the
/// path `[y1, x2, x3]`, so they hold in both directions of a round trip.
pub(crate) fn reconnect(x: &SssSample, dst: &SssDomain) -> Result<SssSample, Fail> {
    let x2 = dst.entry_point(x).ok_or(Fail::Rejected)?;
    let r = (x2.position - dst.x1().position).length();
    // `target` is finite and ≥ 0, so `<= 0` means "outside the support".
    if r.is_nan() || r > dst.material().r_max_all() || dst.target(x) <= 0.0 {
        return Err(Fail::OutOfSupport);
    }
    Ok(*x)
}
