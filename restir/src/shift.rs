//! Domains, shift mappings and candidate samplers: the three things a user plugs into GRIS
//! (DESIGN §3). Everything here is `f32`, like the per-pixel kernels that mirror it on the GPU.

use crate::rng::Stream;

/// One integration domain Ω (a pixel at a frame) with its target function `p̂`.
pub trait Domain: Sync {
    /// A point of Ω, small enough to be stored in a reservoir.
    type Sample: Copy + Send + Sync;

    /// `p̂(x) ≥ 0`, and exactly 0 outside the support.
    fn target(&self, x: &Self::Sample) -> f32;
}

pub use crate::contract::Fail;

/// A shifted sample `y = T(x)` and `J = |T'(x)|` in the measure of `p̂`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shifted<S> {
    pub y: S,
    pub jacobian: f32,
}

/// [`Shift::shift_with_targets`]: `y = T(x)` with `p̂_dst(y)` and `p̂_src(x)`.
pub struct Evaluated<D: Domain> {
    pub shifted: Shifted<D::Sample>,
    /// `p̂_dst(y)`.
    pub target: f32,
    /// `p̂_src(x)`.
    pub source_target: f32,
}

impl<D: Domain> Clone for Evaluated<D> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<D: Domain> Copy for Evaluated<D> {}

/// A shift mapping `T_{src→dst}`.
///
/// Deterministic given the two domains: a shift that needs randomness draws it from a
/// `StreamKey` its domains carry. For a bijective shift `shift(y, dst, src)` undoes
/// `shift(x, src, dst)`, and a point fails in one direction exactly when its image would fail
/// in the other (`restir::check` tests both).
pub trait Shift<D: Domain>: Sync {
    fn shift(&self, x: &D::Sample, src: &D, dst: &D) -> Result<Shifted<D::Sample>, Fail>;

    /// [`Shift::shift`] for a caller that uses `T(x)` only where `p̂_dst(T(x)) > 0`: it returns
    /// the same `Ok` wherever that holds, and may fail (with any [`Fail`]) where it does not.
    /// Resampling is such a caller: a shifted sample with `p̂_r = 0` has weight 0, which is what
    /// a failed shift contributes, and `p̂_{←j} = 0` either way ([`Shift::target_from`]). A
    /// shift overrides it to rule out `p̂_dst = 0` cheaply before work that cannot change the
    /// result then (a shadow ray); the default is [`Shift::shift`].
    fn shift_supported(&self, x: &D::Sample, src: &D, dst: &D) -> Result<Shifted<D::Sample>, Fail> {
        self.shift(x, src, dst)
    }

    /// [`Shift::shift_supported`] with `p̂_dst(T(x))` beside it, which resampling reads next.
    /// A shift whose support check has evaluated `p̂_dst` overrides it to return that value
    /// rather than evaluate it twice; the default evaluates it.
    fn shift_with_target(
        &self,
        x: &D::Sample,
        src: &D,
        dst: &D,
    ) -> Result<(Shifted<D::Sample>, f32), Fail> {
        let shifted = self.shift_supported(x, src, dst)?;
        let target = dst.target(&shifted.y);
        Ok((shifted, target))
    }

    /// [`Shift::shift_with_target`] with `p̂_src(x)` too, the input's target in its own domain
    /// that MIS weights read. A shift that evaluates both from work they share (where a sample
    /// lies, what lights it) overrides it; the default evaluates `p̂_src(x)` on its own.
    fn shift_with_targets(&self, x: &D::Sample, src: &D, dst: &D) -> Result<Evaluated<D>, Fail> {
        let (shifted, target) = self.shift_with_target(x, src, dst)?;
        Ok(Evaluated {
            shifted,
            target,
            source_target: src.target(x),
        })
    }

    /// [`Shift::shift_with_targets`] of one `x` into each of `dsts`, written to `out` (same
    /// length): a spatial pass with reciprocal neighbour pairs shifts each pixel's sample into
    /// its partner of every slot, once for both pixels of the pair. A shift that shares work
    /// between them (locating `x` once, `p̂_src(x)` once) overrides it; the default calls
    /// `shift_with_targets` for each.
    fn shifts_with_targets(
        &self,
        x: &D::Sample,
        src: &D,
        dsts: &[&D],
        out: &mut [Result<Evaluated<D>, Fail>],
    ) {
        for (o, dst) in out.iter_mut().zip(dsts) {
            *o = self.shift_with_targets(x, src, dst);
        }
    }

    /// `p̂_{←j}(y) = p̂_j(T_{r→j}(y)) · |T'_{r→j}(y)|`, 0 when the back-shift fails
    /// (DESIGN §9, [001 Eq. 7]). A shift with a cheaper exact way to evaluate this may override
    /// it; `restir::check::partition_of_unity` catches overrides that ignore failures.
    fn target_from(&self, y: &D::Sample, receiver: &D, other: &D) -> f32 {
        match self.shift_with_target(y, receiver, other) {
            Ok((back, target)) => target * back.jacobian,
            Err(_) => 0.0,
        }
    }

    /// [`Shift::target_from`] of one `y` into each of `others`, written to `out` (same length):
    /// the canonical sample's back-shifts that its MIS weight reads. A shift that shares work
    /// between them (locating `y` once) overrides it; the default calls `target_from` for each.
    fn targets_from(&self, y: &D::Sample, receiver: &D, others: &[&D], out: &mut [f32]) {
        for (t, other) in out.iter_mut().zip(others) {
            *t = self.target_from(y, receiver, other);
        }
    }
}

/// Local coordinates of a sample in the measure of `p̂`, so that `restir::check` can perturb a
/// sample and compare the shift's analytic Jacobian with central differences.
pub trait LocalCoords: Domain {
    /// Number of coordinates (the dimension of `p̂`'s measure).
    fn dim(&self) -> usize;
    /// Writes the coordinates of `x` into `out[..dim]`.
    fn to_local(&self, x: &Self::Sample, out: &mut [f64]);
    /// The sample at `coords`, or `None` outside the domain.
    fn sample_at_local(&self, coords: &[f64]) -> Option<Self::Sample>;
}

/// Draws fresh candidates in one domain with a known density (pbrt style: sample paired with pdf).
pub trait CandidateSampler<D: Domain>: Sync {
    /// A sample and its density `p(x) > 0` in `p̂`'s measure, or `None` when no sample was made.
    fn sample(&self, domain: &D, rng: &mut Stream) -> Option<(D::Sample, f32)>;
    /// The density [`CandidateSampler::sample`] draws `x` with.
    fn pdf(&self, domain: &D, x: &D::Sample) -> f32;
}
