//! The comparison's tables: per method and area as Markdown ([`markdown`]) and CSV ([`csv`]),
//! every number with its 95% interval `value [lo, hi]`; the efficiency of each method over the
//! baseline with its verdict ([`verdict`]); and the per-frame MSE ([`convergence_csv`]).

use std::fmt::Write as _;

use engine::clock::Clock;

use crate::method_result::{Measured, MethodResult};
use crate::metrics::Area;
use crate::uncertainty::{Estimate, Interval};

/// Column names of [`csv`], in order.
pub const CSV_HEADER: &str = "method,spp,mean_spp,replicas,area,pixels,ms_per_frame,ms_per_frame_lo,ms_per_frame_hi,wall_ms_per_frame,wall_ms_per_frame_lo,wall_ms_per_frame_hi,mse,mse_lo,mse_hi,rel_mse,rel_mse_lo,rel_mse_hi,bias,bias_ci99,relative_bias,variance,reference_mse,efficiency,efficiency_lo,efficiency_hi,efficiency_ratio,efficiency_ratio_lo,efficiency_ratio_hi,tonemapped_mse,tonemapped_mse_lo,tonemapped_mse_hi";

/// Column names of [`convergence_csv`], in order.
pub const CONVERGENCE_HEADER: &str = "method,frame,area,pixels,mse,mse_lo,mse_hi,reference_mse";

/// `v` with three significant digits: fixed between 0.01 and 1000, else scientific.
pub fn sig(v: f64) -> String {
    let a = v.abs();
    if !v.is_finite() {
        if v > 0.0 { "∞" } else { "-" }.into()
    } else if a == 0.0 {
        "0".into()
    } else if (0.01..1000.0).contains(&a) {
        let decimals = (2 - a.log10().floor() as i32).max(0) as usize;
        format!("{v:.decimals$}")
    } else {
        format!("{v:.2e}")
    }
}

/// `value [lo, hi]`, or the value alone without an interval; `-` for no value.
pub fn with_ci(m: Option<Measured>) -> String {
    match m {
        None => "-".into(),
        Some(Measured { value, ci: None }) => sig(value),
        Some(Measured {
            value,
            ci: Some(Interval { lo, hi }),
        }) => format!("{} [{}, {}]", sig(value), sig(lo), sig(hi)),
    }
}

/// The verdict of an efficiency ratio over the baseline by its interval: `better` (entirely
/// above 1), `worse` (entirely below), else `inconclusive`.
pub fn verdict_word(ratio: &Measured) -> &'static str {
    match ratio.ci {
        Some(i) if i.above(1.0) => "better",
        Some(i) if i.below(1.0) => "worse",
        _ => "inconclusive",
    }
}

fn relative_bias(r: &MethodResult, area: Area) -> Option<f64> {
    let m = r.area(area)?;
    (m.reference_mean > 0.0).then(|| m.bias / m.reference_mean)
}

/// Milliseconds of seconds `seconds` with its interval.
pub fn milliseconds(seconds: &Estimate) -> Measured {
    let s = Measured::of(seconds);
    Measured {
        value: 1e3 * s.value,
        ci: s.ci.map(|i| Interval {
            lo: 1e3 * i.lo,
            hi: 1e3 * i.hi,
        }),
    }
}

/// What the ms/frame columns measure when `clock` timed the renders ([`engine::clock`]).
pub fn time_note(clock: Clock) -> String {
    format!(
        "ms/frame: {} per rendered frame, over every frame of each replica (what equal-time \
         budgets and efficiencies count); wall ms/frame: the same renders on the wall clock, \
         reported only.",
        clock.name()
    )
}

