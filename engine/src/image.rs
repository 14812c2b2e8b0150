//! Linear RGB images and their two outputs: EXR (linear HDR) and PNG (Reinhard tonemap + sRGB).

use std::fmt;
use std::path::{Path, PathBuf};

use glam::Vec3;

/// A linear RGB image, row-major from the top row.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<Vec3>,
}

/// An image file could not be written.
#[derive(Debug)]
pub struct WriteError {
    pub path: PathBuf,
    pub reason: String,
}

impl fmt::Display for WriteError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.path.display(), self.reason)
    }
}

impl std::error::Error for WriteError {}

impl Image {
    /// A black image.
    pub fn black(width: u32, height: u32) -> Image {
        Image {
            width,
            height,
            pixels: vec![Vec3::ZERO; width as usize * height as usize],
        }
    }

    /// The pixel at column `px`, row `py`.
    pub fn get(&self, px: u32, py: u32) -> Vec3 {
        self.pixels[(py * self.width + px) as usize]
    }

    /// The mean over all pixels, per channel, accumulated in f64.
    pub fn mean(&self) -> [f64; 3] {
        let mut sum = [0.0f64; 3];
        for p in &self.pixels {
            for (s, v) in sum.iter_mut().zip(p.to_array()) {
                *s += v as f64;
            }
        }
        let n = self.pixels.len().max(1) as f64;
        sum.map(|s| s / n)
    }

    /// Every pixel's channels as bits: what a bit-for-bit comparison of two images compares.
    pub fn bits(&self) -> Vec<[u32; 3]> {
        self.pixels
            .iter()
            .map(|p| p.to_array().map(f32::to_bits))
            .collect()
    }

    /// Pixels whose channels are not all finite.
    pub fn non_finite_count(&self) -> u64 {
        self.pixels.iter().filter(|p| !p.is_finite()).count() as u64
    }

    /// Writes linear HDR RGB (32-bit float channels).
    pub fn write_exr(&self, path: impl AsRef<Path>) -> Result<(), WriteError> {
        let path = path.as_ref();
        let width = self.width as usize;
        exr::prelude::write_rgb_file(path, width, self.height as usize, |x, y| {
            let p = self.pixels[y * width + x];
            (p.x, p.y, p.z)
        })
        .map_err(|e| WriteError {
            path: path.to_path_buf(),
            reason: e.to_string(),
        })
    }

    /// Writes an 8-bit sRGB PNG of the Reinhard-tonemapped image ([`tonemap`]).
    pub fn write_png(&self, path: impl AsRef<Path>) -> Result<(), WriteError> {
        let path = path.as_ref();
        let bytes: Vec<u8> = self.pixels.iter().flat_map(|p| tonemap(*p)).collect();
        image::save_buffer(
            path,
            &bytes,
            self.width,
            self.height,
            image::ColorType::Rgb8,
        )
        .map_err(|e| WriteError {
            path: path.to_path_buf(),
            reason: e.to_string(),
        })
    }
}

/// Reinhard `c / (1 + c)` per channel, then the sRGB transfer curve, quantised to 8 bits.
/// Non-finite and negative values map to 0.
pub fn tonemap(c: Vec3) -> [u8; 3] {
    c.to_array().map(|v| {
        let v = if v.is_finite() { v.max(0.0) } else { 0.0 };
        let mapped = v / (1.0 + v);
        let srgb = if mapped <= 0.003_130_8 {
            12.92 * mapped
        } else {
            1.055 * mapped.powf(1.0 / 2.4) - 0.055
        };
        (srgb * 255.0 + 0.5).clamp(0.0, 255.0) as u8
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tonemap_is_monotone_bounded_and_guards_bad_values() {
        assert_eq!(tonemap(Vec3::ZERO), [0, 0, 0]);
        assert_eq!(tonemap(Vec3::new(f32::NAN, -1.0, f32::INFINITY)), [0, 0, 0]);
        assert_eq!(tonemap(Vec3::splat(1e30)), [255, 255, 255]);
        // c = 1 → 0.5 → sRGB 0.7354 → 188.
        assert_eq!(tonemap(Vec3::ONE), [188, 188, 188]);
        let ramp: Vec<u8> = (0..200)
            .map(|i| tonemap(Vec3::splat(i as f32 * 0.05))[0])
            .collect();
        assert!(ramp.windows(2).all(|w| w[0] <= w[1]));
    }

    #[test]
    fn exr_and_png_round_trip_through_files() {
        let dir = std::env::temp_dir().join(format!("reshift-image-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut img = Image::black(3, 2);
        img.pixels[4] = Vec3::new(0.25, 2.0, 8.5);
        let exr_path = dir.join("a.exr");
        img.write_exr(&exr_path).unwrap();
        let read = exr::prelude::read_first_rgba_layer_from_file(
            &exr_path,
            |res, _| vec![[0.0f32; 3]; res.width() * res.height()],
            |buf, pos, (r, g, b, _a): (f32, f32, f32, f32)| buf[pos.y() * 3 + pos.x()] = [r, g, b],
        )
        .unwrap();
        assert_eq!(read.layer_data.channel_data.pixels[4], [0.25, 2.0, 8.5]);
        let png_path = dir.join("a.png");
        img.write_png(&png_path).unwrap();
        let png = image::open(&png_path).unwrap().to_rgb8();
        assert_eq!(png.get_pixel(1, 1).0, tonemap(img.pixels[4]));
        let bad = img.write_png(dir.join("missing-dir").join("b.png"));
        assert!(bad.is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
