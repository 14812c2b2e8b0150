//! Shifts between toy pixels: three correct ones with known Jacobians and the deliberately
//! broken ones that `restir::check` must detect (DESIGN §3, check 7).

use super::{Point, ToyPixel};
use crate::shift::{Domain, Evaluated, Fail, Shift, Shifted};

/// `y = x + (μ_dst − μ_src)`, `J = 1`; fails when `y` leaves Ω.
#[derive(Clone, Copy, Debug, Default)]
pub struct Translation;

impl Shift<ToyPixel> for Translation {
    fn shift(&self, x: &Point, src: &ToyPixel, dst: &ToyPixel) -> Result<Shifted<Point>, Fail> {
        let y = [
            x[0] + (dst.centre[0] - src.centre[0]),
            x[1] + (dst.centre[1] - src.centre[1]),
        ];
        if ToyPixel::in_omega(&y) {
            Ok(Shifted { y, jacobian: 1.0 })
        } else {
            Err(Fail::OutOfSupport)
        }
    }
}

/// The scaling map `y = μ_dst + s (x − μ_src)`, `s = σ_dst / σ_src`, with `J = s²`.
fn scale(x: &Point, src: &ToyPixel, dst: &ToyPixel) -> Result<(Point, f32), Fail> {
    let s = dst.sigma / src.sigma;
    let y = [
        dst.centre[0] + s * (x[0] - src.centre[0]),
        dst.centre[1] + s * (x[1] - src.centre[1]),
    ];
    if ToyPixel::in_omega(&y) {
        Ok((y, s * s))
    } else {
        Err(Fail::OutOfSupport)
    }
}

/// Scaling about the pixel's bump centre by the ratio of widths: `J = (σ_dst/σ_src)² ≠ 1`.
#[derive(Clone, Copy, Debug, Default)]
pub struct Scaling;

impl Shift<ToyPixel> for Scaling {
    fn shift(&self, x: &Point, src: &ToyPixel, dst: &ToyPixel) -> Result<Shifted<Point>, Fail> {
        scale(x, src, dst).map(|(y, jacobian)| Shifted { y, jacobian })
    }
}

/// Primary-sample replay: invert the source pixel's warp `x_d = u_d^{γ_d}`, replay `u` through
/// the destination's warp. `J = p_src(x) / p_dst(y)` with the warp densities
/// `p(x) = Π_d 1 / (γ_d u_d^{γ_d − 1})`; fails (`Degenerate`) where a `u_d` is 0.
#[derive(Clone, Copy, Debug, Default)]
pub struct Replay;

impl Shift<ToyPixel> for Replay {
    fn shift(&self, x: &Point, src: &ToyPixel, dst: &ToyPixel) -> Result<Shifted<Point>, Fail> {
        if !ToyPixel::in_omega(x) {
            return Err(Fail::OutOfSupport);
        }
        let mut y = [0.0f32; 2];
        let mut jacobian = 1.0f32;
        for d in 0..2 {
            let (gs, gd) = (src.warp_gamma[d], dst.warp_gamma[d]);
            let u = x[d].powf(1.0 / gs);
            if u <= 0.0 {
                return Err(Fail::Degenerate);
            }
            y[d] = u.powf(gd);
            // dy/dx = (dy/du) / (dx/du) = γ_d u^{γ_d−1} / (γ_s u^{γ_s−1})
            jacobian *= gd / gs * u.powf(gd - gs);
        }
        if jacobian.is_finite() && jacobian > 0.0 && ToyPixel::in_omega(&y) {
            Ok(Shifted { y, jacobian })
        } else {
            Err(Fail::Degenerate)
        }
    }
}

/// Broken: the scaling map with `J = 1` (wrong Jacobian).
#[derive(Clone, Copy, Debug, Default)]
pub struct ScalingUnitJacobian;

