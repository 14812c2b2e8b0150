//! Diffusion profiles (DESIGN §4, §9): Burley normalized diffusion with exact ([`burley`]) and
//! approximate ([`xie`]) radius sampling, the Christensen–Burley scale `s(A)` ([`scale`]), the
//! Jensen dipole with Newton sampling ([`dipole`]), and paper 000's single / multiple-only split
//! ([`single_scattering`]).

pub mod burley;
pub mod dipole;
pub mod scale;
pub mod single_scattering;
pub mod xie;

pub use burley::{Burley, R_MAX_QUANTILE};
pub use dipole::{Dipole, Pole};
pub use scale::{ScaleFit, scale_factor};
pub use single_scattering::ScatteringOrders;
pub use xie::Xie;

pub use crate::contract::pt::ProfileKind;

impl ProfileKind {
    /// `burley` or `dipole`.
    pub fn name(self) -> &'static str {
        match self {
            ProfileKind::Burley => "burley",
            ProfileKind::Dipole => "dipole",
        }
    }
}

/// Shared pieces of the sampling tests: keyed streams and binned expectations.
#[cfg(test)]
pub(crate) mod test_support {
    use restir::rng::{Stream, StreamKey};

    /// Run seed of the profile sampling tests.
    pub const SEED: u64 = 2001;

    /// The stream of sampling test `purpose` (pass 0x9F0F marks the profile tests).
    pub fn stream(purpose: u32) -> Stream {
        StreamKey {
            pixel: 0,
            frame: 0,
            pass: 0x9F0F,
            purpose,
        }
        .stream(SEED)
    }

    /// `n` radii `sample(u)` from stream `purpose`, `u` by `next_f32` as in the kernels.
    pub fn draw(n: usize, purpose: u32, sample: impl Fn(f32) -> f32) -> Vec<f64> {
        let mut s = stream(purpose);
        (0..n).map(|_| sample(s.next_f32()) as f64).collect()
    }

    /// Bin probabilities of the radius density `pdf` on `[e_k, e_{k+1})` (Simpson with 64
    /// panels, f64), followed by the tail `[e_last, ∞)` as one minus their sum.
    pub fn bin_probabilities(pdf: impl Fn(f32) -> f32, edges: &[f64]) -> Vec<f64> {
        let mut p: Vec<f64> = edges
            .windows(2)
            .map(|w| {
                let (a, b, n) = (w[0], w[1], 64);
                let h = (b - a) / n as f64;
                let f = |r: f64| pdf(r as f32) as f64;
                let inner: f64 = (1..n)
                    .map(|i| f(a + i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 })
                    .sum();
                (f(a) + f(b) + inner) * h / 3.0
            })
            .collect();
        let tail = 1.0 - p.iter().sum::<f64>();
        p.push(tail);
        p
    }

    /// Counts of `samples` in the bins of [`bin_probabilities`] (`edges[0]` must be 0).
    pub fn histogram(samples: &[f64], edges: &[f64]) -> Vec<f64> {
        let mut counts = vec![0.0; edges.len()];
        for &r in samples {
            let k = edges.partition_point(|&e| e <= r).saturating_sub(1);
            counts[k] += 1.0;
        }
        counts
    }
}
