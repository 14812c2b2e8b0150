//! Statistics for unbiasedness tests (DESIGN §3, "Statistics").
//!
//! The unit of independence is a *replica* (a whole run with its own seed): pixels inside one
//! replica are correlated by reuse. Summaries of replicas feed Welch tests, family-wise
//! corrections, and the [`equivalence`] test, the only test allowed to call an estimator's bias
//! negligible ("equivalent within ±δ"); [`replicas_for`] plans how many replicas it needs.
//! Goodness-of-fit tests check sampling routines against their pdfs.

mod equivalence;
mod gof;
mod power;
mod special;
mod summary;
mod welch;

pub use equivalence::{Equivalence, Verdict, equivalence};
pub use gof::{ChiSquare, Ks, chi_square_from_z, chi_square_gof, ks_one_sample};
pub use power::{EquivalencePlan, family_power, replicas_for};
pub use special::{
    beta_i, binomial_cdf, binomial_interval, chi_square_sf, gamma_p, gamma_q, kolmogorov_sf,
    ln_gamma, normal_cdf, normal_quantile, student_t_cdf, student_t_quantile,
};
pub use summary::{Summary, Welford};
pub use welch::{WelchTest, holm, sidak_alpha, welch};

/// Random variates for the statistical tests of this module, all from keyed streams.
#[cfg(test)]
pub(crate) mod testing {
    use crate::rng::{Stream, StreamKey};

    /// The stream of test `purpose` under `seed` (pass 0x57A7 marks the statistics tests).
    pub fn stream(purpose: u32, seed: u64) -> Stream {
        StreamKey {
            pixel: 0,
            frame: 0,
            pass: 0x57A7,
            purpose,
        }
        .stream(seed)
    }

    /// A standard normal variate by Box–Muller (the cosine branch; `1 − u ∈ (0, 1]` keeps
    /// the logarithm finite).
    pub fn normal(s: &mut Stream) -> f64 {
        let radius = (-2.0 * (1.0 - s.next_f64()).ln()).sqrt();
        radius * (std::f64::consts::TAU * s.next_f64()).cos()
    }
}
