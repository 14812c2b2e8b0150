//! Weighted reservoir sampling [001 Alg. 1]: the streaming state [`Ris`] and the stored state
//! [`Reservoir`] are two types, so no field changes meaning after `finish`.

use std::fmt;

/// A reservoir between passes: the selected sample, its unbiased contribution weight `W`
/// (`ucw`) and its confidence `c`. Both numbers are always finite and ≥ 0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reservoir<S> {
    pub y: Option<S>,
    pub ucw: f32,
    pub confidence: f32,
}

impl<S> Reservoir<S> {
    /// No sample, `W = 0`, `c = 0`.
    pub const fn empty() -> Self {
        Self {
            y: None,
            ucw: 0.0,
            confidence: 0.0,
        }
    }
}

impl<S> Default for Reservoir<S> {
    fn default() -> Self {
        Self::empty()
    }
}

/// `c_prev ← min(c_prev, cap · c_cur)`: the temporal confidence cap (cap 20 in [001 §5]).
#[inline]
pub fn cap_confidence(c_prev: f32, c_cur: f32, cap: f32) -> f32 {
    c_prev.min(cap * c_cur)
}

/// Which input of [`Ris::update`] was rejected.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum InvalidCandidate {
    /// The resampling weight was NaN, infinite or negative.
    Weight(f32),
    /// The target of the sample in the receiving domain was NaN, infinite or negative.
    Target(f32),
    /// The confidence was NaN, infinite or negative.
    Confidence(f32),
    /// An input reservoir's UCW `W` was NaN, infinite or negative (checked by the driver).
    Ucw(f32),
}

impl fmt::Display for InvalidCandidate {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Weight(v) => write!(f, "resampling weight {v} is not finite and ≥ 0"),
            Self::Target(v) => write!(f, "target p̂ = {v} is not finite and ≥ 0"),
            Self::Confidence(v) => write!(f, "confidence {v} is not finite and ≥ 0"),
            Self::Ucw(v) => write!(f, "unbiased contribution weight {v} is not finite and ≥ 0"),
        }
    }
}

impl std::error::Error for InvalidCandidate {}

/// Streaming GRIS state [001 Alg. 1–2]: `w_sum`, the running confidence and the selected sample
/// with its target in the receiving domain.
#[derive(Clone, Copy, Debug)]
pub struct Ris<S> {
    w_sum: f32,
    confidence: f32,
    selected: Option<(S, f32)>,
}

impl<S: Copy> Default for Ris<S> {
    fn default() -> Self {
        Self::new()
    }
}

impl<S: Copy> Ris<S> {
    pub const fn new() -> Self {
        Self {
            w_sum: 0.0,
            confidence: 0.0,
            selected: None,
        }
    }

    /// Streams candidate `y` with target `p̂_r(y)`, resampling weight `w` and confidence `c`;
    /// `u ∈ [0, 1)` decides the selection (`u · w_sum < w`, [001 Alg. 1]).
    ///
    /// Invalid input never poisons the state: a bad `w` or `p̂` drops the candidate's weight but
    /// still counts its confidence (the domain took part in the MIS), a bad `c` counts as 0, and
    /// the first problem is returned as a typed error. A bad `c` counts as 0 and also drops the
    /// weight. A zero confidence is valid.
    pub fn update(
        &mut self,
        y: S,
        target: f32,
        weight: f32,
        confidence: f32,
        u: f32,
    ) -> Result<(), InvalidCandidate> {
        let confidence_ok = confidence.is_finite() && confidence >= 0.0;
        if confidence_ok {
            self.confidence += confidence;
        }
        if !(weight.is_finite() && weight >= 0.0) {
            return Err(InvalidCandidate::Weight(weight));
        }
        if !(target.is_finite() && target >= 0.0) {
            return Err(InvalidCandidate::Target(target));
        }
        if !confidence_ok {
            return Err(InvalidCandidate::Confidence(confidence));
        }
        if weight > 0.0 && target > 0.0 {
            let w_sum = self.w_sum + weight;
            if !w_sum.is_finite() {
                return Err(InvalidCandidate::Weight(weight));
            }
            self.w_sum = w_sum;
            if self.took(weight, u) {
                self.selected = Some((y, target));
            }
        }
        Ok(())
    }

    /// A candidate that produced no sample (failed shift, empty reservoir): weight 0, its
    /// confidence still counts. A NaN, infinite or negative confidence counts as 0.
    pub fn skip(&mut self, confidence: f32) -> Result<(), InvalidCandidate> {
        if confidence.is_finite() && confidence >= 0.0 {
            self.confidence += confidence;
            Ok(())
        } else {
            Err(InvalidCandidate::Confidence(confidence))
        }
    }

    /// Whether the candidate of positive `weight` just streamed with number `u` was selected:
    /// `u · w_sum < w` [001 Alg. 1], `w_sum` including it.
    pub fn took(&self, weight: f32, u: f32) -> bool {
        u * self.w_sum < weight
    }

