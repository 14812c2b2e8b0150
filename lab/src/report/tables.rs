//! The comparison table of `reshift compare` as Markdown and CSV: one row per method and area.

use std::fmt::Write as _;

use crate::method_result::MethodResult;
use crate::metrics::{AreaMetrics, efficiency};

/// Column names of [`csv`], in order.
pub const CSV_HEADER: &str = "method,spp,mean_spp,replicas,area,pixels,ms_per_frame,mse,mse_ci99,rel_mse,bias,bias_ci99,relative_bias,variance,reference_mse,efficiency,tonemapped_mse,tonemapped_rmse";

/// `mse` relative to the row with the lowest `mse` in the same area, e.g. `×1.00` for the best.
fn rank(results: &[MethodResult], row: &AreaMetrics) -> String {
    let best = results
        .iter()
        .filter_map(|r| r.metrics.iter().find(|m| m.area == row.area))
        .map(|m| m.mse)
        .fold(f64::INFINITY, f64::min);
    if best > 0.0 && best.is_finite() {
        format!("×{:.2}", row.mse / best)
    } else {
        "-".into()
    }
}

fn relative_bias(m: &AreaMetrics) -> Option<f64> {
    (m.reference_mean > 0.0).then(|| m.bias / m.reference_mean)
}

fn opt(v: Option<f64>, digits: usize) -> String {
    v.map_or("-".into(), |v| format!("{v:.digits$e}"))
}

/// The Markdown table: per method and area, MSE (and its ratio to the best method in that
/// area), relMSE, bias ± 99% CI (relative to the reference mean), per-pixel variance,
/// ms/frame and efficiency `1/(MSE·s)`; the whole-frame (`image`) row also carries seed 001's
/// tonemapped 8-bit MSE and RMSE.
pub fn markdown(results: &[MethodResult]) -> String {
    let mut out = String::new();
    out.push_str(
        "| method | spp | area | px | MSE ± 99% CI | vs best | relMSE | bias ± 99% CI | rel. bias | variance | ms/frame | efficiency | TM-8bit RMSE |\n\
         |---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    for r in results {
        for m in &r.metrics {
            let bias = match m.bias_ci {
                Some(ci) => format!("{:+.2e} ± {ci:.1e}", m.bias),
                None => format!("{:+.2e}", m.bias),
            };
            let mse = match m.mse_ci {
                Some(ci) => format!("{:.3e} ± {ci:.1e}", m.mse),
                None => format!("{:.3e}", m.mse),
            };
            let rel = relative_bias(m).map_or("-".into(), |b| format!("{:+.2}%", 100.0 * b));
            let tm = if m.area == crate::metrics::Area::Image {
                format!("{:.4}", r.tonemapped_mse.sqrt())
            } else {
                String::new()
            };
            let _ = writeln!(
                out,
                "| {} | {} | {} | {} | {} | {} | {:.3e} | {} | {} | {} | {:.1} | {} | {} |",
                r.method,
                spp_cell(r),
                m.area.name(),
                m.pixels,
                mse,
                rank(results, m),
                m.rel_mse,
                bias,
                rel,
                opt(m.variance, 2),
                1e3 * r.seconds_per_frame,
                opt(efficiency(m.mse, r.seconds_per_frame), 2),
                tm,
            );
        }
    }
    out
}

/// The `spp` cell: the method's spp, or `mean ≤ max` for a method that chooses its counts per
/// pixel.
fn spp_cell(r: &MethodResult) -> String {
    if r.mean_spp == r.spp as f64 {
        r.spp.to_string()
    } else {
        format!("{:.1} ≤ {}", r.mean_spp, r.spp)
    }
}

/// The same rows as CSV with [`CSV_HEADER`]; empty cells for values that do not exist.
pub fn csv(results: &[MethodResult]) -> String {
    let mut out = format!("{CSV_HEADER}\n");
    let cell = |v: Option<f64>| v.map_or(String::new(), |v| format!("{v:e}"));
    for r in results {
        for m in &r.metrics {
            let _ = writeln!(
                out,
                "{},{},{},{},{},{},{},{:e},{},{:e},{:e},{},{},{},{:e},{},{:e},{:e}",
                r.method,
                r.spp,
                r.mean_spp,
                r.replicas,
                m.area.name(),
                m.pixels,
                1e3 * r.seconds_per_frame,
                m.mse,
                cell(m.mse_ci),
                m.rel_mse,
                m.bias,
                cell(m.bias_ci),
                cell(relative_bias(m)),
                cell(m.variance),
                m.reference_mse,
                cell(efficiency(m.mse, r.seconds_per_frame)),
                r.tonemapped_mse,
                r.tonemapped_mse.sqrt(),
            );
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metrics::Area;
    use crate::regions::Region;

    fn result(method: &str, mse: f64) -> MethodResult {
        let m = |area| AreaMetrics {
            area,
            pixels: 10,
            replicas: 2,
            mse,
            mse_ci: Some(0.1 * mse),
            rel_mse: mse,
            reference_mean: 0.5,
            bias: 0.01,
            bias_ci: Some(0.02),
            variance: Some(mse),
            reference_mse: 0.0,
        };
        MethodResult {
            method: method.into(),
            spp: 1,
            mean_spp: 1.0,
            replicas: 2,
            seconds_per_frame: 0.5,
            frames_rendered: 16,
            metrics: vec![m(Area::Image), m(Area::Region(Region::Shadowed))],
            tonemapped_mse: 0.25,
            nonfinite: 0,
        }
    }

    #[test]
    fn tables_have_one_row_per_method_and_area() {
        let results = [result("pt:1", 0.2), result("restir:hybrid", 0.1)];
        let md = markdown(&results);
        assert_eq!(md.lines().count(), 2 + 4, "{md}");
        assert!(
            md.contains("| restir:hybrid | 1 | shadowed | 10 | 1.000e-1 ± 1.0e-2 | ×1.00 |"),
            "{md}"
        );
        assert!(
            md.contains("| pt:1 | 1 | image | 10 | 2.000e-1 ± 2.0e-2 | ×2.00 |"),
            "{md}"
        );
        assert!(md.contains("+2.00%"), "relative bias 0.01/0.5: {md}");
        let adaptive = MethodResult {
            spp: 64,
            mean_spp: 12.34,
            ..result("adaptive", 0.1)
        };
        assert!(
            markdown(&[adaptive]).contains("| adaptive | 12.3 ≤ 64 | image |"),
            "a method that chooses its counts shows their mean and maximum"
        );
        let csv = csv(&results);
        let columns = CSV_HEADER.split(',').count();
        assert_eq!(csv.lines().count(), 1 + 4);
        for line in csv.lines() {
            assert_eq!(line.split(',').count(), columns, "{line}");
        }
        // efficiency = 1 / (0.2 · 0.5) = 10; tonemapped RMSE = √0.25 = 0.5.
        assert!(
            csv.lines().nth(1).unwrap().ends_with(",1e1,2.5e-1,5e-1"),
            "{csv}"
        );
    }
}
