//! Plots of a comparison, drawn with `plotters` through [`crate::draw`] and written as PNG: the
//! convergence plot (MSE against frame, log y, one line per method with its 95% band, one panel
//! per region; [`convergence`]). [`write_figures`] writes the convergence plot and the inset
//! figure ([`super::figure`]).

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;
use sss::integrator::Reference;

use crate::draw::{FONT, draw_error, png};
use crate::error::Error;
use crate::method_result::{Measured, MethodResult};
use crate::metrics::Area;
use crate::regions::Regions;
use crate::report::results::FigureFiles;

use super::figure;

/// Size of the convergence plot.
const CONVERGENCE_SIZE: (u32, u32) = (1200, 900);

/// Method colours, in method order (Okabe–Ito, distinguishable with colour-vision deficiency).
pub const PALETTE: [RGBColor; 8] = [
    RGBColor(0, 0, 0),
    RGBColor(230, 159, 0),
    RGBColor(86, 180, 233),
    RGBColor(0, 158, 115),
    RGBColor(213, 94, 0),
    RGBColor(0, 114, 178),
    RGBColor(204, 121, 167),
    RGBColor(240, 228, 66),
];

/// Writes `convergence.png` and `figure.png` into `out`: the MSE of every method and area
/// over frames, and the reference and each method's final frame (`finals`, replica 0) with
/// insets of the lit, penumbra and shadowed regions of the last frame's `regions`, labelled
/// with their MSE and efficiency ratio over `baseline`.
pub fn write_figures(
    out: &Path,
    rows: &[MethodResult],
    bands: &[figure::Band],
    reference: &Reference,
    regions: &Regions,
) -> Result<FigureFiles, Error> {
    let files = FigureFiles {
        figure: "figure.png".into(),
        convergence: "convergence.png".into(),
        report: "report.html".into(),
    };
    convergence(&out.join(&files.convergence), rows)?;
    figure::write(&out.join(&files.figure), bands, reference, regions)?;
    Ok(files)
}

/// The convergence plot: per area with pixels (a 2 × 2 grid of the regions), the MSE of every
/// method against frame on a log axis, with its 95% interval as a band.
pub fn convergence(path: &Path, rows: &[MethodResult]) -> Result<(), Error> {
    let areas: Vec<Area> = Area::ALL[1..].to_vec();
    let fail = draw_error(path);
    png(path, CONVERGENCE_SIZE, |root| {
        root.fill(&WHITE).map_err(|e| fail(&e))?;
        let (title, body) = root.split_vertically(40);
        title
            .titled(
                "MSE over the camera trajectory (95% CI over replicas; reference variance subtracted)",
                (FONT, 22),
            )
            .map_err(|e| fail(&e))?;
        for (panel, &area) in body.split_evenly((2, 2)).iter().zip(&areas) {
            convergence_panel(panel, rows, area).map_err(|e| fail(&e))?;
        }
        Ok(())
    })
}

/// `(frame, MSE)` points of `row` in `area`.
fn series(row: &MethodResult, area: Area) -> Vec<(u32, Measured)> {
    row.convergence
        .iter()
        .filter_map(|f| {
            let m = f.metrics.iter().find(|m| m.area == area)?;
            Some((f.frame, Measured::of(&m.mse)))
        })
        .collect()
}

fn convergence_panel(
    panel: &DrawingArea<BitMapBackend, Shift>,
    rows: &[MethodResult],
    area: Area,
) -> Result<(), DrawingAreaErrorKind<<BitMapBackend<'static> as DrawingBackend>::ErrorType>> {
    let all: Vec<Vec<(u32, Measured)>> = rows.iter().map(|r| series(r, area)).collect();
    // The axis spans the estimates (and the intervals' upper ends); a band reaching below it
    // (an interval down to 0) is cut at the bottom.
    let positive = |f: fn(&Measured) -> Option<f64>| {
        all.iter()
            .flatten()
            .filter_map(move |(_, m)| f(m))
            .filter(|v| v.is_finite() && *v > 0.0)
    };
    let lo = positive(|m| Some(m.value)).fold(f64::INFINITY, f64::min);
    let hi = positive(|m| Some(m.ci.map_or(m.value, |i| i.hi))).fold(0.0, f64::max);
    let last = all.iter().flatten().map(|(f, _)| *f).max().unwrap_or(0);
    if !(lo.is_finite() && hi > 0.0) {
        return panel
            .titled(&format!("{}: no pixels", area.name()), (FONT, 18))
            .map(|_| ());
    }
    let (y0, y1) = (lo / 4.0, hi * 1.5);
    let mut chart = ChartBuilder::on(panel)
        .caption(area.name(), (FONT, 20))
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(80)
        .build_cartesian_2d(-0.3f64..last as f64 + 0.3, (y0..y1).log_scale())?;
    chart
        .configure_mesh()
        .x_desc("frame")
        .y_desc("MSE (linear HDR)")
        .x_labels(last as usize + 1)
        .max_light_lines(0)
        .x_label_formatter(&|x| format!("{}", x.round() as i64))
        .y_label_formatter(&|y| format!("{y:.1e}"))
        .label_style((FONT, 14))
        .axis_desc_style((FONT, 15))
        .draw()?;
    for (i, (row, points)) in rows.iter().zip(&all).enumerate() {
        let colour = PALETTE[i % PALETTE.len()];
        let band: Vec<(f64, f64)> = points
            .iter()
            .filter_map(|(f, m)| Some((*f as f64, m.ci?.hi.clamp(y0, y1))))
            .chain(
                points
                    .iter()
                    .rev()
                    .filter_map(|(f, m)| Some((*f as f64, m.ci?.lo.clamp(y0, y1)))),
            )
            .collect();
        chart.draw_series(std::iter::once(Polygon::new(band, colour.mix(0.15))))?;
        let line: Vec<(f64, f64)> = points
            .iter()
            .filter(|(_, m)| m.value > 0.0)
            .map(|(f, m)| (*f as f64, m.value))
            .collect();
        chart
            .draw_series(LineSeries::new(line.clone(), colour.stroke_width(2)))?
            .label(row.method.as_str())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(3))
            });
        chart.draw_series(line.into_iter().map(|p| Circle::new(p, 3, colour.filled())))?;
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .label_font((FONT, 13))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
}