/// The Markdown table: per method and area, MSE and relMSE (the reference's variance
/// subtracted), bias ± 99% CI (also relative to the reference mean), ms/frame on the backend's
/// clock and on the wall clock ([`time_note`]), efficiency `1/(MSE·s)` and its ratio to
/// `baseline`, each with its 95% interval; the whole-frame
/// (`image`) row also carries paper 001's tonemapped 8-bit MSE.
pub fn markdown(results: &[MethodResult], baseline: Option<&MethodResult>) -> String {
    let base = baseline.map_or("baseline".into(), |b| b.label());
    let mut out = format!(
        "| method | spp | area | px | MSE [95% CI] | relMSE [95% CI] | bias ± 99% CI | rel. bias | ms/frame [95% CI] | wall ms/frame [95% CI] | efficiency [95% CI] | eff. / {base} [95% CI] | TM-8bit MSE [95% CI] |\n\
         |---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n"
    );
    for r in results {
        for m in &r.metrics {
            let bias = match m.bias_ci {
                Some(ci) => format!("{:+.2e} ± {ci:.1e}", m.bias),
                None => format!("{:+.2e}", m.bias),
            };
            let rel =
                relative_bias(r, m.area).map_or("-".into(), |b| format!("{:+.2}%", 100.0 * b));
            let tm = if m.area == Area::Image {
                with_ci(Some(Measured::of(&r.tonemapped_mse)))
            } else {
                String::new()
            };
            let _ = writeln!(
                out,
                "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
                r.label(),
                spp_cell(r),
                m.area.name(),
                m.pixels,
                with_ci(Some(Measured::of(&m.mse))),
                with_ci(Some(Measured::of(&m.rel_mse))),
                bias,
                rel,
                with_ci(Some(milliseconds(&r.seconds))),
                with_ci(Some(milliseconds(&r.wall_seconds))),
                with_ci(r.efficiency(m.area)),
                with_ci(baseline.and_then(|b| r.efficiency_ratio(b, m.area))),
                tm,
            );
        }
    }
    out
}

/// The efficiency of every other method over `baseline` per area, `ratio [lo, hi] verdict`
/// ([`verdict_word`]), as Markdown; empty without a baseline.
pub fn verdict(results: &[MethodResult], baseline: Option<&MethodResult>) -> String {
    let Some(b) = baseline else {
        return String::new();
    };
    let areas: Vec<Area> = Area::ALL
        .into_iter()
        .filter(|&a| b.area(a).is_some())
        .collect();
    let names: Vec<&str> = areas.iter().map(|a| a.name()).collect();
    let mut out = format!(
        "Efficiency over {} (ratio of 1/(MSE·s) per frame, 95% CI over replicas; > 1: more \
         efficient; the verdict is the interval's):\n\n| method | {} |\n|---|{}\n",
        b.label(),
        names.join(" | "),
        "---:|".repeat(areas.len())
    );
    for r in results.iter().filter(|r| r.method != b.method) {
        let cells: Vec<String> = areas
            .iter()
            .map(|&a| match r.efficiency_ratio(b, a) {
                Some(m) => format!("{} {}", with_ci(Some(m)), verdict_word(&m)),
                None => "-".into(),
            })
            .collect();
        let _ = writeln!(out, "| {} | {} |", r.label(), cells.join(" | "));
    }
    out
}

/// The denoiser's milliseconds per frame of each denoised row with its 95% interval, as
/// Markdown.
pub fn denoiser_time(results: &[MethodResult]) -> String {
    let mut out = String::from("| method | denoiser ms/frame [95% CI] |\n|---|---:|\n");
    for r in results {
        if let Some(s) = &r.denoiser_seconds {
            let _ = writeln!(
                out,
                "| {} | {} |",
                r.label(),
                with_ci(Some(milliseconds(s)))
            );
        }
    }
    out
}

/// FLIP and the low-frequency error per method and area at the last frame, each with its 95%
/// interval over replicas, as Markdown ([`crate::perceptual`]); rows of every group given.
pub fn perceptual(results: &[MethodResult]) -> String {
    let mut out = format!(
        "FLIP (LDR, after the tonemap; 0 = identical) and the low-frequency error (MSE after a \
         Gaussian blur of σ = {} px, the reference's blurred noise subtracted), last frame, 95% CI \
         over replicas:\n\n| method | area | FLIP [95% CI] | low-freq. MSE [95% CI] |\n\
         |---|---|---:|---:|\n",
        crate::low_frequency::SIGMA_PIXELS
    );
    for r in results {
        for m in &r.perceptual {
            let _ = writeln!(
                out,
                "| {} | {} | {} | {} |",
                r.label(),
                m.area.name(),
                with_ci(Some(Measured::of(&m.flip))),
                with_ci(Some(Measured::of(&m.low_frequency))),
            );
        }
    }
    out
}

