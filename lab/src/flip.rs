//! FLIP [Andersson et al. 2020, "FLIP: A Difference Evaluator for Alternating Images"]: the
//! perceived difference between a method's frame and the reference, per pixel in [0, 1], through
//! the `nv-flip` crate (bindings to NVIDIA's C++ FLIP 1.2).
//!
//! Both images are shown as a viewer sees them: tonemapped with [`engine::image::tonemap`]
//! (Reinhard, sRGB, 8 bits), then compared with LDR-FLIP at [`PIXELS_PER_DEGREE`]. Only LDR-FLIP
//! is offered: `nv-flip` 0.1 takes 8-bit sRGB images only and does not expose HDR-FLIP (its
//! exposure range and tonemapper).

use std::path::Path;

use engine::Image;
use engine::image::{WriteError, tonemap};
use glam::DVec3;
use nv_flip::{FlipImageFloat, FlipImageRgb8};

use crate::error::Error;

/// Pixels per degree of visual angle: `nv-flip`'s default viewing condition, about a 0.7 m wide
/// 3840-pixel monitor seen from 0.7 m (`flip-evaluator`'s default of the same condition is
/// 67.02).
pub const PIXELS_PER_DEGREE: f32 = nv_flip::DEFAULT_PIXELS_PER_DEGREE;

/// The LDR-FLIP error of `image` against `reference` (the reference's per-pixel mean), both
/// tonemapped: row-major, one value in [0, 1] per pixel. `None` when the sizes disagree or the
/// image is empty.
pub fn flip_map(image: &Image, reference: &[DVec3]) -> Option<Vec<f32>> {
    let n = image.width as usize * image.height as usize;
    if n == 0 || image.pixels.len() != n || reference.len() != n {
        return None;
    }
    let test: Vec<u8> = image.pixels.iter().flat_map(|&c| tonemap(c)).collect();
    let reference: Vec<u8> = reference
        .iter()
        .flat_map(|c| tonemap(c.as_vec3()))
        .collect();
    let (w, h) = (image.width, image.height);
    let map = nv_flip::flip(
        FlipImageRgb8::with_data(w, h, &reference),
        FlipImageRgb8::with_data(w, h, &test),
        PIXELS_PER_DEGREE,
    );
    Some(map.to_vec())
}

/// The mean of `map` over `pixels` (indices into it, e.g. a region's); 0 for no pixels.
pub fn area_mean(map: &[f32], pixels: &[usize]) -> f64 {
    if pixels.is_empty() {
        return 0.0;
    }
    pixels.iter().map(|&p| map[p] as f64).sum::<f64>() / pixels.len() as f64
}

/// Writes `map` (`width × height`, row-major) as a PNG in FLIP's magma colour map (black: no
/// difference, light yellow: 1), as FLIP's own tool shows it.
pub fn write_flip_map(path: &Path, map: &[f32], width: u32, height: u32) -> Result<(), Error> {
    let failed = |reason: String| {
        Error::Image(WriteError {
            path: path.to_path_buf(),
            reason,
        })
    };
    if width == 0 || height == 0 || map.len() != width as usize * height as usize {
        return Err(failed(format!(
            "{} FLIP values for a {width}×{height} map",
            map.len()
        )));
    }
    let coloured =
        FlipImageFloat::with_data(width, height, map).apply_color_lut(&nv_flip::magma_lut());
    let rgb = image::RgbImage::from_raw(width, height, coloured.to_vec())
        .ok_or_else(|| failed("colour-mapped FLIP image of the wrong size".into()))?;
    rgb.save(path).map_err(|e| failed(e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// A 64×64 frame: a bright disc of radius 10 at the centre on a dim background.
    fn disc() -> Image {
        let (w, h) = (64u32, 64u32);
        let pixels = (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f32 - 31.5, (i / w) as f32 - 31.5);
                if x * x + y * y < 100.0 {
                    Vec3::new(2.0, 1.0, 0.5)
                } else {
                    Vec3::splat(0.1)
                }
            })
            .collect();
        Image {
            width: w,
            height: h,
            pixels,
        }
    }

    fn as_reference(image: &Image) -> Vec<DVec3> {
        image.pixels.iter().map(|c| c.as_dvec3()).collect()
    }

    #[test]
    fn identical_frames_have_no_error_and_sizes_must_agree() {
        let image = disc();
        let map = flip_map(&image, &as_reference(&image)).unwrap();
        assert_eq!(map.len(), 64 * 64);
        assert!(map.iter().all(|&v| v == 0.0));
        assert!(flip_map(&image, &as_reference(&image)[1..]).is_none());
        assert!(flip_map(&Image::black(0, 0), &[]).is_none());
    }

    #[test]
    fn a_moved_edge_is_seen_where_it_moved() {
        let image = disc();
        let mut shifted = image.clone();
        shifted.pixels.rotate_right(3);
        let map = flip_map(&shifted, &as_reference(&image)).unwrap();
        assert!(map.iter().all(|v| (0.0..=1.0).contains(v)));
        // The corner, 34 px from the disc, is beyond the filters' reach (radius 10 px at 67 ppd:
        // 3 standard deviations of FLIP's widest contrast-sensitivity Gaussian) and unchanged;
        // the disc's left edge (x = 22 on row 32) moved 3 px to the right.
        let (corner, edge) = (0usize, 32 * 64 + 22);
        assert_eq!(map[corner], 0.0);
        assert!(map[edge] > 0.5, "{}", map[edge]);
        let all: Vec<usize> = (0..map.len()).collect();
        let mean = area_mean(&map, &all);
        assert!(mean > 0.0 && mean < map[edge] as f64);
        assert_eq!(area_mean(&map, &[corner, edge]), map[edge] as f64 / 2.0);
        assert_eq!(area_mean(&map, &[]), 0.0);
    }

    #[test]
    fn the_map_is_written_in_magma_and_bad_sizes_are_refused() {
        let dir = std::env::temp_dir().join(format!("reshift-flip-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("flip.png");
        let map = [0.0, 0.5, 1.0, 0.25, 0.75, 0.0];
        write_flip_map(&path, &map, 3, 2).unwrap();
        let png = image::open(&path).unwrap().into_rgb8();
        assert_eq!(png.dimensions(), (3, 2));
        // Magma's ends, FLIP's table entries 0 and 255 in 8 bits: (0.0015, 0.0005, 0.0139) and
        // (0.9871, 0.9914, 0.7495).
        assert_eq!(png.get_pixel(0, 0).0, [0, 0, 4]);
        assert_eq!(png.get_pixel(2, 0).0, [252, 253, 191]);
        let err = write_flip_map(&path, &map, 4, 2).unwrap_err().to_string();
        assert!(
            err.contains("flip.png") && err.contains("6 FLIP values"),
            "{err}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
