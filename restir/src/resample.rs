//! The resampling driver: candidate generation (RIS in one domain) and the GRIS combination of
//! a canonical reservoir with neighbour reservoirs through any shift and MIS scheme
//! [001 Alg. 2], streaming with no allocation.

use std::fmt;
use std::ops::Range;

pub use crate::contract::ResampleCode;
use crate::mis::{MAX_DOMAINS, MisScheme};
use crate::reservoir::{InvalidCandidate, Reservoir, Ris};
use crate::rng::Stream;
use crate::shift::{CandidateSampler, Domain, Evaluated, Fail, Shift};

/// A reservoir together with the domain its sample lives in.
pub struct Source<'a, D: Domain> {
    pub domain: &'a D,
    pub reservoir: &'a Reservoir<D::Sample>,
}

impl<D: Domain> Clone for Source<'_, D> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<D: Domain> Copy for Source<'_, D> {}

/// Why a resampling step produced no reservoir.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ResampleError {
    /// More than [`MAX_DOMAINS`] domains (receiver + neighbours) in one step.
    TooManyDomains(usize),
    /// A candidate sampler returned a density that is not finite and > 0.
    BadPdf(f32),
    /// A shift returned a Jacobian that is not finite and > 0 (it must return `Fail::Degenerate`).
    BadJacobian { source: usize, jacobian: f32 },
    /// A domain's target, a weight or a confidence was invalid; `source` is the domain index
    /// (0 = receiver).
    Candidate {
        source: usize,
        error: InvalidCandidate,
    },
}

impl ResampleError {
    /// The error a GPU kernel reported as `word` (`restir/glsl/resample.glsl`): the
    /// [`ResampleCode`] in the low byte, the domain index `source` in bits 8–15 (the domain
    /// count for `TooManyDomains`). The offending value is not carried and reads as NaN.
    /// `None` for 0 (no error) or an unknown code.
    pub fn from_gpu(word: u32) -> Option<ResampleError> {
        let source = ((word >> 8) & 0xff) as usize;
        let nan = f32::NAN;
        let candidate = |error| ResampleError::Candidate { source, error };
        Some(match ResampleCode::from_code(word & 0xff)? {
            ResampleCode::InvalidWeight => candidate(InvalidCandidate::Weight(nan)),
            ResampleCode::InvalidTarget => candidate(InvalidCandidate::Target(nan)),
            ResampleCode::InvalidConfidence => candidate(InvalidCandidate::Confidence(nan)),
            ResampleCode::InvalidUcw => candidate(InvalidCandidate::Ucw(nan)),
            ResampleCode::TooManyDomains => ResampleError::TooManyDomains(source),
            ResampleCode::BadPdf => ResampleError::BadPdf(nan),
            ResampleCode::BadJacobian => ResampleError::BadJacobian {
                source,
                jacobian: nan,
            },
        })
    }
}

impl fmt::Display for ResampleError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::TooManyDomains(n) => {
                write!(
                    f,
                    "{n} domains in one resampling step; at most {MAX_DOMAINS}"
                )
            }
            Self::BadPdf(p) => write!(f, "candidate sampler returned pdf {p}; need finite > 0"),
            Self::BadJacobian { source, jacobian } => {
                write!(
                    f,
                    "shift from domain {source} returned Jacobian {jacobian}; need finite > 0"
                )
            }
            Self::Candidate { source, error } => write!(f, "domain {source}: {error}"),
        }
    }
}

impl std::error::Error for ResampleError {}

/// RIS of `count` fresh candidates in `domain` (identity shift, `m_i = 1/M`, `W_{X_i} = 1/p`,
/// `c_i = 1`, so `c = M` [001 §2.2.2 (1)]). `count = 0` gives the empty reservoir.
pub fn generate_candidates<D, C>(
    domain: &D,
    sampler: &C,
    count: u32,
    rng: &mut Stream,
) -> Result<Reservoir<D::Sample>, ResampleError>
where
    D: Domain,
    C: CandidateSampler<D> + ?Sized,
{
    let mut ris = Ris::new();
    let inv_count = if count > 0 { 1.0 / count as f32 } else { 0.0 };
    for _ in 0..count {
        let drawn = sampler.sample(domain, rng);
        let u = rng.next_f32();
        let result = match drawn {
            Some((x, pdf)) => {
                if !(pdf.is_finite() && pdf > 0.0) {
                    return Err(ResampleError::BadPdf(pdf));
                }
                let target = domain.target(&x);
                // w_i = m_i p̂(x_i) W_{X_i} = p̂(x_i) / (M p(x_i))   [001 Eq. 6]
                ris.update(x, target, inv_count * target / pdf, 1.0, u)
            }
            None => ris.skip(1.0),
        };
        result.map_err(|error| ResampleError::Candidate { source: 0, error })?;
    }
    Ok(ris.finish())
}

