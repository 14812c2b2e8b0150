//! The comparison figure in the style of paper 001 Fig. 6 and 7: the reference on the left with
//! the insets marked, then one row per inset (lit, penumbra, shadowed) and one column per image
//! (the reference, then each method's final frame of replica 0), each crop labelled with its
//! region's MSE and efficiency ratio over the baseline with their 95% intervals. With denoisers,
//! each adds a band of the same rows below, its denoised frames in the methods' columns. The
//! insets are chosen automatically ([`inset`]): the square window with the most pixels of the
//! region.

use std::path::Path;

use engine::Image;
use engine::denoise::Denoiser;
use engine::image::tonemap;
use plotters::prelude::*;
use sss::integrator::Reference;

use crate::draw::{FONT, draw_error, png, upscale};
use crate::error::Error;
use crate::method_result::{Measured, MethodResult};
use crate::metrics::Area;
use crate::reference_cache::mean_image;
use crate::regions::{Region, Regions};

use super::tables::{sig, with_ci};

/// The regions shown as insets, in row order, with the colour of their frame.
pub const INSETS: [(Region, RGBColor); 3] = [
    (Region::Lit, RGBColor(230, 159, 0)),
    (Region::Penumbra, RGBColor(0, 158, 115)),
    (Region::Shadowed, RGBColor(0, 114, 178)),
];

/// Displayed size of a crop, in pixels (at least; crops scale by whole factors).
const CROP: u32 = 160;
/// Width of a column: a crop and its labels.
const COLUMN: u32 = 200;
/// Height of the column titles.
const HEADER: u32 = 32;
/// Height of the labels under each crop.
const LABELS: u32 = 58;

/// A rectangle of pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Rect {
    pub x: u32,
    pub y: u32,
    pub width: u32,
    pub height: u32,
}

/// The `side × side` window (clamped to the image) containing the most pixels of `region`,
/// the first in row-major order among equals; `None` when the region is empty. Counts come
/// from a summed-area table, so every window is considered.
pub fn inset(regions: &Regions, region: Region, side: u32) -> Option<Rect> {
    let (w, h) = (regions.width as usize, regions.height as usize);
    let side = (side as usize).clamp(1, w.min(h));
    let mut table = vec![0u32; (w + 1) * (h + 1)];
    let mut member = vec![false; w * h];
    for p in regions.pixels(region) {
        member[p] = true;
    }
    for y in 0..h {
        for x in 0..w {
            table[(y + 1) * (w + 1) + x + 1] = member[y * w + x] as u32
                + table[y * (w + 1) + x + 1]
                + table[(y + 1) * (w + 1) + x]
                - table[y * (w + 1) + x];
        }
    }
    let count = |x: usize, y: usize| {
        let at = |x: usize, y: usize| table[y * (w + 1) + x];
        at(x + side, y + side) + at(x, y) - at(x + side, y) - at(x, y + side)
    };
    let mut best: Option<(u32, usize, usize)> = None;
    for y in 0..=h - side {
        for x in 0..=w - side {
            let c = count(x, y);
            if c > 0 && best.is_none_or(|(b, _, _)| c > b) {
                best = Some((c, x, y));
            }
        }
    }
    best.map(|(_, x, y)| Rect {
        x: x as u32,
        y: y as u32,
        width: side as u32,
        height: side as u32,
    })
}

/// The tonemapped 8-bit sRGB bytes of `rect` of `image`.
fn crop(image: &Image, rect: Rect) -> Vec<u8> {
    (rect.y..rect.y + rect.height)
        .flat_map(|y| {
            (rect.x..rect.x + rect.width)
                .flat_map(move |x| tonemap(image.pixels[(y * image.width + x) as usize]))
        })
        .collect()
}

