//! Negative controls: deliberately wrong shifts that the conformance tests must detect. Each
//! is biased; never use one to render.

use restir::shift::{Fail, Shift, Shifted};

use crate::contract::{BROKEN_JACOBIAN_ERROR, DELAYED_CHECK_JACOBIAN, DELAYED_CHECK_VISIBILITY};
use crate::delayed::{Checks, Wanted, replay};
use crate::domain::SssDomain;
use crate::hybrid::Hybrid;
use crate::numbers::{DeclaresNumbers, Numbers};
use crate::sample::SssSample;

/// Delayed reconnection with `J = 1` instead of [001 Eq. 11] (still bijective, so its Jacobians
/// are trivially reciprocal; finite differences and unbiasedness catch it).
#[derive(Clone, Copy, Debug, Default)]
pub struct DelayedWithoutJacobian;

impl DeclaresNumbers for DelayedWithoutJacobian {
    const NUMBERS: Numbers = Numbers::REPLAYED;
}

impl Shift<SssDomain<'_>> for DelayedWithoutJacobian {
    fn shift(
        &self,
        x: &SssSample,
        src: &SssDomain,
        dst: &SssDomain,
    ) -> Result<Shifted<SssSample>, Fail> {
        replay(x, src, dst, Checks::ALL.without(DELAYED_CHECK_JACOBIAN))?.finish(
            dst,
            false,
            Wanted::Every,
        )
    }
}

/// Delayed reconnection without the y2–x3 visibility test: light leaks into shadows.
#[derive(Clone, Copy, Debug, Default)]
pub struct DelayedWithoutVisibility;

impl DeclaresNumbers for DelayedWithoutVisibility {
    const NUMBERS: Numbers = Numbers::REPLAYED;
}

impl Shift<SssDomain<'_>> for DelayedWithoutVisibility {
    fn shift(
        &self,
        x: &SssSample,
        src: &SssDomain,
        dst: &SssDomain,
    ) -> Result<Shifted<SssSample>, Fail> {
        replay(x, src, dst, Checks::ALL.without(DELAYED_CHECK_VISIBILITY))?.finish(
            dst,
            false,
            Wanted::Every,
        )
    }
}

/// The hybrid shift with paper 001's thresholds for the source's material
/// ([`Hybrid::for_material`]), choosing by the base path only, without testing the criterion on
/// the offset path: not a bijection (a round trip can take the other branch).
#[derive(Clone, Copy, Debug, Default)]
pub struct HybridIgnoringCriterion;

/// The hybrid's declaration, which this control breaks: skipping the offset path's test it
/// keeps numbers on paths not connectable at the destination. The conformance kit and the
/// unbiasedness test catch it (`shifts/tests/conformance.rs`, `lab/tests/unbiased.rs`).
impl DeclaresNumbers for HybridIgnoringCriterion {
    const NUMBERS: Numbers = Hybrid::NUMBERS;
}

impl Shift<SssDomain<'_>> for HybridIgnoringCriterion {
    fn shift(
        &self,
        x: &SssSample,
        src: &SssDomain,
        dst: &SssDomain,
    ) -> Result<Shifted<SssSample>, Fail> {
        Hybrid::for_material(src.material()).shift_checked(x, src, dst, false, Wanted::Every)
    }
}

/// Delayed reconnection with its Jacobian [001 Eq. 11] multiplied by
/// [`BROKEN_JACOBIAN_ERROR`] (1.03): a control near the ±2% tolerance of the unbiasedness tests
/// (`lab/tests/unbiased.rs`), where [`DelayedWithoutJacobian`] is far off. Biased; never render
/// with it.
#[derive(Clone, Copy, Debug, Default)]
pub struct DelayedJacobianOff;

impl DeclaresNumbers for DelayedJacobianOff {
    const NUMBERS: Numbers = Numbers::REPLAYED;
}

impl Shift<SssDomain<'_>> for DelayedJacobianOff {
    fn shift(
        &self,
        x: &SssSample,
        src: &SssDomain,
        dst: &SssDomain,
    ) -> Result<Shifted<SssSample>, Fail> {
        let s = replay(x, src, dst, Checks::ALL)?.finish(dst, false, Wanted::Every)?;
        Ok(Shifted {
            jacobian: s.jacobian * BROKEN_JACOBIAN_ERROR,
            ..s
        })
    }
}