/// Combines the receiver's canonical reservoir with `neighbours` into the receiver's domain
/// [001 Alg. 2], one uniform number per input from `rng`.
///
/// Weights follow DESIGN §9: `w_i = m_i(y_i) p̂_r(y_i) W_i J_i` with `y_i = T_{i→r}(x_i)`;
/// `targets[j] = p̂_{←j}(y)` via [`Shift::target_from`], and `p̂_i(x_i) / J_i` for the
/// sample's own domain. Confidences are used as given: cap them before the call.
///
/// Forward shifts and back-shifts go through [`Shift::shift_supported`] (as [`Shift::shift_with_target`]): only samples with a
/// positive target weigh.
///
/// Failure convention (paper 001's): a neighbour whose forward shift fails, or whose reservoir is
/// empty or has `W = 0`, contributes weight 0 but its confidence is still added. This does not darken the
/// estimate because the MIS weights of the other samples already give that domain
/// `m_j(y) = 0` wherever its shift fails
/// (test: `failed_forward_shifts_keep_confidence_and_do_not_darken`).
pub fn resample<D, T, M>(
    receiver: Source<'_, D>,
    neighbours: &[Source<'_, D>],
    shift: &T,
    mis: &M,
    rng: &mut Stream,
) -> Result<Reservoir<D::Sample>, ResampleError>
where
    D: Domain,
    T: Shift<D> + ?Sized,
    M: MisScheme + ?Sized,
{
    resample_observed(receiver, neighbours, shift, mis, rng, &mut |_| {})
}

/// One input of a resampling step as [`resample_observed`] reports it.
#[derive(Clone, Copy, Debug)]
pub struct Observed<'a, S> {
    /// 0 for the receiver's own (canonical) reservoir, `i` for neighbour `i − 1`.
    pub source: usize,
    /// The input's sample in the receiver's domain, `y_i = T_{i→r}(x_i)`.
    pub y: &'a S,
    /// Its MIS weight `m_i(y_i)`.
    pub mis_weight: f32,
    /// `m_i(y_i) · W_i · J_i = w_i / p̂_r(y_i)`.
    pub factor: f32,
    /// Whether the stream selected it; the last input observed with `selected` is `Y`.
    pub selected: bool,
}