/// The flicker of every row that has one ([`crate::flicker`]) per area with its interval, and
/// the references' own frame-to-frame change (`reference`) as the scale; a line saying why
/// when no row has one.
pub fn flicker(results: &[MethodResult], reference: &[(Area, f64)]) -> String {
    if results.iter().all(|r| r.flicker.is_empty()) {
        return "Flicker: not measured (it needs every frame's reference: a convergence record).\n"
            .into();
    }
    let mut out = String::from(
        "Flicker: mean over frames and pixels of |e_t − e_{t−1}|, e_t = Y(I_t) − Y(R_t) the \
         luminance error of frame t against its reference (lower: steadier), 95% CI over \
         replicas; the reference row is its own change |Y(R_t) − Y(R_{t−1})|, the camera's \
         motion plus its noise:\n\n| method | area | flicker [95% CI] |\n|---|---|---:|\n",
    );
    for (area, change) in reference {
        let _ = writeln!(out, "| reference | {} | {} |", area.name(), sig(*change));
    }
    for r in results {
        for f in &r.flicker {
            let _ = writeln!(
                out,
                "| {} | {} | {} |",
                r.label(),
                f.area.name(),
                with_ci(Some(Measured::of(&f.flicker)))
            );
        }
    }
    out
}

/// CSV cells of an optional measured number: value, lo, hi (empty when absent).
fn cells(m: Option<Measured>) -> String {
    let cell = |v: Option<f64>| v.map_or(String::new(), |v| format!("{v:e}"));
    let ci = m.and_then(|m| m.ci);
    format!(
        "{},{},{}",
        cell(m.map(|m| m.value)),
        cell(ci.map(|i| i.lo)),
        cell(ci.map(|i| i.hi))
    )
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

/// The rows of [`markdown`] as CSV with [`CSV_HEADER`]; empty cells for values that do not
/// exist.
pub fn csv(results: &[MethodResult], baseline: Option<&MethodResult>) -> String {
    let mut out = format!("{CSV_HEADER}\n");
    let cell = |v: Option<f64>| v.map_or(String::new(), |v| format!("{v:e}"));
    for r in results {
        for m in &r.metrics {
            let _ = writeln!(
                out,
                "{},{},{},{},{},{},{},{},{},{},{:e},{},{},{},{:e},{},{},{}",
                r.label(),
                r.spp,
                r.mean_spp,
                r.replicas,
                m.area.name(),
                m.pixels,
                cells(Some(milliseconds(&r.seconds))),
                cells(Some(milliseconds(&r.wall_seconds))),
                cells(Some(Measured::of(&m.mse))),
                cells(Some(Measured::of(&m.rel_mse))),
                m.bias,
                cell(m.bias_ci),
                cell(relative_bias(r, m.area)),
                cell(m.variance),
                m.reference_mse,
                cells(r.efficiency(m.area)),
                cells(baseline.and_then(|b| r.efficiency_ratio(b, m.area))),
                cells(Some(Measured::of(&r.tonemapped_mse))),
            );
        }
    }
    out
}

/// The MSE of every method, frame and area with its interval, as CSV with
/// [`CONVERGENCE_HEADER`].
pub fn convergence_csv(results: &[MethodResult]) -> String {
    let mut out = format!("{CONVERGENCE_HEADER}\n");
    for r in results {
        for f in &r.convergence {
            for m in &f.metrics {
                let _ = writeln!(
                    out,
                    "{},{},{},{},{},{:e}",
                    r.method,
                    f.frame,
                    m.area.name(),
                    m.pixels,
                    cells(Some(Measured::of(&m.mse))),
                    m.reference_mse
                );
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flicker::AreaFlicker;
    use crate::method_result::FrameMetrics;
    use crate::metrics::AreaMetrics;
    use crate::regions::Region;
    use crate::uncertainty::Estimate;

    /// Two replicas with MSE `mse · (1 ± 0.1)` and 0.5 s/frame ± 0.05.
    fn result(method: &str, mse: f64) -> MethodResult {
        let m = |area| AreaMetrics {
            area,
            pixels: 10,
            replicas: 2,
            mse: Estimate::mean(&[0.9 * mse, 1.1 * mse]),
            rel_mse: Estimate::mean(&[mse, mse]),
            reference_mean: 0.5,
            bias: 0.01,
            bias_ci: Some(0.02),
            variance: Some(mse),
            reference_mse: 0.0,
        };
        let metrics = vec![m(Area::Image), m(Area::Region(Region::Shadowed))];
        MethodResult {
            method: method.into(),
            denoiser: None,
            spp: 1,
            mean_spp: 1.0,
            replicas: 2,
            seconds: Estimate::mean(&[0.45, 0.55]),
            wall_seconds: Estimate::mean(&[0.25, 0.3]),
            denoiser_seconds: None,
            frames_rendered: 16,
            convergence: vec![FrameMetrics {
                frame: 15,
                metrics: metrics.clone(),
            }],
            metrics,
            tonemapped_mse: Estimate::mean(&[0.25, 0.25]),
            perceptual: Vec::new(),
            nonfinite: 0,
            flicker: vec![AreaFlicker {
                area: Area::Image,
                flicker: Estimate::mean(&[0.01, 0.03]),
            }],
        }
    }

    #[test]
    fn the_flicker_table_has_the_reference_and_every_measured_row() {
        let text = flicker(&[result("pt", 0.1)], &[(Area::Image, 0.5)]);
        assert!(text.contains("| reference | image | 0.500 |"), "{text}");
        // Mean 0.02, s.e. 0.01, t_1(0.975) = 12.706.
        assert!(
            text.contains("| pt | image | 0.0200 [-0.107, 0.147] |"),
            "{text}"
        );
        let none = MethodResult {
            flicker: Vec::new(),
            ..result("pt", 0.1)
        };
        assert!(flicker(&[none], &[]).starts_with("Flicker: not measured"));
    }

    #[test]
    fn numbers_print_with_three_significant_digits() {
        assert_eq!(sig(0.5234), "0.523");
        assert_eq!(sig(12.345), "12.3");
        assert_eq!(sig(1.0), "1.00");
        assert_eq!(sig(0.001234), "1.23e-3");
        assert_eq!(sig(f64::INFINITY), "∞");
        let m = Measured {
            value: 2.0,
            ci: Some(Interval { lo: 1.5, hi: 2.5 }),
        };
        assert_eq!(with_ci(Some(m)), "2.00 [1.50, 2.50]");
        assert_eq!(verdict_word(&m), "better");
    }

    #[test]
    fn tables_have_one_row_per_method_and_area_with_intervals() {
        let results = [result("pt:1", 0.2), result("restir:hybrid", 0.1)];
        let baseline = Some(&results[0]);
        let md = markdown(&results, baseline);
        assert_eq!(md.lines().count(), 2 + 4, "{md}");
        // MSE 0.1 from {0.09, 0.11}: s.e. 0.01, t_1(0.975) = 12.706 → [-0.027, 0.227].
        assert!(
            md.contains("| restir:hybrid | 1 | shadowed | 10 | 0.100 [-0.0271, 0.227] |"),
            "{md}"
        );
        assert!(md.contains("| eff. / pt:1 [95% CI] |"), "{md}");
        assert!(md.contains("+2.00%"), "relative bias 0.01/0.5: {md}");
        let adaptive = MethodResult {
            spp: 64,
            mean_spp: 12.34,
            ..result("adaptive", 0.1)
        };
        assert!(
            markdown(&[adaptive], None).contains("| adaptive | 12.3 ≤ 64 | image |"),
            "a method that chooses its counts shows their mean and maximum"
        );
        let csv = csv(&results, baseline);
        let columns = CSV_HEADER.split(',').count();
        assert_eq!(csv.lines().count(), 1 + 4);
        for line in csv.lines() {
            assert_eq!(line.split(',').count(), columns, "{line}");
        }
        // Efficiency = 1 / (0.2 · 0.5) = 10 (column 24), from the clock's seconds, not the
        // wall's (0.275 s, column 10); the tonemapped MSE has no spread.
        let row = csv.lines().nth(1).unwrap();
        let column = |i: usize| -> f64 { row.split(',').nth(i).unwrap().parse().unwrap() };
        assert!((column(23) - 10.0).abs() < 1e-9, "{row}");
        assert!((column(9) - 275.0).abs() < 1e-9, "{row}");
        assert!(row.ends_with(",2.5e-1,2.5e-1,2.5e-1"), "{row}");
        let v = verdict(&results, baseline);
        assert!(v.contains("| restir:hybrid | 2.00 ["), "{v}");
        assert!(
            !v.contains("| pt:1 |"),
            "no row for the baseline itself: {v}"
        );
        assert_eq!(verdict(&results, None), "");
        let conv = convergence_csv(&results);
        assert_eq!(conv.lines().count(), 1 + 4);
        assert!(
            conv.contains("restir:hybrid,15,shadowed,10,1e-1,"),
            "{conv}"
        );
    }
}
