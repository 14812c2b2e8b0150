//! The low-frequency error of a frame: the energy of its error against the reference at low
//! spatial frequencies, where denoisers leave blotches and discontinuities (paper 001 §6) that
//! a per-pixel MSE weighs no more than fine noise.
//!
//! With the error `e_q = I_q − R̂_q` per channel and a Gaussian low-pass `g_pq` (standard
//! deviation σ pixels, separable, truncated at radius ⌈3σ⌉, its weights normalised over the
//! pixels inside the image so that a constant error passes unchanged up to the borders), the
//! value at pixel p is, averaged over the three channels,
//!
//! `L_p = (Σ_q g_pq e_q)² − Σ_q g_pq² s_q²`
//!
//! with `s` the reference's per-pixel standard error. `R̂ = R + ε` with zero-mean noise `ε`
//! independent of `I` and between pixels, so `E[(Σ g e)²] = (Σ g (I − R))² + Σ g² Var(ε)`:
//! subtracting the second term with `s² ≈ Var(ε)` (as [`crate::metrics`] does for the MSE) makes
//! `L_p` estimate the low-pass error against the true image. A single `L_p` may be negative;
//! its mean over an area is the measure. The method's own pixel noise passes the low-pass
//! attenuated to `Σ_q g_pq²` ≈ 1/(4πσ²) of its variance (0.5% at σ = 4).

use std::path::Path;

use engine::Image;
use glam::DVec3;
use rayon::prelude::*;

use crate::draw::{false_colour_map, quantile};
use crate::error::Error;

/// The default standard deviation of the low-pass, in pixels: wavelengths of ~25 pixels
/// (2π σ) and longer pass at more than half their amplitude.
pub const SIGMA_PIXELS: f64 = 4.0;

/// The kernel is truncated at this many standard deviations (⌈3σ⌉ pixels).
pub const TRUNCATION_SIGMAS: f64 = 3.0;

/// `L_p` of the module documentation for every pixel of `image` (row-major) against the
/// reference mean `reference` with per-pixel standard error `reference_std_err`, at low-pass
/// standard deviation `sigma` pixels. `None` when the sizes disagree, `sigma` is not positive
/// and finite, or a value is not finite.
pub fn low_frequency_error(
    image: &Image,
    reference: &[DVec3],
    reference_std_err: &[DVec3],
    sigma: f64,
) -> Option<Vec<f64>> {
    let (w, h) = (image.width as usize, image.height as usize);
    let n = w * h;
    let sizes_agree =
        image.pixels.len() == n && reference.len() == n && reference_std_err.len() == n;
    let sigma_valid = sigma > 0.0 && sigma.is_finite();
    if !sizes_agree || !sigma_valid {
        return None;
    }
    let error: Vec<DVec3> = image
        .pixels
        .iter()
        .zip(reference)
        .map(|(i, r)| i.as_dvec3() - *r)
        .collect();
    if !error.iter().chain(reference_std_err).all(|v| v.is_finite()) {
        return None;
    }
    let variance: Vec<DVec3> = reference_std_err.iter().map(|s| *s * *s).collect();
    let taps = gaussian_taps(sigma);
    let low = blur(&error, (w, h), &taps, Weight::Linear);
    let noise = blur(&variance, (w, h), &taps, Weight::Squared);
    Some(
        low.iter()
            .zip(&noise)
            .map(|(b, v)| (*b * *b - *v).element_sum() / 3.0)
            .collect(),
    )
}

/// Writes `values` (`width × height`, row-major, from [`low_frequency_error`]) as a false-colour
/// PNG from 0 (negative values show as 0) to `max`, or to the 99th percentile of the values
/// when `max` is `None`, with `title` above.
pub fn write_map(
    path: &Path,
    values: &[f64],
    (width, height): (u32, u32),
    max: Option<f64>,
    title: &str,
) -> Result<(), Error> {
    let max = max.unwrap_or_else(|| quantile(values, 0.99));
    false_colour_map(path, values, (width, height), max, title)
}

/// The unnormalised Gaussian weights `exp(−d²/2σ²)` for `d = 0..=⌈3σ⌉`.
fn gaussian_taps(sigma: f64) -> Vec<f64> {
    let radius = (TRUNCATION_SIGMAS * sigma).ceil() as usize;
    (0..=radius)
        .map(|d| (-((d * d) as f64) / (2.0 * sigma * sigma)).exp())
        .collect()
}

