//! Drawing helpers shared by every image the lab writes: the bundled font ([`FONT`]), a PNG
//! canvas drawn with `plotters` ([`png`]), pixel replication ([`upscale`]), the viridis-like
//! colour ramp ([`ramp`], [`false_colour`]) and robust scale ([`quantile`]) of false-colour maps, and the
//! false-colour map with its labelled colour bar ([`false_colour_map`]). Text uses the bundled
//! DejaVu Sans (`lab/assets/fonts`).

use std::path::Path;
use std::sync::Once;

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::FontStyle;

use crate::error::Error;

/// The font family every plot's text uses.
pub const FONT: &str = "sans-serif";

/// DejaVu Sans 2.37 (Bitstream Vera licence, `lab/assets/fonts/LICENSE-DejaVu.txt`).
const FONT_BYTES: &[u8] = include_bytes!("../assets/fonts/DejaVuSans.ttf");

/// Registers the bundled font once; plotters looks fonts up by family name.
pub fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The font is compiled in and parses; a failure would leave text undrawn, not panic.
        let _ = plotters::style::register_font(FONT, FontStyle::Normal, FONT_BYTES);
    });
}

/// An error of a drawing into `path`.
pub fn draw_error(path: &Path) -> impl Fn(&dyn std::fmt::Debug) -> Error + '_ {
    move |e| Error::Io(format!("{}: drawing failed: {e:?}", path.display()))
}

/// Draws `draw` on a white `size` canvas and writes it to `path` as an RGB PNG.
pub fn png(
    path: &Path,
    size: (u32, u32),
    draw: impl FnOnce(&DrawingArea<BitMapBackend, Shift>) -> Result<(), Error>,
) -> Result<(), Error> {
    register_font();
    let mut buffer = vec![255u8; size.0 as usize * size.1 as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut buffer, size).into_drawing_area();
        draw(&root)?;
        root.present().map_err(|e| draw_error(path)(&e))?;
    }
    image::save_buffer(path, &buffer, size.0, size.1, image::ColorType::Rgb8)
        .map_err(|e| Error::Io(format!("{}: {e}", path.display())))
}

/// `rgb` (row-major `width × height`, 3 bytes a pixel) enlarged `scale` times by pixel
/// replication, so that single pixels of noise stay visible.
pub fn upscale(rgb: &[u8], width: u32, height: u32, scale: u32) -> Vec<u8> {
    let (w, s) = (width as usize, scale as usize);
    let mut out = Vec::with_capacity(rgb.len() * s * s);
    for y in 0..height as usize {
        let row: Vec<u8> = (0..w)
            .flat_map(|x| {
                let p = &rgb[3 * (y * w + x)..3 * (y * w + x) + 3];
                std::iter::repeat_n(p, s).flatten().copied()
            })
            .collect();
        for _ in 0..s {
            out.extend_from_slice(&row);
        }
    }
    out
}

/// A five-stop approximation of viridis for `t` clamped to [0, 1].
pub fn ramp(t: f64) -> [u8; 3] {
    const STOPS: [[f64; 3]; 5] = [
        [68.0, 1.0, 84.0],
        [59.0, 82.0, 139.0],
        [33.0, 145.0, 140.0],
        [94.0, 201.0, 98.0],
        [253.0, 231.0, 37.0],
    ];
    let x = t.clamp(0.0, 1.0) * 4.0;
    let i = (x.floor() as usize).min(3);
    let f = x - i as f64;
    std::array::from_fn(|c| (STOPS[i][c] * (1.0 - f) + STOPS[i + 1][c] * f).round() as u8)
}

/// The `q`-quantile (0..=1) of the finite values, for colour-map scales robust to fireflies;
/// 0 when there is none.
pub fn quantile(values: &[f64], q: f64) -> f64 {
    let mut finite: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
    if finite.is_empty() {
        return 0.0;
    }
    finite.sort_by(f64::total_cmp);
    let at = ((finite.len() - 1) as f64 * q.clamp(0.0, 1.0)).round() as usize;
    finite[at]
}

/// `values` as RGB bytes on the [`ramp`] from 0 to `max` (> 0); magenta: not finite.
pub fn false_colour(values: &[f64], max: f64) -> Vec<u8> {
    values
        .iter()
        .flat_map(|&v| {
            if v.is_finite() {
                ramp(v / max)
            } else {
                [255, 0, 255]
            }
        })
        .collect()
}