    pub fn w_sum(&self) -> f32 {
        self.w_sum
    }

    pub fn confidence(&self) -> f32 {
        self.confidence
    }

    /// `W = w_sum / p̂_r(Y)` [001 Alg. 2, line 7], 0 without a sample; `c` is the streamed sum.
    pub fn finish(&self) -> Reservoir<S> {
        match self.selected {
            Some((y, target)) => {
                let ucw = self.w_sum / target;
                if ucw.is_finite() {
                    Reservoir {
                        y: Some(y),
                        ucw,
                        confidence: self.confidence,
                    }
                } else {
                    Reservoir {
                        y: Some(y),
                        ucw: 0.0,
                        confidence: self.confidence,
                    }
                }
            }
            None => Reservoir {
                y: None,
                ucw: 0.0,
                confidence: self.confidence,
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::StreamKey;

    #[test]
    fn first_positive_candidate_is_always_taken_and_ucw_is_wsum_over_target() {
        let mut ris = Ris::new();
        ris.update(1u32, 2.0, 0.0, 1.0, 0.0).unwrap();
        ris.update(2u32, 4.0, 3.0, 1.0, 0.999_999).unwrap();
        let r = ris.finish();
        assert_eq!(r.y, Some(2));
        assert_eq!(r.ucw, 3.0 / 4.0);
        assert_eq!(r.confidence, 2.0);
    }

    /// Selection frequencies follow w_i / w_sum: chi-square over 3 candidates, N = 60 000,
    /// α = 1e-3. Negative control: streaming other weights (7:6:3) must be rejected against the
    /// same expectation.
    #[test]
    fn selection_probability_is_proportional_to_weight() {
        let weights = [1.0f32, 2.0, 5.0];
        let n = 60_000;
        let count = |streamed: [f32; 3]| {
            let mut hits = [0.0f64; 3];
            let mut rng = StreamKey::new(0, 0, 0, 7).stream(11);
            for _ in 0..n {
                let mut ris = Ris::new();
                for (i, &w) in streamed.iter().enumerate() {
                    ris.update(i, 1.0, w, 1.0, rng.next_f32()).unwrap();
                }
                hits[ris.finish().y.unwrap()] += 1.0;
            }
            hits
        };
        let expected: Vec<f64> = weights.iter().map(|w| n as f64 * *w as f64 / 8.0).collect();
        let good = crate::stats::chi_square_gof(&count(weights), &expected, 5.0);
        assert!(good.p_value > 1e-3, "α = 1e-3, N = {n}: {good:?}");
        let bad = crate::stats::chi_square_gof(&count([7.0, 6.0, 3.0]), &expected, 5.0);
        assert!(
            bad.p_value < 1e-3,
            "negative control not detected, α = 1e-3, N = {n}: {bad:?}"
        );
    }

    #[test]
    fn invalid_inputs_never_poison_the_reservoir() {
        let mut ris = Ris::new();
        ris.update(0u8, 1.0, 2.0, 1.0, 0.5).unwrap();
        assert!(matches!(
            ris.update(1, 1.0, f32::NAN, 1.0, 0.0),
            Err(InvalidCandidate::Weight(_))
        ));
        assert!(matches!(
            ris.update(1, 1.0, -1.0, 1.0, 0.0),
            Err(InvalidCandidate::Weight(_))
        ));
        assert!(matches!(
            ris.update(1, 1.0, f32::INFINITY, 1.0, 0.0),
            Err(InvalidCandidate::Weight(_))
        ));
        assert!(matches!(
            ris.update(1, f32::NAN, 1.0, 1.0, 0.0),
            Err(InvalidCandidate::Target(_))
        ));
        assert!(matches!(
            ris.update(1, 1.0, 1.0, f32::NAN, 0.0),
            Err(InvalidCandidate::Confidence(_))
        ));
        assert!(matches!(
            ris.skip(-2.0),
            Err(InvalidCandidate::Confidence(_))
        ));
        ris.update(2, 1.0, 0.0, 0.0, 0.0).unwrap();
        let r = ris.finish();
        assert_eq!(r.y, Some(0));
        assert_eq!(r.ucw, 2.0);
        // The valid sample's confidence plus the four candidates with a bad w or p̂ but a valid c.
        assert_eq!(r.confidence, 5.0);
    }

    #[test]
    fn empty_stream_gives_the_empty_reservoir() {
        let r = Ris::<u8>::new().finish();
        assert_eq!(r, Reservoir::empty());
        let mut ris = Ris::<u8>::new();
        ris.skip(3.0).unwrap();
        let r = ris.finish();
        assert_eq!((r.y, r.ucw, r.confidence), (None, 0.0, 3.0));
    }

    #[test]
    fn confidence_cap() {
        assert_eq!(cap_confidence(100.0, 2.0, 20.0), 40.0);
        assert_eq!(cap_confidence(10.0, 2.0, 20.0), 10.0);
    }
}