/// The labels under a method's crop of `region`: MSE and its interval, then the efficiency
/// ratio over `baseline` with its interval.
fn labels(
    row: Option<&MethodResult>,
    baseline: Option<&MethodResult>,
    region: Area,
) -> Vec<String> {
    let Some(row) = row else {
        return vec!["(no replica)".into()];
    };
    let Some(m) = row.area(region) else {
        return vec!["(region empty)".into()];
    };
    let mse = Measured::of(&m.mse);
    let mut out = vec![format!("MSE {}", sig(mse.value))];
    if let Some(ci) = mse.ci {
        out.push(format!("[{}, {}]", sig(ci.lo), sig(ci.hi)));
    }
    match baseline {
        Some(b) if b.method == row.method => out.push("eff. ×1 (baseline)".into()),
        Some(b) => out.push(format!(
            "eff. ×{}",
            with_ci(row.efficiency_ratio(b, region))
        )),
        None => out.push(format!("eff. {}", with_ci(row.efficiency(region)))),
    }
    out
}

/// One band of rows of the figure: the raw frames (`denoiser` `None`) or one denoiser's.
pub struct Band<'a> {
    pub denoiser: Option<Denoiser>,
    /// The band's results, by spec.
    pub rows: &'a [MethodResult],
    pub baseline: Option<&'a MethodResult>,
    /// `(spec, replica-0 last frame)` per method.
    pub finals: Vec<(&'a str, &'a Image)>,
}

/// Writes the figure (module documentation) to `path`: the first band's methods are the
/// columns; `regions` are those of the last frame.
pub fn write(
    path: &Path,
    bands: &[Band],
    reference: &Reference,
    regions: &Regions,
) -> Result<(), Error> {
    let Some(first) = bands.first() else {
        return Ok(());
    };
    let finals = &first.finals;
    let full = mean_image(reference);
    let (w, h) = (full.width, full.height);
    let side = (w.min(h) / 5).max(4);
    let mut insets: Vec<(Area, RGBColor, Rect)> = INSETS
        .iter()
        .filter_map(|&(r, c)| Some((Area::Region(r), c, inset(regions, r, side)?)))
        .collect();
    if insets.is_empty() {
        let whole = Rect {
            x: 0,
            y: 0,
            width: w,
            height: h,
        };
        insets.push((Area::Image, BLACK, whole));
    }
    let zoom = (CROP / insets[0].2.width.max(insets[0].2.height)).max(1);
    let row_height = insets[0].2.height * zoom + LABELS;
    let band_height = insets.len() as u32 * row_height + HEADER;
    let grid_height = bands.len() as u32 * band_height;
    let left_scale = (grid_height / h).clamp(1, (640 / w).max(1));
    let left_width = w * left_scale + 20;
    let columns = 1 + finals.len() as u32;
    let size = (
        left_width + columns * COLUMN,
        grid_height.max(h * left_scale + HEADER) + 40,
    );
    let fail = draw_error(path);
    png(path, size, |root| {
        root.fill(&WHITE).map_err(|e| fail(&e))?;
        let text = |s: &str, at: (i32, i32), px: u32, colour: &RGBColor| {
            let style = (FONT, px).into_font().color(colour);
            root.draw(&Text::new(s.to_string(), at, style))
                .map_err(|e| fail(&e))
        };
        let blit = |rgb: Vec<u8>, at: (i32, i32), size: (u32, u32)| {
            let element = BitMapElement::with_owned_buffer(at, size, rgb)
                .ok_or_else(|| fail(&"image buffer size"))?;
            root.draw(&element).map_err(|e| fail(&e))
        };
        // The reference with the insets framed.
        let whole = Rect {
            x: 0,
            y: 0,
            width: w,
            height: h,
        };
        text("reference", (0, 8), 16, &BLACK)?;
        let big = upscale(&crop(&full, whole), w, h, left_scale);
        blit(big, (0, HEADER as i32), (w * left_scale, h * left_scale))?;
        for (_, colour, r) in &insets {
            let s = left_scale as i32;
            let (x, y) = (r.x as i32 * s, HEADER as i32 + r.y as i32 * s);
            let corner = (x + r.width as i32 * s - 1, y + r.height as i32 * s - 1);
            root.draw(&Rectangle::new([(x, y), corner], colour.stroke_width(2)))
                .map_err(|e| fail(&e))?;
        }
        // One column per method, one row per inset and band.
        let columns: Vec<&str> = std::iter::once("reference")
            .chain(finals.iter().map(|(name, _)| *name))
            .collect();
        for (b, band) in bands.iter().enumerate() {
            let top = b as u32 * band_height;
            if let Some(d) = band.denoiser {
                let x = left_width as i32;
                text(&format!("denoised: {d}"), (x, top as i32 + 8), 15, &BLACK)?;
            }
            for (c, name) in columns.iter().enumerate() {
                let x = (left_width + c as u32 * COLUMN) as i32;
                let image = match c {
                    0 => Some(&full),
                    _ => band.finals.iter().find(|(n, _)| n == name).map(|(_, i)| *i),
                };
                if b == 0 {
                    text(name, (x, 8), 15, &BLACK)?;
                }
                let Some(image) = image else { continue };
                for (i, (area, colour, r)) in insets.iter().enumerate() {
                    let y = (top + HEADER + i as u32 * row_height) as i32;
                    let (cw, ch) = (r.width * zoom, r.height * zoom);
                    blit(
                        upscale(&crop(image, *r), r.width, r.height, zoom),
                        (x, y),
                        (cw, ch),
                    )?;
                    root.draw(&Rectangle::new(
                        [(x, y), (x + cw as i32 - 1, y + ch as i32 - 1)],
                        colour.stroke_width(2),
                    ))
                    .map_err(|e| fail(&e))?;
                    let lines = if c == 0 {
                        vec![
                            area.name().to_string(),
                            format!("{} spp", reference_spp(reference)),
                        ]
                    } else {
                        let row = band.rows.iter().find(|r| r.method == *name);
                        labels(row, band.baseline, *area)
                    };
                    for (l, line) in lines.iter().enumerate() {
                        text(line, (x, y + ch as i32 + 4 + 17 * l as i32), 13, &BLACK)?;
                    }
                }
            }
        }
        let base = first.baseline.map_or("-".into(), |b| b.method.clone());
        let caption = format!(
            "Last frame, replica 0. Labels: MSE over the whole region (reference variance \
             subtracted) and efficiency 1/(MSE·s) relative to {base} (denoised: to {base} through \
             the same denoiser), with 95% intervals over {} replicas.",
            first.rows.first().map_or(0, |r| r.replicas)
        );
        text(&caption, (0, size.1 as i32 - 28), 14, &BLACK)
    })
}