/// How a blur applies its normalised weights `g`.
#[derive(Clone, Copy)]
enum Weight {
    /// `Σ g v`: the low-pass itself.
    Linear,
    /// `Σ g² v`: the variance of a low-passed sum of independent values of variance `v`.
    Squared,
}

/// The separable blur of `values` (`w × h`, row-major): along rows, then along columns. At
/// each output pixel the taps inside the image are normalised to sum to one; the in-image
/// pixels of the 2-D kernel form a rectangle, so the 2-D weights `g_pq = g_x g_y` and their
/// squares factor over the two passes exactly.
fn blur(values: &[DVec3], (w, h): (usize, usize), taps: &[f64], weight: Weight) -> Vec<DVec3> {
    let mut rows = vec![DVec3::ZERO; w * h];
    rows.par_chunks_mut(w).enumerate().for_each(|(y, out)| {
        for (x, o) in out.iter_mut().enumerate() {
            *o = filter_at(x, w, taps, weight, |i| values[y * w + i]);
        }
    });
    let mut out = vec![DVec3::ZERO; w * h];
    out.par_chunks_mut(w).enumerate().for_each(|(y, out)| {
        for (x, o) in out.iter_mut().enumerate() {
            *o = filter_at(y, h, taps, weight, |i| rows[i * w + x]);
        }
    });
    out
}

