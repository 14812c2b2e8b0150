//! The identity shift and reconnection `[y0, y1, x2, x3]` [001 §3.2.1] (DESIGN §5).

use restir::shift::{Evaluated, Fail, Shift, Shifted};

use crate::delayed::light_jacobian;
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
        src: &SssDomain,
        dst: &SssDomain,
    ) -> Result<Shifted<SssSample>, Fail> {
        reconnect_shifted(x, src, dst)
    }

    /// The support check has evaluated `p̂_dst(y)`: it is returned, not evaluated again.
    fn shift_with_target(
        &self,
        x: &SssSample,
        src: &SssDomain,
        dst: &SssDomain,
    ) -> Result<(Shifted<SssSample>, f32), Fail> {
        let (y, target) = reconnect_with_target(x, dst)?;
        let jacobian = pose_jacobian(x, src, dst)?;
        Ok((Shifted { y, jacobian }, target))
    }

    /// `y = x`: both targets from one [`SssDomain::locate`] of x.
    fn shift_with_targets(
        &self,
        x: &SssSample,
        src: &SssDomain<'s>,
        dst: &SssDomain<'s>,
    ) -> Result<Evaluated<SssDomain<'s>>, Fail> {
        let located = src.locate(x).ok_or(Fail::Rejected)?;
        let target = reconnect_from(&located, x, src, dst)?;
        Ok(Evaluated {
            shifted: Shifted {
                y: *x,
                jacobian: pose_jacobian(x, src, dst)?,
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
            *o = reconnect_from(&located, x, src, dst).and_then(|target| {
                Ok(Evaluated {
                    shifted: Shifted {
                        y: *x,
                        jacobian: pose_jacobian(x, src, dst)?,
                    },
                    target,
                    source_target,
                })
            });
        }
    }

    /// `y` located once for all of `others` that share its pose (`J = 1` there).
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
                .and_then(|l| {
                    let target = reconnect_from(&l, y, receiver, other).ok()?;
                    Some(target * pose_jacobian(y, receiver, other).ok()?)
                })
                .unwrap_or(0.0);
        }
    }
}

/// [`reconnect`] as the shift from `src` to `dst`: `y = x` with [`pose_jacobian`].
pub(crate) fn reconnect_shifted(
    x: &SssSample,
    src: &SssDomain,
    dst: &SssDomain,
) -> Result<Shifted<SssSample>, Fail> {
    let y = reconnect(x, dst)?;
    let jacobian = pose_jacobian(x, src, dst)?;
    Ok(Shifted { y, jacobian })
}

/// The Jacobian of reconnecting `x` from `src` to `dst`: 1 where both see the scene in one pose
/// (x2 and x3 stay where they are). Where a moving object carried x2 from `src`'s pose to
/// `dst`'s, its area is kept (the motion is rigid) but x3's solid angle at x2 changes: the
/// light factor of [001 Eq. 11], as delayed reconnection's (`Degenerate` where it is not
/// positive and finite).
pub(crate) fn pose_jacobian(x: &SssSample, src: &SssDomain, dst: &SssDomain) -> Result<f32, Fail> {
    if src.shares_pose(dst) {
        return Ok(1.0);
    }
    let (from, to) = (src.locate_x2(x), dst.locate_x2(x));
    let (Some(from), Some(to)) = (from, to) else {
        return Err(Fail::Rejected);
    };
    let lights = &dst.scene().lights;
    let jacobian = light_jacobian(lights, x.light(), x.x3(), from.position, to.position);
    if jacobian > 0.0 && jacobian.is_finite() {
        Ok(jacobian)
    } else {
        Err(Fail::Degenerate)
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

/// [`reconnect_located`] of `x` located in `src`: that location where `dst` shares its pose
/// ([`SssDomain::shares_pose`]), else `x` located again in `dst` (a moving object carried its
/// x2 from one frame's pose to the other's).
fn reconnect_from(
    located: &Located,
    x: &SssSample,
    src: &SssDomain,
    dst: &SssDomain,
) -> Result<f32, Fail> {
    if src.shares_pose(dst) {
        reconnect_located(located, x, dst)
    } else {
        reconnect_with_target(x, dst).map(|(_, target)| target)
    }
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
