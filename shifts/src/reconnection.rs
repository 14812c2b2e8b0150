//! The identity shift and reconnection `[y0, y1, x2, x3]` [001 §3.2.1] (DESIGN §5).

use restir::shift::{Evaluated, Fail, Shift, Shifted};

use crate::domain::{Located, SssDomain};
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

impl<'s> Shift<SssDomain<'s>> for Reconnection {
    fn shift(
        &self,
        x: &SssSample,
        _src: &SssDomain,
        dst: &SssDomain,
    ) -> Result<Shifted<SssSample>, Fail> {
        reconnect(x, dst).map(|y| Shifted { y, jacobian: 1.0 })
    }

    /// The support check has evaluated `p̂_dst(y)`: it is returned, not evaluated again.
    fn shift_with_target(
        &self,
        x: &SssSample,
        _src: &SssDomain,
        dst: &SssDomain,
    ) -> Result<(Shifted<SssSample>, f32), Fail> {
        reconnect_with_target(x, dst).map(|(y, target)| (Shifted { y, jacobian: 1.0 }, target))
    }

    /// `y = x`: both targets from one [`SssDomain::locate`] of x.
    fn shift_with_targets(
        &self,
        x: &SssSample,
        src: &SssDomain<'s>,
        dst: &SssDomain<'s>,
    ) -> Result<Evaluated<SssDomain<'s>>, Fail> {
        let located = src.locate(x).ok_or(Fail::Rejected)?;
        let target = reconnect_located(&located, x, dst)?;
        Ok(Evaluated {
            shifted: Shifted {
                y: *x,
                jacobian: 1.0,
            },
            target,
            source_target: src.target_located(&located, x),
        })
    }

    /// `x` located and `p̂_src(x)` evaluated once for all of `dsts`.
    fn shifts_with_targets(
        &self,
        x: &SssSample,
        src: &SssDomain<'s>,
        dsts: &[&SssDomain<'s>],
        out: &mut [Result<Evaluated<SssDomain<'s>>, Fail>],
    ) {
        let Some(located) = src.locate(x) else {
            out.fill(Err(Fail::Rejected));
            return;
        };
        let source_target = src.target_located(&located, x);
        for (o, dst) in out.iter_mut().zip(dsts) {
            *o = reconnect_located(&located, x, dst).map(|target| Evaluated {
                shifted: Shifted {
                    y: *x,
                    jacobian: 1.0,
                },
                target,
                source_target,
            });
        }
    }

    /// `y` located once for all of `others` (`J = 1`).
    fn targets_from(
        &self,
        y: &SssSample,
        receiver: &SssDomain,
        others: &[&SssDomain],
        out: &mut [f32],
    ) {
        let located = receiver.locate(y);
        for (t, other) in out.iter_mut().zip(others) {
            *t = located
                .and_then(|l| reconnect_located(&l, y, other).ok())
                .unwrap_or(0.0);
        }
    }
}

/// The support checks of reconnection into `dst`: x2 on y1's object (`Rejected`), within
/// `r_max` of the widest channel and with `p̂_dst > 0` (`OutOfSupport`). All depend only on the
/// path `[y1, x2, x3]`, so they hold in both directions of a round trip.
pub(crate) fn reconnect(x: &SssSample, dst: &SssDomain) -> Result<SssSample, Fail> {
    reconnect_with_target(x, dst).map(|(y, _)| y)
}

/// [`reconnect`] with the `p̂_dst(y) > 0` its check evaluated.
fn reconnect_with_target(x: &SssSample, dst: &SssDomain) -> Result<(SssSample, f32), Fail> {
    let located = dst.locate(x).ok_or(Fail::Rejected)?;
    reconnect_located(&located, x, dst).map(|target| (*x, target))
}

/// [`reconnect`]'s checks of `x`, found where `located` says, into `dst`; `p̂_dst(x)` if they
/// pass.
fn reconnect_located(located: &Located, x: &SssSample, dst: &SssDomain) -> Result<f32, Fail> {
    if x.object() != dst.x1().object {
        return Err(Fail::Rejected);
    }
    let r = (located.x2.position - dst.x1().position).length();
    // x1's `r_max` are the material's (`ExitPoint::new`), so this is `r_max_all`.
    if r.is_nan() || r > dst.x1().r_max.max_element() {
        return Err(Fail::OutOfSupport);
    }
    // `target` is finite and ≥ 0, so `<= 0` means "outside the support".
    let target = dst.target_located(located, x);
    if target <= 0.0 {
        return Err(Fail::OutOfSupport);
    }
    Ok(target)
}
