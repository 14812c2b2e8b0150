//! The rows of a bias test as a Markdown table ([`Table`]).

use std::fmt::{self, Write as _};

use super::BiasRow;

/// The rows as a Markdown table (relative bias, CI and its half-width in percent; δ, the CI's
/// confidence to six decimals of a percent and N on every row).
pub struct Table<'a>(pub &'a [BiasRow]);

impl fmt::Display for Table<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "| method | region | channel | pixels | N | mean | reference ± s.e. | bias | CI | ±half | δ | confidence | p(bias=0) | Holm | verdict |"
        )?;
        writeln!(
            f,
            "|---|---|---|---:|---:|---:|---:|---:|---|---:|---:|---:|---:|---|---|"
        )?;
        for row in self.0 {
            let e = &row.equivalence;
            let mut line = String::new();
            write!(
                line,
                "| {} | {} | {} | {} | {} | {:.5} | {:.5} ± {:.5} | {:+.2}% | [{:+.2}%, {:+.2}%] | {:.2}% | ±{}% | {}% | {:.2e} | {} | {} |",
                row.method,
                row.region,
                row.channel,
                row.pixels,
                e.n,
                row.estimate.mean,
                row.reference.mean,
                row.reference.std_err,
                100.0 * e.relative_bias,
                100.0 * e.ci_low,
                100.0 * e.ci_high,
                100.0 * row.ci_half_width(),
                100.0 * e.delta,
                (1e8 * e.confidence).round() / 1e6,
                e.p_zero_bias,
                if row.holm_rejected { "reject" } else { "-" },
                row.verdict.describe(e.delta, e.confidence),
            )?;
            writeln!(f, "{line}")?;
        }
        Ok(())
    }
}
