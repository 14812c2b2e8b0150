//! BSSRDF IS techniques: a projection axis times a profile channel [001 §2.1, §4.3].

pub use crate::contract::bssrdf::Axis;
use crate::contract::bssrdf::TECHNIQUE_COUNT;

impl Axis {
    pub const fn index(self) -> usize {
        self.code() as usize
    }
}

/// One of the nine BSSRDF IS techniques: which axis the probe runs along and which channel's
/// profile samples the disk radius (and bounds the chord by its `r_max`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Technique {
    pub axis: Axis,
    /// RGB channel, 0..3.
    pub channel: usize,
}

impl Technique {
    pub const COUNT: usize = TECHNIQUE_COUNT;

    /// All techniques in index order (`axis · 3 + channel`).
    pub const ALL: [Technique; TECHNIQUE_COUNT] = {
        let mut all = [Technique {
            axis: Axis::Normal,
            channel: 0,
        }; TECHNIQUE_COUNT];
        let mut i = 0;
        while i < TECHNIQUE_COUNT {
            all[i] = Technique {
                axis: Axis::ALL[i / 3],
                channel: i % 3,
            };
            i += 1;
        }
        all
    };

    pub const fn index(self) -> usize {
        self.axis.index() * 3 + self.channel
    }
}

/// The selection probabilities `P(a)` and `P(c)` of the one-sample MIS mixture (DESIGN §9).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TechniqueSelection {
    /// `P(a)` for normal, tangent, bitangent; sums to 1.
    pub axis: [f32; 3],
    /// `P(c)` for R, G, B; sums to 1.
    pub channel: [f32; 3],
}

impl Default for TechniqueSelection {
    /// Seed 001's choice: axes 0.5 / 0.25 / 0.25, channels uniform.
    fn default() -> Self {
        TechniqueSelection {
            axis: [0.5, 0.25, 0.25],
            channel: [1.0 / 3.0; 3],
        }
    }
}

impl TechniqueSelection {
    /// Channels picked with probability proportional to `weights` (a channel CDF, e.g. ∝ albedo as
    /// in seed 000), axes as in [`TechniqueSelection::default`]. `None` unless every weight is
    /// finite and ≥ 0 and their sum is > 0.
    pub fn with_channel_weights(weights: [f32; 3]) -> Option<Self> {
        let sum: f32 = weights.iter().sum();
        if weights.iter().any(|w| !(w.is_finite() && *w >= 0.0)) || !(sum > 0.0 && sum.is_finite())
        {
            return None;
        }
        Some(TechniqueSelection {
            channel: weights.map(|w| w / sum),
            ..Self::default()
        })
    }

    /// `P(a) · P(c)`.
    pub fn probability(&self, t: Technique) -> f32 {
        self.axis[t.axis.index()] * self.channel[t.channel]
    }

    /// The technique whose cumulative interval (in index order) contains `u ∈ [0, 1)`.
    /// Techniques of probability 0 are never returned.
    pub fn sample(&self, u: f32) -> Technique {
        let mut cumulative = 0.0;
        let mut last = Technique::ALL[0];
        for t in Technique::ALL {
            let p = self.probability(t);
            if p <= 0.0 {
                continue;
            }
            cumulative += p;
            last = t;
            if u < cumulative {
                return t;
            }
        }
        last
    }

    /// Inverse of [`TechniqueSelection::sample`]: the interval `[lo, hi)` of `u` that selects `t`.
    pub fn u_interval(&self, t: Technique) -> (f32, f32) {
        let lo: f32 = Technique::ALL[..t.index()]
            .iter()
            .map(|&s| self.probability(s))
            .sum();
        (lo, lo + self.probability(t))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use restir::rng::StreamKey;

    #[test]
    fn indices_round_trip_and_probabilities_sum_to_one() {
        let sel = TechniqueSelection::default();
        let total: f32 = Technique::ALL.iter().map(|&t| sel.probability(t)).sum();
        assert!((total - 1.0).abs() < 1e-6, "Σ P(a)P(c) = {total}");
        for (i, t) in Technique::ALL.into_iter().enumerate() {
            assert_eq!(t.index(), i);
        }
        assert!(TechniqueSelection::with_channel_weights([1.0, -1.0, 1.0]).is_none());
        assert!(TechniqueSelection::with_channel_weights([0.0; 3]).is_none());
        assert!(TechniqueSelection::with_channel_weights([f32::NAN, 1.0, 1.0]).is_none());
    }

    /// `sample(u)` lands in `u_interval` of the returned technique, and the interval lengths are
    /// the probabilities (checked on u's at interval midpoints and on random u's).
    #[test]
    fn sample_and_interval_are_inverse() {
        let sel = TechniqueSelection::with_channel_weights([0.7, 0.2, 0.1]).unwrap();
        for t in Technique::ALL {
            let (lo, hi) = sel.u_interval(t);
            assert!((hi - lo - sel.probability(t)).abs() < 1e-7);
            assert_eq!(sel.sample(0.5 * (lo + hi)), t);
        }
        let mut rng = StreamKey::new(0, 0, 0, 0x7EC).stream(1);
        for _ in 0..10_000 {
            let u = rng.next_f32();
            let (lo, hi) = sel.u_interval(sel.sample(u));
            assert!(lo <= u && u < hi + 1e-6, "u = {u} outside [{lo}, {hi})");
        }
        // A zero-probability channel is never picked, even at interval boundaries.
        let no_blue = TechniqueSelection::with_channel_weights([1.0, 1.0, 0.0]).unwrap();
        assert!((0..=1000).all(|i| no_blue.sample(i as f32 / 1001.0).channel != 2));
    }
}