fn reference_spp(reference: &Reference) -> u64 {
    reference.batches_done() as u64 * reference.config.spp_per_batch as u64
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::regions::VISIBILITY_SAMPLES;

    /// 6 × 4: a shadowed 2 × 2 block at (3, 1), lit elsewhere on the top row, nothing else.
    fn regions() -> Regions {
        let visible = (0..24)
            .map(|p: u32| {
                let (x, y) = (p % 6, p / 6);
                if (3..5).contains(&x) && (1..3).contains(&y) {
                    Some(0)
                } else if y == 0 {
                    Some(VISIBILITY_SAMPLES)
                } else {
                    None
                }
            })
            .collect();
        Regions::from_visible_samples(6, 4, visible).unwrap()
    }

    #[test]
    fn an_inset_frames_the_most_pixels_of_its_region() {
        let r = regions();
        let shadowed = inset(&r, Region::Shadowed, 2).unwrap();
        assert_eq!((shadowed.x, shadowed.y, shadowed.width), (3, 1, 2));
        let lit = inset(&r, Region::Lit, 3).unwrap();
        assert_eq!(
            (lit.x, lit.y),
            (0, 0),
            "first of the windows holding 3 lit pixels"
        );
        assert_eq!(inset(&r, Region::Penumbra, 2), None);
        assert_eq!(inset(&r, Region::Shadowed, 99).unwrap().width, 4, "clamped");
    }
}