/// [`resample`] that also calls `observe` ([`Observed`]) for every input streamed with a
/// positive resampling weight. Observing draws no random number and changes nothing.
///
/// `Σ_i f(y_i) · m_i(y_i) W_i J_i` over the observed inputs is the Rao-Blackwellised estimate of
/// the step: `E[f(Y)·W | inputs]`, with the same expectation `∫f` as `f(Y)·W` and without the
/// variance of the selection (for a vector-valued `f` whose scalar target is `p̂`, the selected
/// sample's `f(Y)/p̂(Y)` ratio). Its `p̂`-part is exact: `Σ_i p̂_r(y_i) · factor_i = w_sum =
/// p̂_r(Y) · W`.
pub fn resample_observed<D, T, M>(
    receiver: Source<'_, D>,
    neighbours: &[Source<'_, D>],
    shift: &T,
    mis: &M,
    rng: &mut Stream,
    observe: &mut dyn FnMut(Observed<'_, D::Sample>),
) -> Result<Reservoir<D::Sample>, ResampleError>
where
    D: Domain,
    T: Shift<D> + ?Sized,
    M: MisScheme + ?Sized,
{
    let n = neighbours.len() + 1;
    if n > MAX_DOMAINS {
        return Err(ResampleError::TooManyDomains(n));
    }
    // Domain j: the receiver, then the neighbours' (padded with the receiver's).
    let mut domains = [receiver.domain; MAX_DOMAINS];
    let mut reservoirs = [receiver.reservoir; MAX_DOMAINS];
    for (j, nb) in neighbours.iter().enumerate() {
        domains[j + 1] = nb.domain;
        reservoirs[j + 1] = nb.reservoir;
    }
    let exchange = Shifting { shift, domains };
    resample_exchanged(receiver, &reservoirs[1..n], &exchange, mis, rng, observe)
}

/// Where a resampling step takes its shifts from (DESIGN §9): the forward shift of each
/// neighbour's sample into the receiver, and the back-shifts of a sample in the receiver into
/// the other domains. [`resample_observed`] evaluates them with a [`Shift`]; a caller that has
/// them already hands them to [`resample_exchanged`] (reciprocal neighbour pairs: the shift of
/// `x_p` into `q` is `q`'s forward shift and `p`'s canonical back-shift at once).
pub trait Exchange<D: Domain> {
    /// `T_{i→r}(x_i)` with `p̂_r(y_i)` and `p̂_i(x_i)` ([`Shift::shift_with_targets`]), for the
    /// sample `x` of neighbour `i ≥ 1` (domain `i` of the step).
    fn forward(&self, i: usize, x: &D::Sample) -> Result<Evaluated<D>, Fail>;

    /// `p̂_{←j}(y)` ([`Shift::target_from`]) for each domain `j` of `js` into `out` (same length),
    /// where `y` is input `i`'s sample in the receiver (`i = 0`: the canonical sample).
    fn back(&self, i: usize, y: &D::Sample, js: Range<usize>, out: &mut [f32]);
}

/// The [`Exchange`] that evaluates every shift with `shift` between `domains` (0: the receiver).
struct Shifting<'a, 's, D: Domain, T: ?Sized> {
    shift: &'s T,
    domains: [&'a D; MAX_DOMAINS],
}

impl<D: Domain, T: Shift<D> + ?Sized> Exchange<D> for Shifting<'_, '_, D, T> {
    fn forward(&self, i: usize, x: &D::Sample) -> Result<Evaluated<D>, Fail> {
        self.shift
            .shift_with_targets(x, self.domains[i], self.domains[0])
    }

    fn back(&self, _i: usize, y: &D::Sample, js: Range<usize>, out: &mut [f32]) {
        self.shift
            .targets_from(y, self.domains[0], &self.domains[js], out);
    }
}

/// The streaming combination of [`resample_observed`] with its shifts from `exchange`:
/// `neighbours[i − 1]` is the reservoir of domain `i` (its sample `x_i` in its own domain, its
/// `W_i` and capped `c_i`). Given an exchange whose values equal the shift's, the result is the
/// one [`resample_observed`] gives, bit for bit (`exchanged_shifts_give_the_same_reservoir`).
pub fn resample_exchanged<D, M, E>(
    receiver: Source<'_, D>,
    neighbours: &[&Reservoir<D::Sample>],
    exchange: &E,
    mis: &M,
    rng: &mut Stream,
    observe: &mut dyn FnMut(Observed<'_, D::Sample>),
) -> Result<Reservoir<D::Sample>, ResampleError>
where
    D: Domain,
    M: MisScheme + ?Sized,
    E: Exchange<D> + ?Sized,
{
    let n = neighbours.len() + 1;
    if n > MAX_DOMAINS {
        return Err(ResampleError::TooManyDomains(n));
    }
    let mut confidences = [0.0f32; MAX_DOMAINS];
    confidences[0] = receiver.reservoir.confidence;
    for (c, nb) in confidences[1..n].iter_mut().zip(neighbours) {
        *c = nb.confidence;
    }
    let confidences = &confidences[..n];
    let mut targets = [0.0f32; MAX_DOMAINS];
    let mut ris = Ris::new();
    let r = receiver.domain;

    for i in 0..n {
        let input = if i == 0 {
            receiver.reservoir
        } else {
            neighbours[i - 1]
        };
        let u = rng.next_f32();
        let wrap = |error| ResampleError::Candidate { source: i, error };
        if !(input.ucw.is_finite() && input.ucw >= 0.0) {
            return Err(wrap(InvalidCandidate::Ucw(input.ucw)));
        }
        // An input with W = 0 has weight 0 whatever its shift gives (and its target is not
        // read), so it is streamed like an empty one and its shift, often a ray, is skipped.
        let Some(x) = input.y.filter(|_| input.ucw > 0.0) else {
            ris.skip(input.confidence).map_err(wrap)?;
            continue;
        };
        let (y, jacobian, own_target, target) = if i == 0 {
            (x, 1.0, None, r.target(&x))
        } else {
            match exchange.forward(i, &x) {
                Ok(Evaluated {
                    shifted: s,
                    target,
                    source_target,
                }) => {
                    if !(s.jacobian.is_finite() && s.jacobian > 0.0) {
                        return Err(ResampleError::BadJacobian {
                            source: i,
                            jacobian: s.jacobian,
                        });
                    }
                    (s.y, s.jacobian, Some(source_target / s.jacobian), target)
                }
                Err(_) => {
                    ris.skip(input.confidence).map_err(wrap)?;
                    continue;
                }
            }
        };
        if !(target.is_finite() && target >= 0.0) {
            return Err(wrap(InvalidCandidate::Target(target)));
        }
        let m = if target > 0.0 {
            let targets = &mut targets[..n];
            targets.fill(0.0);
            targets[0] = target;
            if let Some(t) = own_target {
                targets[i] = t;
            }
            if mis.needs_all_targets(i) {
                // Every domain but r and i: those before i, then those after it.
                let (before, after) = (1..i.max(1), (i + 1).max(1)..n);
                for js in [before, after] {
                    exchange.back(i, &y, js.clone(), &mut targets[js]);
                }
            }
            mis.weight(i, targets, confidences)
        } else {
            0.0
        };
        // w_i = m_i(y_i) p̂_r(y_i) W_i J_i   [001 Eq. 6]
        let weight = m * target * input.ucw * jacobian;
        ris.update(y, target, weight, input.confidence, u)
            .map_err(wrap)?;
        if weight > 0.0 {
            observe(Observed {
                source: i,
                y: &y,
                mis_weight: m,
                factor: m * input.ucw * jacobian,
                selected: ris.took(weight, u),
            });
        }
    }
    Ok(ris.finish())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gpu_error_words_decode_to_the_errors() {
        assert!(matches!(
            ResampleError::from_gpu(0x0204),
            Some(ResampleError::Candidate {
                source: 2,
                error: InvalidCandidate::Ucw(_)
            })
        ));
        assert!(matches!(
            ResampleError::from_gpu(0x0107),
            Some(ResampleError::BadJacobian { source: 1, .. })
        ));
        assert!(matches!(
            ResampleError::from_gpu(6),
            Some(ResampleError::BadPdf(_))
        ));
        assert!(matches!(
            ResampleError::from_gpu(2),
            Some(ResampleError::Candidate {
                source: 0,
                error: InvalidCandidate::Target(_)
            })
        ));
        assert_eq!(ResampleError::from_gpu(0), None);
        assert_eq!(ResampleError::from_gpu(8), None);
    }
    use crate::mis::{ConfidenceOnly, DefensivePairwise, Gbh, Pairwise};
    use crate::rng::StreamKey;
    use crate::shift::{Fail, Shifted};
    use crate::stats::{Summary, Verdict, equivalence};
    use crate::toy::shifts::Translation;
    use crate::toy::{LinearSampler, Point, Supports, ToyPixel};

    /// δ on the relative bias, α (CI confidence 1 − α), and replicas of the tests below.
    const DELTA: f64 = 0.03;
    const ALPHA: f64 = 1e-3;
    const N: usize = 20_000;

    /// A `resample` argument: `reservoir` in `domain`.
    fn source<'a>(domain: &'a ToyPixel, reservoir: &'a Reservoir<Point>) -> Source<'a, ToyPixel> {
        Source { domain, reservoir }
    }

    fn pixel(centre: [f32; 2]) -> ToyPixel {
        ToyPixel {
            centre,
            ..ToyPixel::new(0, 0, 1, Supports::Equal)
        }
    }

    fn verdict(estimates: &[f64], reference: f64) -> crate::stats::Equivalence {
        equivalence(
            &Summary::from_samples(estimates),
            &Summary::exact(reference),
            DELTA,
            1.0 - ALPHA,
        )
    }

    /// A sampler that draws uniformly but reports the linear density (a lying pdf).
    struct LyingSampler;

    impl CandidateSampler<ToyPixel> for LyingSampler {
        fn sample(&self, _: &ToyPixel, rng: &mut Stream) -> Option<(Point, f32)> {
            let x = [rng.next_f32(), rng.next_f32()];
            Some((x, LinearSampler::density(&x)))
        }
        fn pdf(&self, _: &ToyPixel, x: &Point) -> f32 {
            LinearSampler::density(x)
        }
    }

    /// E[f(Y)·W] = ∫f for RIS of M = 1 and 4 candidates (N = 20 000, δ = 3%, α = 1e-3).
    /// Negative control: a sampler whose reported pdf is not its density is found biased.
    #[test]
    fn candidate_ris_is_unbiased_and_a_lying_pdf_is_caught() {
        let d = pixel([0.4, 0.6]);
        let run = |sampler: &dyn CandidateSampler<ToyPixel>, m: u32| -> Vec<f64> {
            (0..N)
                .map(|i| {
                    let mut rng = StreamKey::new(0, 0, 0, 0).stream(i as u64);
                    let r = generate_candidates(&d, sampler, m, &mut rng).unwrap();
                    assert_eq!(r.confidence, m as f32);
                    r.y.map_or(0.0, |y| d.integrand(&y) as f64 * r.ucw as f64)
                })
                .collect()
        };
        for m in [1, 4] {
            let good = verdict(&run(&LinearSampler, m), d.integrand_integral());
            assert_eq!(good.verdict, Verdict::Equivalent, "M = {m}: {good}");
            let bad = verdict(&run(&LyingSampler, m), d.integrand_integral());
            assert_eq!(
                bad.verdict,
                Verdict::Biased,
                "negative control, M = {m}: {bad}"
            );
        }
    }

    /// Paper 001's convention: a neighbour whose forward shift fails adds weight 0 but its
    /// confidence. With translation by (0.35, −0.25) about half the neighbour's samples fail,
    /// and the estimate stays unbiased under GBH, pairwise and defensive pairwise (N = 20 000,
    /// δ = 3%, α = 1e-3): the other samples' MIS weights already give the failing domain 0.
    /// Negative control: `1/M` weights in the same setup darken the estimate (CI below −δ).
    #[test]
    fn failed_forward_shifts_keep_confidence_and_do_not_darken() {
        let receiver = pixel([0.3, 0.6]);
        let neighbour = pixel([0.65, 0.35]);
        let run = |mis: &dyn MisScheme| -> (Vec<f64>, usize) {
            let mut failures = 0;
            let estimates = (0..N)
                .map(|i| {
                    let key = |purpose| StreamKey::new(0, 0, 0, purpose).stream(i as u64);
                    let canonical =
                        generate_candidates(&receiver, &LinearSampler, 1, &mut key(0)).unwrap();
                    let other =
                        generate_candidates(&neighbour, &LinearSampler, 4, &mut key(1)).unwrap();
                    if let Some(x) = other.y {
                        failures += Translation.shift(&x, &neighbour, &receiver).is_err() as usize;
                    }
                    let r = resample(
                        source(&receiver, &canonical),
                        &[source(&neighbour, &other)],
                        &Translation,
                        mis,
                        &mut key(2),
                    )
                    .unwrap();
                    assert_eq!(r.confidence, 5.0);
                    r.y.map_or(0.0, |y| receiver.integrand(&y) as f64 * r.ucw as f64)
                })
                .collect();
            (estimates, failures)
        };
        let reference = receiver.integrand_integral();
        for mis in [&Gbh as &dyn MisScheme, &Pairwise, &DefensivePairwise] {
            let (estimates, failures) = run(mis);
            assert!(
                failures > N / 5,
                "only {failures} of {N} forward shifts failed"
            );
            let e = verdict(&estimates, reference);
            assert_eq!(e.verdict, Verdict::Equivalent, "{}: {e}", mis.name());
        }
        let dark = verdict(&run(&ConfidenceOnly).0, reference);
        assert!(
            dark.verdict == Verdict::Biased && dark.ci_high < -DELTA,
            "negative control: {dark}"
        );
    }

    /// The shifts of a step stored beforehand, as reciprocal pairs share them: each neighbour's
    /// forward shift, and the canonical sample's back-shift into each neighbour.
    struct Stored {
        forward: Vec<Result<Evaluated<ToyPixel>, Fail>>,
        back: Vec<f32>,
    }

    impl Exchange<ToyPixel> for Stored {
        fn forward(&self, i: usize, _x: &Point) -> Result<Evaluated<ToyPixel>, Fail> {
            match &self.forward[i - 1] {
                Ok(e) => Ok(Evaluated { ..*e }),
                Err(fail) => Err(*fail),
            }
        }

        fn back(&self, i: usize, _y: &Point, js: Range<usize>, out: &mut [f32]) {
            assert_eq!(
                i, 0,
                "a pairwise scheme reads only the canonical sample's back-shifts"
            );
            out.copy_from_slice(&self.back[js.start - 1..js.end - 1]);
        }
    }

    /// A step whose shifts come from an [`Exchange`] holding the values the shift gives (the
    /// forward shift of each neighbour's sample, and `p̂_{←j}` of the canonical sample, which
    /// for a reciprocal pair is the forward shift of the receiver's sample into `j`) selects
    /// the same sample with the same `W` and `c` as [`resample`], bit for bit, with pairwise and
    /// defensive pairwise MIS, over 2 000 replicas with three neighbours (one of them failing
    /// about half its shifts). Control: an exchange whose back-shifts are 1% too large changes
    /// `W` in some replica.
    #[test]
    fn exchanged_shifts_give_the_same_reservoir() {
        let receiver = pixel([0.3, 0.6]);
        let others = [pixel([0.35, 0.55]), pixel([0.65, 0.35]), pixel([0.2, 0.7])];
        for mis in [&Pairwise as &dyn MisScheme, &DefensivePairwise] {
            let mut control_differs = false;
            for i in 0..2000u64 {
                let key = |purpose| StreamKey::new(0, 0, 0, purpose).stream(i);
                let canonical =
                    generate_candidates(&receiver, &LinearSampler, 1, &mut key(0)).unwrap();
                let stored: Vec<Reservoir<Point>> = (others.iter().enumerate())
                    .map(|(j, d)| {
                        generate_candidates(d, &LinearSampler, 2, &mut key(1 + j as u32)).unwrap()
                    })
                    .collect();
                let sources: Vec<_> = (others.iter().zip(&stored))
                    .map(|(d, r)| source(d, r))
                    .collect();
                let want = resample(
                    source(&receiver, &canonical),
                    &sources,
                    &Translation,
                    mis,
                    &mut key(9),
                )
                .unwrap();
                let forward = (others.iter().zip(&stored))
                    .map(|(d, r)| match r.y {
                        Some(x) => Translation.shift_with_targets(&x, d, &receiver),
                        None => Err(Fail::Rejected),
                    })
                    .collect();
                let back: Vec<f32> = others
                    .iter()
                    .map(|d| match canonical.y {
                        Some(y) => match Translation.shift_with_targets(&y, &receiver, d) {
                            Ok(e) => e.target * e.shifted.jacobian,
                            Err(_) => 0.0,
                        },
                        None => 0.0,
                    })
                    .collect();
                let refs: Vec<&Reservoir<Point>> = stored.iter().collect();
                let mut exchange = Stored { forward, back };
                let run = |exchange: &Stored| {
                    let receiver = source(&receiver, &canonical);
                    let mut observe = |_: Observed<'_, Point>| {};
                    resample_exchanged(receiver, &refs, exchange, mis, &mut key(9), &mut observe)
                        .unwrap()
                };
                assert_eq!(run(&exchange), want, "replica {i}, {}", mis.name());
                exchange.back.iter_mut().for_each(|t| *t *= 1.01);
                control_differs |= run(&exchange).ucw != want.ucw;
            }
            assert!(control_differs, "control: {}", mis.name());
        }
    }

    /// The Rao-Blackwellised estimate of a step, `Σ_i f(y_i) m_i W_i J_i` from
    /// [`resample_observed`]: (1) its `p̂`-part is the step's `w_sum = p̂(Y)·W` for every
    /// replica (exact up to rounding), (2) `E[Σ_i f(y_i) m_i W_i J_i] = ∫f` (equivalence, N =
    /// 20 000, δ = 3%, α = 1e-3) with a neighbour whose shifts fail half the time, (3) its
    /// variance is below that of `f(Y)·W` (the selection's variance is gone). Negative control:
    /// the same sum with `f` evaluated in the neighbour's domain instead of the receiver's is
    /// found biased, and so is the Rao-Blackwellised sum scaled by `1 + 1.5δ` (power at δ).
    /// The last input observed as `selected` is the output's `Y` in every replica.
    #[test]
    fn observed_inputs_give_the_rao_blackwellised_estimate() {
        let receiver = pixel([0.3, 0.6]);
        let neighbour = pixel([0.65, 0.35]);
        let (mut rb, mut selected, mut uniform) = (Vec::new(), Vec::new(), Vec::new());
        for i in 0..N {
            let key = |purpose| StreamKey::new(0, 0, 0, purpose).stream(i as u64);
            let canonical = generate_candidates(&receiver, &LinearSampler, 1, &mut key(0)).unwrap();
            let other = generate_candidates(&neighbour, &LinearSampler, 4, &mut key(1)).unwrap();
            let (mut sum, mut p_sum, mut wrong) = (0.0f64, 0.0f64, 0.0f64);
            let mut chosen = None;
            let r = resample_observed(
                source(&receiver, &canonical),
                &[source(&neighbour, &other)],
                &Translation,
                &Gbh,
                &mut key(2),
                &mut |o| {
                    let factor = o.factor as f64;
                    sum += receiver.integrand(o.y) as f64 * factor;
                    p_sum += receiver.target(o.y) as f64 * factor;
                    // The control: f evaluated in the neighbour's domain, not the receiver's.
                    wrong += neighbour.integrand(o.y) as f64 * factor;
                    if o.selected {
                        chosen = Some(*o.y);
                    }
                },
            )
            .unwrap();
            assert_eq!(chosen, r.y, "replica {i}: the observed selection is Y");
            let value =
                r.y.map_or(0.0, |y| receiver.integrand(&y) as f64 * r.ucw as f64);
            let w_sum =
                r.y.map_or(0.0, |y| receiver.target(&y) as f64 * r.ucw as f64);
            assert!(
                (p_sum - w_sum).abs() <= 1e-4 * w_sum.max(1e-3),
                "replica {i}: Σ p̂ · factor = {p_sum} vs p̂(Y)·W = {w_sum}"
            );
            rb.push(sum);
            selected.push(value);
            uniform.push(wrong);
        }
        let reference = receiver.integrand_integral();
        let good = verdict(&rb, reference);
        assert_eq!(good.verdict, Verdict::Equivalent, "{good}");
        let (rb_var, selected_var) = (
            Summary::from_samples(&rb).std_err,
            Summary::from_samples(&selected).std_err,
        );
        assert!(
            rb_var < selected_var,
            "s.e. Rao-Blackwellised {rb_var} vs selected {selected_var}"
        );
        let bad = verdict(&uniform, reference);
        assert_eq!(bad.verdict, Verdict::Biased, "negative control: {bad}");
        let near: Vec<f64> = rb.iter().map(|v| v * (1.0 + 1.5 * DELTA)).collect();
        let near = verdict(&near, reference);
        assert_eq!(near.verdict, Verdict::Biased, "control at 1.5δ: {near}");
    }

    /// [`Translation`] that counts its calls out of the domain centred at `.1` (forward shifts
    /// of that neighbour; the MIS back-shifts start at the receiver).
    struct Counted(std::sync::atomic::AtomicU32, [f32; 2]);

    impl Shift<ToyPixel> for Counted {
        fn shift(&self, x: &Point, src: &ToyPixel, dst: &ToyPixel) -> Result<Shifted<Point>, Fail> {
            if src.centre == self.1 {
                self.0.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            }
            Translation.shift(x, src, dst)
        }
    }

    /// A neighbour with `W = 0` is streamed like an empty one of the same confidence (same
    /// reservoir, bit for bit, under every scheme) and its forward shift is not evaluated; one
    /// with `W > 0` is (control: the shift is called for it).
    #[test]
    fn zero_weight_inputs_are_not_shifted() {
        let receiver = pixel([0.3, 0.6]);
        let neighbour = pixel([0.4, 0.5]);
        for mis in [&Gbh as &dyn MisScheme, &Pairwise, &DefensivePairwise] {
            for i in 0..200u64 {
                let key = |purpose| StreamKey::new(0, 0, 0, purpose).stream(i);
                let canonical =
                    generate_candidates(&receiver, &LinearSampler, 1, &mut key(0)).unwrap();
                let other =
                    generate_candidates(&neighbour, &LinearSampler, 4, &mut key(1)).unwrap();
                let run = |input: &Reservoir<Point>| {
                    let shift = Counted(std::sync::atomic::AtomicU32::new(0), neighbour.centre);
                    let r = resample(
                        source(&receiver, &canonical),
                        &[source(&neighbour, input)],
                        &shift,
                        mis,
                        &mut key(2),
                    )
                    .unwrap();
                    (r, shift.0.into_inner())
                };
                let zero = Reservoir { ucw: 0.0, ..other };
                let empty = Reservoir { y: None, ..zero };
                let ((with_zero, zero_calls), (with_empty, _)) = (run(&zero), run(&empty));
                assert_eq!(zero_calls, 0, "{}: replica {i}", mis.name());
                assert_eq!(with_zero.y, with_empty.y);
                assert_eq!(with_zero.ucw.to_bits(), with_empty.ucw.to_bits());
                assert_eq!(
                    with_zero.confidence.to_bits(),
                    with_empty.confidence.to_bits()
                );
                if other.y.is_some() && other.ucw > 0.0 {
                    assert!(run(&other).1 > 0, "control: {}: replica {i}", mis.name());
                }
            }
        }
    }

    /// A domain whose target is NaN, a shift with a NaN Jacobian, a sampler with pdf 0.
    struct Broken;

    impl Domain for Broken {
        type Sample = f32;
        fn target(&self, x: &f32) -> f32 {
            if *x > 0.5 { f32::NAN } else { 1.0 }
        }
    }

    impl Shift<Broken> for Broken {
        fn shift(&self, x: &f32, _: &Broken, _: &Broken) -> Result<Shifted<f32>, Fail> {
            Ok(Shifted {
                y: *x,
                jacobian: f32::NAN,
            })
        }
    }

    struct Fixed(f32, f32);

    impl CandidateSampler<Broken> for Fixed {
        fn sample(&self, _: &Broken, _: &mut Stream) -> Option<(f32, f32)> {
            Some((self.0, self.1))
        }
        fn pdf(&self, _: &Broken, _: &f32) -> f32 {
            self.1
        }
    }

    #[test]
    fn bad_input_gives_typed_errors_or_defined_results() {
        let mut rng = StreamKey::default().stream(0);
        let empty = generate_candidates(&Broken, &Fixed(0.2, 1.0), 0, &mut rng).unwrap();
        assert_eq!(empty, Reservoir::empty());
        for pdf in [0.0, -1.0, f32::NAN, f32::INFINITY] {
            let got = generate_candidates(&Broken, &Fixed(0.2, pdf), 2, &mut rng);
            assert!(
                matches!(got, Err(ResampleError::BadPdf(_))),
                "pdf {pdf}: {got:?}"
            );
        }
        let got = generate_candidates(&Broken, &Fixed(0.7, 1.0), 1, &mut rng);
        assert!(
            matches!(got, Err(ResampleError::Candidate { source: 0, .. })),
            "{got:?}"
        );

        let good = Reservoir {
            y: Some(0.2f32),
            ucw: 1.0,
            confidence: 1.0,
        };
        let receiver = Source {
            domain: &Broken,
            reservoir: &good,
        };
        let got = resample(receiver, &[receiver], &Broken, &Gbh, &mut rng);
        assert!(
            matches!(got, Err(ResampleError::BadJacobian { source: 1, .. })),
            "{got:?}"
        );
        let many = vec![receiver; MAX_DOMAINS];
        let got = resample(receiver, &many, &Broken, &Gbh, &mut rng);
        assert_eq!(got, Err(ResampleError::TooManyDomains(MAX_DOMAINS + 1)));

        let toy = pixel([0.5, 0.5]);
        let canonical = Reservoir {
            y: Some([0.5f32, 0.5]),
            ucw: 1.0,
            confidence: 1.0,
        };
        for bad in [
            Reservoir {
                y: Some([0.5f32, 0.5]),
                ucw: f32::NAN,
                confidence: 1.0,
            },
            Reservoir {
                y: Some([0.5f32, 0.5]),
                ucw: -1.0,
                confidence: 1.0,
            },
            Reservoir {
                y: Some([0.5f32, 0.5]),
                ucw: 1.0,
                confidence: f32::NAN,
            },
            Reservoir {
                y: None,
                ucw: 0.0,
                confidence: -3.0,
            },
        ] {
            let got = resample(
                source(&toy, &canonical),
                &[source(&toy, &bad)],
                &Translation,
                &DefensivePairwise,
                &mut rng,
            );
            assert!(
                matches!(got, Err(ResampleError::Candidate { source: 1, .. })),
                "{bad:?}: {got:?}"
            );
        }
        let zero = Reservoir {
            y: Some([0.5f32, 0.5]),
            ucw: 1.0,
            confidence: 0.0,
        };
        let got = resample(
            source(&toy, &zero),
            &[source(&toy, &zero)],
            &Translation,
            &Gbh,
            &mut rng,
        )
        .unwrap();
        assert!(
            got.ucw.is_finite() && got.confidence == 0.0,
            "zero confidences: {got:?}"
        );
    }
}