impl Shift<ToyPixel> for ScalingUnitJacobian {
    fn shift(&self, x: &Point, src: &ToyPixel, dst: &ToyPixel) -> Result<Shifted<Point>, Fail> {
        scale(x, src, dst).map(|(y, _)| Shifted { y, jacobian: 1.0 })
    }
}

/// How [`NoBackShift`] gets `p̂_{←j}` wrong.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BackShiftBug {
    /// `p̂_j(y)` at the un-shifted point (and never 0 where the back-shift fails).
    Unshifted,
    /// `p̂_j(T_{r→j}(y))` without the Jacobian.
    NoJacobian,
}

/// Broken: a correct forward shift whose MIS target `p̂_{←j}` skips the back-shift.
#[derive(Clone, Copy, Debug)]
pub struct NoBackShift<T> {
    pub inner: T,
    pub bug: BackShiftBug,
}

impl<T: Shift<ToyPixel>> Shift<ToyPixel> for NoBackShift<T> {
    fn shift(&self, x: &Point, src: &ToyPixel, dst: &ToyPixel) -> Result<Shifted<Point>, Fail> {
        self.inner.shift(x, src, dst)
    }
    fn target_from(&self, y: &Point, receiver: &ToyPixel, other: &ToyPixel) -> f32 {
        match self.bug {
            BackShiftBug::Unshifted => other.target(y),
            BackShiftBug::NoJacobian => match self.inner.shift(y, receiver, other) {
                Ok(back) => other.target(&back.y),
                Err(_) => 0.0,
            },
        }
    }
}

/// How [`WrongShortcut`] breaks a shortcut resampling takes.
#[derive(Clone, Copy, Debug)]
pub enum ShortcutBug {
    /// [`Shift::targets_from`] evaluates `y` in each domain without shifting it.
    UnshiftedBatch,
    /// [`Shift::shift_with_targets`] reports `p̂_src` of the shifted point, not of the input.
    SourceTargetOfShifted,
}

/// Broken: translation whose plain evaluations are right but one shortcut is not (the bug an
/// optimised override can bring; caught by check 4 (c) and, in the chain, by unbiasedness).
#[derive(Clone, Copy, Debug)]
pub struct WrongShortcut(pub ShortcutBug);

impl Shift<ToyPixel> for WrongShortcut {
    fn shift(&self, x: &Point, src: &ToyPixel, dst: &ToyPixel) -> Result<Shifted<Point>, Fail> {
        Translation.shift(x, src, dst)
    }
    fn shift_with_targets(
        &self,
        x: &Point,
        src: &ToyPixel,
        dst: &ToyPixel,
    ) -> Result<Evaluated<ToyPixel>, Fail> {
        let shifted = self.shift(x, src, dst)?;
        let source_target = match self.0 {
            ShortcutBug::SourceTargetOfShifted => src.target(&shifted.y),
            ShortcutBug::UnshiftedBatch => src.target(x),
        };
        Ok(Evaluated {
            target: dst.target(&shifted.y),
            shifted,
            source_target,
        })
    }
    fn targets_from(&self, y: &Point, receiver: &ToyPixel, others: &[&ToyPixel], out: &mut [f32]) {
        for (t, other) in out.iter_mut().zip(others) {
            *t = match self.0 {
                ShortcutBug::UnshiftedBatch => other.target(y),
                ShortcutBug::SourceTargetOfShifted => self.target_from(y, receiver, other),
            };
        }
    }
}

/// Broken: translation that rejects `src → dst` when `src.id < dst.id` and `x₀ > ½`, but
/// never rejects the reverse direction (asymmetric rejection).
#[derive(Clone, Copy, Debug, Default)]
pub struct AsymmetricRejection;

impl Shift<ToyPixel> for AsymmetricRejection {
    fn shift(&self, x: &Point, src: &ToyPixel, dst: &ToyPixel) -> Result<Shifted<Point>, Fail> {
        if src.id < dst.id && x[0] > 0.5 {
            return Err(Fail::Rejected);
        }
        Translation.shift(x, src, dst)
    }
}
