//! Replica summaries: mean, sample variance and standard error (DESIGN §3, "Statistics").

/// Mean, sample variance (n − 1) and standard error of a set of independent replicas.
///
/// Conventions (never NaN from the summary itself; a NaN or ±∞ sample is carried into `mean`
/// and the tests treat it as a defect, see [`welch`](super::welch())):
/// * empty sample: `n = 0`, `mean = 0`, `variance = std_err = ∞` (no information);
/// * one replica: `n = 1`, `mean = x`, `variance = std_err = ∞` (spread unknown);
/// * replicas that are all equal: `variance = std_err = 0`, flagged by [`Summary::no_spread`];
/// * [`Summary::exact`]: `n = 0`, `variance = std_err = 0`, a constant without sampling error.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Summary {
    pub n: usize,
    pub mean: f64,
    pub variance: f64,
    pub std_err: f64,
}

impl Summary {
    /// Two-pass mean and unbiased variance of `xs`.
    pub fn from_samples(xs: &[f64]) -> Summary {
        let n = xs.len();
        if n == 0 {
            return Summary::from_moments(0, 0.0, 0.0);
        }
        let mean = xs.iter().sum::<f64>() / n as f64;
        let m2 = xs.iter().map(|x| (x - mean) * (x - mean)).sum();
        Summary::from_moments(n, mean, m2)
    }

    /// A known constant (an analytic reference): `n = 0`, `variance = std_err = 0`. Tests
    /// against it reduce to one-sample tests; it is distinguished from an empty sample by its
    /// zero (not infinite) standard error.
    pub fn exact(value: f64) -> Summary {
        Summary {
            n: 0,
            mean: value,
            variance: 0.0,
            std_err: 0.0,
        }
    }

    /// Whether this is a sample of at least two replicas that are all equal: its zero standard
    /// error reflects too few replicas (e.g. a region that is black in every replica), not
    /// knowledge, so the tests treat its spread as unknown. [`Summary::exact`] is not one.
    pub fn no_spread(&self) -> bool {
        self.n >= 2 && self.variance == 0.0
    }

    /// `n` samples with mean `mean` and sum of squared deviations `m2`.
    fn from_moments(n: usize, mean: f64, m2: f64) -> Summary {
        if n < 2 {
            return Summary {
                n,
                mean,
                variance: f64::INFINITY,
                std_err: f64::INFINITY,
            };
        }
        let variance = m2 / (n - 1) as f64;
        Summary {
            n,
            mean,
            variance,
            std_err: (variance / n as f64).sqrt(),
        }
    }
}

/// Accumulates replicas one at a time (Welford 1962), for long runs that cannot keep every
/// replica; shards merge exactly with [`Welford::merge`] (Chan, Golub & LeVeque 1979).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Welford {
    n: usize,
    mean: f64,
    m2: f64,
}

impl Welford {
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds one replica.
    pub fn push(&mut self, x: f64) {
        self.n += 1;
        let d = x - self.mean;
        self.mean += d / self.n as f64;
        self.m2 += d * (x - self.mean);
    }

    /// Adds every replica accumulated by `other` (e.g. another seed range of the same run).
    pub fn merge(&mut self, other: &Welford) {
        if other.n == 0 {
            return;
        }
        let n = self.n + other.n;
        let d = other.mean - self.mean;
        let w = other.n as f64 / n as f64;
        self.m2 += other.m2 + d * d * self.n as f64 * w;
        self.mean += d * w;
        self.n = n;
    }

    /// The summary of the replicas pushed so far (same conventions as [`Summary::from_samples`]).
    pub fn summary(&self) -> Summary {
        Summary::from_moments(self.n, self.mean, self.m2)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stats::testing::{normal, stream};

    #[test]
    fn small_samples_are_defined() {
        let empty = Summary::from_samples(&[]);
        assert_eq!((empty.n, empty.mean), (0, 0.0));
        assert_eq!(
            (empty.variance, empty.std_err),
            (f64::INFINITY, f64::INFINITY)
        );
        let one = Summary::from_samples(&[3.5]);
        assert_eq!((one.n, one.mean, one.std_err), (1, 3.5, f64::INFINITY));
        let exact = Summary::exact(2.0);
        assert_eq!((exact.n, exact.mean, exact.std_err), (0, 2.0, 0.0));
        assert_eq!(Welford::new().summary(), empty);
        assert!(Summary::from_samples(&[0.0, 0.0]).no_spread());
        assert!(!exact.no_spread() && !one.no_spread() && !empty.no_spread());
    }

    #[test]
    fn known_sample() {
        // 2, 4, 4, 4, 5, 5, 7, 9: mean 5, Σ(x − 5)² = 32, variance 32/7.
        let s = Summary::from_samples(&[2.0, 4.0, 4.0, 4.0, 5.0, 5.0, 7.0, 9.0]);
        assert_eq!(s.n, 8);
        assert_eq!(s.mean, 5.0);
        assert!((s.variance - 32.0 / 7.0).abs() < 1e-15);
        assert!((s.std_err - (32.0 / 7.0 / 8.0f64).sqrt()).abs() < 1e-15);
    }

    /// Welford, shard merging and the two-pass summary agree on a stream with a large offset
    /// (the case where a naive Σx² − n·mean² loses every digit).
    #[test]
    fn welford_and_merge_match_two_pass() {
        let mut s = stream(1, 11);
        let xs: Vec<f64> = (0..1000).map(|_| 1e8 + normal(&mut s)).collect();
        let two_pass = Summary::from_samples(&xs);
        let mut whole = Welford::new();
        let (mut left, mut right) = (Welford::new(), Welford::new());
        for (i, &x) in xs.iter().enumerate() {
            whole.push(x);
            if i < 377 { left.push(x) } else { right.push(x) }
        }
        left.merge(&right);
        for w in [whole.summary(), left.summary()] {
            assert_eq!(w.n, 1000);
            assert!((w.mean - two_pass.mean).abs() <= 1e-15 * two_pass.mean);
            assert!(
                (w.variance / two_pass.variance - 1.0).abs() < 1e-7,
                "{w:?} vs {two_pass:?}"
            );
        }
        // The naive one-pass formula is the negative control: catastrophic cancellation.
        let naive =
            (xs.iter().map(|x| x * x).sum::<f64>() - 1000.0 * two_pass.mean.powi(2)) / 999.0;
        assert!(
            (naive / two_pass.variance - 1.0).abs() > 1e-3,
            "naive variance {naive}"
        );
    }
}