/// A false-colour map (an error map, a sample-count map): `values` (row-major
/// `width × height`) scaled up to at least 256 pixels wide, viridis from 0 to `max` ([`ramp`];
/// magenta: not finite), `title` above and a colour bar with labelled ticks to the right.
pub fn false_colour_map(
    path: &Path,
    values: &[f64],
    (width, height): (u32, u32),
    max: f64,
    title: &str,
) -> Result<(), Error> {
    if values.len() != width as usize * height as usize || width == 0 || height == 0 {
        return Err(Error::Invalid(format!(
            "{}: {} values for a {width}×{height} false-colour map",
            path.display(),
            values.len()
        )));
    }
    let max = if max > 0.0 && max.is_finite() {
        max
    } else {
        1.0
    };
    let scale = 256u32.div_ceil(width).max(1);
    let (w, h) = (width * scale, height * scale);
    let map = upscale(&false_colour(values, max), width, height, scale);
    let fail = draw_error(path);
    png(path, (w + 110, h + 34), |root| {
        root.fill(&WHITE).map_err(|e| fail(&e))?;
        root.draw(&Text::new(title.to_string(), (4, 6), (FONT, 15)))
            .map_err(|e| fail(&e))?;
        let element = BitMapElement::with_owned_buffer((0, 30), (w, h), map)
            .ok_or_else(|| fail(&"map buffer size"))?;
        root.draw(&element).map_err(|e| fail(&e))?;
        let bar = root.margin(30, 4, w as i32 + 8, 0);
        colour_bar(&bar, max).map_err(|e| fail(&e))
    })
}

/// A vertical colour bar from 0 (bottom) to `max` (top) with five labelled ticks.
fn colour_bar(
    area: &DrawingArea<BitMapBackend, Shift>,
    max: f64,
) -> Result<(), DrawingAreaErrorKind<<BitMapBackend<'static> as DrawingBackend>::ErrorType>> {
    let mut chart = ChartBuilder::on(area)
        .margin_top(6)
        .margin_bottom(6)
        .y_label_area_size(0)
        .right_y_label_area_size(70)
        .build_cartesian_2d(0f64..1.0, 0f64..max)?;
    chart
        .configure_mesh()
        .disable_x_mesh()
        .disable_y_mesh()
        .disable_x_axis()
        .y_labels(5)
        .y_label_formatter(&|y| format!("{y:.2e}"))
        .label_style((FONT, 12))
        .draw()?;
    const STEPS: usize = 64;
    chart.draw_series((0..STEPS).map(|i| {
        let (a, b) = (i as f64 / STEPS as f64, (i + 1) as f64 / STEPS as f64);
        let [r, g, bl] = ramp(0.5 * (a + b));
        Rectangle::new(
            [(0.0, a * max), (1.0, b * max)],
            RGBColor(r, g, bl).filled(),
        )
    }))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ramp_is_ordered_and_clamped() {
        assert_eq!(ramp(0.0), [68, 1, 84]);
        assert_eq!(ramp(1.0), [253, 231, 37]);
        assert_eq!(ramp(-3.0), ramp(0.0));
        assert_eq!(ramp(7.0), ramp(1.0));
        // Luminance-like ordering: green grows monotonically along the ramp.
        let greens: Vec<u8> = (0..=20).map(|i| ramp(i as f64 / 20.0)[1]).collect();
        assert!(greens.windows(2).all(|w| w[0] <= w[1]), "{greens:?}");
    }

    #[test]
    fn quantile_ignores_non_finite_values() {
        let values = [3.0, f64::NAN, 1.0, 2.0, f64::INFINITY, 4.0];
        assert_eq!(quantile(&values, 0.0), 1.0);
        assert_eq!(quantile(&values, 1.0), 4.0);
        assert_eq!(quantile(&[], 0.5), 0.0);
    }

    #[test]
    fn upscaling_replicates_pixels() {
        let rgb = [1, 2, 3, 4, 5, 6];
        let big = upscale(&rgb, 2, 1, 2);
        assert_eq!(
            big,
            [
                1, 2, 3, 1, 2, 3, 4, 5, 6, 4, 5, 6, 1, 2, 3, 1, 2, 3, 4, 5, 6, 4, 5, 6
            ]
        );
    }
}