/// One output of a 1-D pass at position `at` of a line of `len` values read by `value`.
fn filter_at(
    at: usize,
    len: usize,
    taps: &[f64],
    weight: Weight,
    value: impl Fn(usize) -> DVec3,
) -> DVec3 {
    let radius = taps.len() - 1;
    let (lo, hi) = (at.saturating_sub(radius), (at + radius).min(len - 1));
    let tap = |i: usize| taps[i.abs_diff(at)];
    let norm: f64 = (lo..=hi).map(tap).sum();
    (lo..=hi)
        .map(|i| {
            let g = tap(i) / norm;
            let g = match weight {
                Weight::Linear => g,
                Weight::Squared => g * g,
            };
            value(i) * g
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;
    use restir::rng::StreamKey;

    const W: u32 = 64;
    const H: u32 = 64;

    fn frame(f: impl Fn(usize, usize) -> DVec3) -> Vec<DVec3> {
        (0..(W * H) as usize)
            .map(|p| f(p % W as usize, p / W as usize))
            .collect()
    }

    fn as_image(values: &[DVec3]) -> Image {
        Image {
            width: W,
            height: H,
            pixels: values.iter().map(|v| v.as_vec3()).collect(),
        }
    }

    /// A smooth true image, exactly representable in `f32`.
    fn truth() -> Vec<DVec3> {
        frame(|x, y| DVec3::new(0.25 + x as f64 / 64.0, 0.5, 1.0 + y as f64 / 32.0))
    }

    #[test]
    fn pixel_wise_alternating_error_is_removed() {
        let r = truth();
        let a = 0.125;
        let i = frame(|x, y| {
            r[y * W as usize + x]
                + DVec3::splat(a * if (x + y).is_multiple_of(2) { 1.0 } else { -1.0 })
        });
        let zero = vec![DVec3::ZERO; r.len()];
        let l = low_frequency_error(&as_image(&i), &r, &zero, SIGMA_PIXELS).unwrap();
        // The checkerboard's amplitude after the low-pass is the product of the 1-D responses
        // to (−1)^d: 7.1e-4 inside the image (the truncated kernel's tails), 0.0915 at a border
        // (one-sided kernel), both at σ = 4. The energy fraction L/a² is their product squared:
        // ≤ 0.0915⁴ = 7.0e-5 anywhere, ≤ (7.1e-4)⁴ = 2.5e-13 at least 12 px from the borders.
        let (edge_bound, interior_bound) = (1e-4, 1e-12);
        let r = 12;
        for (p, v) in l.iter().enumerate() {
            let (x, y) = (p % W as usize, p / W as usize);
            let interior = (r..W as usize - r).contains(&x) && (r..H as usize - r).contains(&y);
            let bound = if interior { interior_bound } else { edge_bound };
            assert!(*v / (a * a) <= bound, "({x}, {y}): {v}");
        }
    }

    #[test]
    fn a_constant_offset_is_kept_in_full_up_to_the_borders() {
        let r = truth();
        let offset = DVec3::new(0.25, -0.5, 0.125);
        let i = frame(|x, y| r[y * W as usize + x] + offset);
        let zero = vec![DVec3::ZERO; r.len()];
        let l = low_frequency_error(&as_image(&i), &r, &zero, SIGMA_PIXELS).unwrap();
        let expected = (offset * offset).element_sum() / 3.0;
        // Normalised weights sum to one up to rounding (~25 terms, relative 1e-15 each).
        assert!(
            l.iter().all(|v| (v - expected).abs() <= 1e-12 * expected),
            "{l:?}"
        );
    }

    #[test]
    fn the_reference_noise_correction_is_unbiased() {
        // N = 400 trials on 64×64 frames: the method errs by a constant δ = 0.01 per channel
        // (so E[L_p] = δ² = 1e-4 exactly, by the test above), the reference has uniform noise
        // of standard deviation s from 0.05 to 0.2 across the frame. Uncorrected, the mean of
        // L would be high by mean(Σ g² s²) ≈ 1.0e-4 (Σ g² ≈ 1/(4πσ²) = 0.005 inside the frame,
        // more near the borders, where fewer taps share the weight); the trials' standard error
        // is ≈ 1.3e-6.
        // The corrected mean must lie within 4 standard errors of δ² (a 6e-5 false-failure
        // rate for a normal mean), and the uncorrected one outside them.
        const N: u64 = 400;
        const DELTA: f64 = 0.01;
        let r = truth();
        let s = frame(|x, y| DVec3::splat(0.05 + 0.15 * ((x + y) as f64 / 126.0)));
        let method = as_image(&frame(|x, y| r[y * W as usize + x] + DVec3::splat(DELTA)));
        let zero = vec![DVec3::ZERO; r.len()];
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
        let (mut corrected, mut raw) = (Vec::new(), Vec::new());
        for trial in 0..N {
            let mut stream = StreamKey::new(0, 0, 0x10F, 0).stream(trial);
            let noisy: Vec<DVec3> = r
                .iter()
                .zip(&s)
                .map(|(r, s)| {
                    let u = DVec3::new(stream.next_f64(), stream.next_f64(), stream.next_f64());
                    // Uniform on [−½, ½] scaled to unit variance.
                    *r + *s * (u - DVec3::splat(0.5)) * 12f64.sqrt()
                })
                .collect();
            corrected.push(mean(
                &low_frequency_error(&method, &noisy, &s, SIGMA_PIXELS).unwrap(),
            ));
            raw.push(mean(
                &low_frequency_error(&method, &noisy, &zero, SIGMA_PIXELS).unwrap(),
            ));
        }
        let std_err = |v: &[f64]| {
            let m = mean(v);
            (v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / ((v.len() - 1) * v.len()) as f64)
                .sqrt()
        };
        let truth = DELTA * DELTA;
        let (c, se) = (mean(&corrected), std_err(&corrected));
        let (u, se_u) = (mean(&raw), std_err(&raw));
        eprintln!("corrected {c} ± {se}, uncorrected {u} ± {se_u}, truth {truth}");
        assert!(
            (c - truth).abs() <= 4.0 * se,
            "corrected {c} ± {se}, truth {truth}"
        );
        assert!(
            (u - truth).abs() > 4.0 * se_u,
            "uncorrected {u} ± {se_u}, truth {truth}"
        );
    }

    #[test]
    fn bad_input_is_refused() {
        let r = truth();
        let zero = vec![DVec3::ZERO; r.len()];
        let i = as_image(&r);
        assert!(low_frequency_error(&i, &r[1..], &zero, 4.0).is_none());
        assert!(low_frequency_error(&i, &r, &zero[1..], 4.0).is_none());
        assert!(low_frequency_error(&i, &r, &zero, 0.0).is_none());
        assert!(low_frequency_error(&i, &r, &zero, f64::NAN).is_none());
        let mut bad = i.clone();
        bad.pixels[5] = Vec3::new(f32::NAN, 0.0, 0.0);
        assert!(low_frequency_error(&bad, &r, &zero, 4.0).is_none());
        let same = low_frequency_error(&i, &r, &zero, 4.0).unwrap();
        assert!(same.iter().all(|&v| v == 0.0));
    }

    #[test]
    fn the_map_is_written() {
        let dir = std::env::temp_dir().join(format!("reshift-low-freq-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("low.png");
        let values: Vec<f64> = (0..(W * H)).map(|p| p as f64).collect();
        write_map(&path, &values, (W, H), None, "low-frequency error").unwrap();
        let png = image::open(&path).unwrap();
        assert!(png.width() >= W && png.height() >= H);
        assert!(write_map(&path, &values[1..], (W, H), None, "t").is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
