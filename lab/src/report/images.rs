//! Images a comparison writes: the reference, each method's final frame (EXR + PNG through
//! `engine::Image`), its absolute and relative error maps as false-colour PNGs with labelled
//! colour bars, on one scale shared by all methods, its FLIP map (FLIP's own colour map, 0 to 1)
//! and its low-frequency error map ([`crate::perceptual`]), also on one shared scale
//! ([`write_comparison_images`]).

use std::path::Path;

use engine::Image;
use sss::integrator::Reference;

use super::results::{ErrorMapScale, ImageFiles};
use crate::draw::{false_colour_map, quantile};
use crate::error::Error;
use crate::flip::write_flip_map;
use crate::low_frequency;
use crate::metrics::error_maps;
use crate::output::file_stem;
use crate::perceptual::Maps;
use crate::reference_cache::{FrameReference, mean_image};

/// Writes `reference.exr`/`.png` and, per method `(name, replica-0 final frame)`, its frame and
/// error maps into `out`; every map of a kind is scaled to the 99th percentile of all methods'
/// errors (FLIP's to its own range [0, 1]). Returns the files per method, in order, and the
/// scales.
pub fn write_comparison_images(
    out: &Path,
    methods: &[(&str, &Image)],
    reference: &Reference,
) -> Result<(Vec<ImageFiles>, ErrorMapScale), Error> {
    let mean = reference.mean();
    let reference_image = mean_image(reference);
    reference_image.write_exr(out.join("reference.exr"))?;
    reference_image.write_png(out.join("reference.png"))?;
    let frame_reference = FrameReference::new(reference);
    let maps: Vec<(&str, &Image, Vec<f64>, Vec<f64>, Maps)> = methods
        .iter()
        .filter_map(|&(spec, image)| {
            let (abs, rel) = error_maps(image, &mean)?;
            Some((spec, image, abs, rel, Maps::new(image, &frame_reference)?))
        })
        .collect();
    let all_abs: Vec<f64> = maps.iter().flat_map(|m| m.2.iter().copied()).collect();
    let all_rel: Vec<f64> = maps.iter().flat_map(|m| m.3.iter().copied()).collect();
    let all_low: Vec<f64> = maps
        .iter()
        .flat_map(|m| m.4.low_frequency.iter().copied())
        .collect();
    let scale = ErrorMapScale {
        absolute: quantile(&all_abs, 0.99),
        relative: quantile(&all_rel, 0.99),
        low_frequency: quantile(&all_low, 0.99),
    };
    let mut written = Vec::new();
    for (spec, image, abs, rel, perceptual) in &maps {
        let stem = file_stem(spec);
        let files = ImageFiles {
            final_exr: format!("{stem}.exr"),
            final_png: format!("{stem}.png"),
            abs_error_png: format!("{stem}-abs-error.png"),
            rel_error_png: format!("{stem}-rel-error.png"),
            flip_png: format!("{stem}-flip.png"),
            low_frequency_png: format!("{stem}-low-frequency.png"),
        };
        image.write_exr(out.join(&files.final_exr))?;
        image.write_png(out.join(&files.final_png))?;
        let size = (image.width, image.height);
        let title = format!("{spec}: luminance of |I − R|");
        false_colour_map(
            &out.join(&files.abs_error_png),
            abs,
            size,
            scale.absolute,
            &title,
        )?;
        let title = format!("{spec}: |I − R| / (Y(R) + 0.1)");
        false_colour_map(
            &out.join(&files.rel_error_png),
            rel,
            size,
            scale.relative,
            &title,
        )?;
        write_flip_map(
            &out.join(&files.flip_png),
            &perceptual.flip,
            image.width,
            image.height,
        )?;
        let title = format!(
            "{spec}: |G * (I − R)|², σ = {} px",
            low_frequency::SIGMA_PIXELS
        );
        low_frequency::write_map(
            &out.join(&files.low_frequency_png),
            &perceptual.low_frequency,
            size,
            Some(scale.low_frequency),
            &title,
        )?;
        written.push(files);
    }
    Ok((written, scale))
}
