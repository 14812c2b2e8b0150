//! The sequential scheme's reconnection pass: reconnection followed by probabilistic inversion
//! [001 §4.2, Alg. 4], which re-draws the BSSRDF IS random numbers for the receiving pixel so a
//! later delayed-reconnection pass can replay them.

use restir::shift::{Fail, Shift, Shifted};
use sss::bssrdf::{BssrdfSample, EntryPoint, Probe, find_index, invert_random_numbers};

use crate::domain::{PURPOSE_INVERSION, SssDomain};
use crate::numbers::{DeclaresNumbers, Numbers};
use crate::reconnection::reconnect_shifted;
use crate::sample::SssSample;

pub use crate::contract::IndexPolicy;

/// Reconnection (`J = 1`, same failures as [`crate::Reconnection`]) followed by probabilistic
/// inversion of x2 for y1 [001 Alg. 4]: the technique is drawn from its posterior
/// `P(a)P(c) p_{d_c}(r_a)|n2·axis_a| 1[…] / p_disk(x2 | y1)` with `γ`, then
/// `u_radius = CDF_{d_c}(r_a)`, `u_angle = atan2 / 2π` wrapped to [0, 1), and `p_disk(x2 | y1)` is
/// cached.
///
/// The inversion at a domain `e` paired with `p` uses `γ_e`, the first number of the stream
/// `(e.pixel, e.frame, e.pass, PURPOSE_INVERSION | p.pixel)` (see [`SssDomain`]); the shift is
/// deterministic given `(src, dst)`.
///
/// **Extended path space** [001 §4.2, App. A]. For the pair `{s, d}` the shift acts on
/// `P × Γ²`, `(x, γ_s, γ_d) ↦ (x, γ_s, γ_d)`: the identity on the path (x2, x3) and on both
/// γ's, so `J = 1`. The random numbers a sample stores at `e` are `R_e(x, γ_e)`, and the point
/// belongs to the extended domain of `e` only if they regenerate x2 there, i.e. the re-traced
/// chord finds x2. `T_{s→d}` needs this at `d` to write its sample, and its back-shift
/// `T_{d→s}` (evaluated by the MIS weights of every other sample of the pass) needs it at `s`.
/// With the exact policy both directions therefore test *both* ends, each with its own `γ_e`:
/// the same two γ-dependent events, so a point fails one way exactly when its image fails the
/// other, and the MIS weights partition unity for every sample. Testing only the receiving end
/// (each direction its own) is biased where the two chords disagree
/// (`shifts/tests/mis_weights.rs`). The deferred policy has no γ-dependent failure.
///
/// Round trips are equal in path space (x2, x3) and in both γ's, `J = 1` in both directions; the
/// stored random numbers are recomputed at each end, so the round trip re-draws them for the
/// source pixel. Over runs `γ_e` is uniform and independent of the path (the run seed keys it),
/// so the stored technique follows its posterior given x2, which a later delayed pass's mixture
/// Jacobian `p_disk(x2|x1)/p_disk(y2|y1)` requires (`shifts/tests/jacobian.rs`); within a run it
/// is fixed per pair, frame and pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct InvertingReconnection {
    pub policy: IndexPolicy,
}

impl DeclaresNumbers for InvertingReconnection {
    const NUMBERS: Numbers = Numbers::INVERTED;
}

impl Shift<SssDomain<'_>> for InvertingReconnection {
    fn shift(
        &self,
        x: &SssSample,
        src: &SssDomain,
        dst: &SssDomain,
    ) -> Result<Shifted<SssSample>, Fail> {
        let Shifted { y, jacobian } = reconnect_shifted(x, src, dst)?;
        let x2 = dst.entry_point(&y).ok_or(Fail::Rejected)?;
        let exact = self.policy == IndexPolicy::Exact;
        let (probe, p_disk, index) = invert_at(dst, src, &x2, exact)?;
        if exact {
            // The back-shift's own inversion: T_{dst→src} fails exactly when this does. It
            // inverts x2 where `src` sees it (a moving object carries it between poses).
            let x2_src = src.entry_point(x).ok_or(Fail::Rejected)?;
            invert_at(src, dst, &x2_src, true)?;
        }
        let y = y.with_bssrdf(&BssrdfSample::new(&probe, index, &x2, p_disk));
        Ok(Shifted { y, jacobian })
    }
}

/// Probabilistic inversion of x2 at `end`'s x1 with `γ_end` (keyed by `partner`) [001 Alg. 4]:
/// the probe, `p_disk(x2 | x1)` and, with `find`, x2's rank among the re-traced chord's hits
/// (`NotInvertible` when x2 is not among them); `OutOfSupport` when no technique reaches x2.
fn invert_at(
    end: &SssDomain,
    partner: &SssDomain,
    x2: &EntryPoint,
    find: bool,
) -> Result<(Probe, f32, Option<u32>), Fail> {
    let gamma = end.shift_stream(PURPOSE_INVERSION, partner).next_f32();
    let (probe, p_disk) = invert_random_numbers(end.x1(), end.selection(), x2, gamma)
        .map_err(|_| Fail::OutOfSupport)?;
    if !find {
        return Ok((probe, p_disk, None));
    }
    let mut hits = Vec::new();
    let index = find_index(&end.scene().geometry, end.x1(), &probe, x2, &mut hits);
    Ok((probe, p_disk, Some(index.ok_or(Fail::NotInvertible)?)))
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
