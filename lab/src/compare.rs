//! Pieces of `reshift compare` (DESIGN §7): the cached reference, per-method results from
//! replicas, equal-time calibration and false-colour error maps. The CLI drives the loops (progress
//! bars, Ctrl-C); everything here is a pure function of its inputs or one file.
//!
//! The reference is `sss::integrator::reference` (the path tracer in independent batches) at the
//! final frame, with a seed no replica uses ([`REFERENCE_SEED`]). It is cached as a checkpoint
//! named by [`ReferenceKey::file_name`] and reused when the key matches.

use std::path::{Path, PathBuf};

use glam::DVec3;
use sss::InputError;
use sss::integrator::pt::PtSettings;
use sss::integrator::{Reference, ReferenceConfig, Shard};

use crate::methods::{Method, Rendered};
use crate::metrics::{AreaMetrics, area_metrics, tonemapped_mse};
use crate::regions::Regions;
use engine::image::WriteError;

/// Seed of the reference's batches (ASCII "REFERENC"); replicas use seeds `0..K`.
pub const REFERENCE_SEED: u64 = 0x5245_4645_5245_4E43;

/// What identifies a cached reference.
#[derive(Clone, Debug, PartialEq)]
pub struct ReferenceKey {
    /// The built-in scene name, or `file-<stem>-<hash of the file's text>`.
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub frame: u32,
    pub spp_per_batch: u32,
    pub batches: u32,
}

impl ReferenceKey {
    /// Total samples per pixel.
    pub fn spp(&self) -> u64 {
        self.spp_per_batch as u64 * self.batches as u64
    }

    /// `ref-<scene>-<W>x<H>-f<frame>-<batches>x<spp_per_batch>spp.rsref`.
    pub fn file_name(&self) -> String {
        format!(
            "ref-{}-{}x{}-f{}-{}x{}spp.rsref",
            self.scene, self.width, self.height, self.frame, self.batches, self.spp_per_batch
        )
    }

    /// The reference configuration of this key (default path-tracer settings).
    pub fn config(&self, scene_name: &str) -> ReferenceConfig {
        ReferenceConfig {
            scene: scene_name.to_string(),
            frame: self.frame,
            seed: REFERENCE_SEED,
            spp_per_batch: self.spp_per_batch,
            batches: self.batches,
            settings: PtSettings::default(),
        }
    }

    /// An empty (unsharded) reference for this key.
    pub fn empty(&self, scene_name: &str) -> Result<Reference, InputError> {
        Reference::new(
            self.config(scene_name),
            self.width,
            self.height,
            Shard::WHOLE,
        )
    }
}

/// A stable 64-bit FNV-1a hash (file-scene cache keys).
pub use engine::hash::fnv1a;

/// Checks that `reference` (read from `path`) is of `width × height` at `frame`: a reference
/// of another size or frame is an input error, not a silent mismatch.
pub fn check_reference(
    reference: &Reference,
    path: &Path,
    width: u32,
    height: u32,
    frame: u32,
) -> Result<(), InputError> {
    if (reference.width, reference.height) != (width, height) {
        return Err(InputError::new(
            path,
            "width×height",
            format!("{}×{}", reference.width, reference.height),
            format!("the comparison renders {width}×{height}"),
        ));
    }
    if reference.config.frame != frame {
        return Err(InputError::new(
            path,
            "frame",
            reference.config.frame.to_string(),
            format!("the comparison measures frame {frame}"),
        ));
    }
    if reference.batches_done() < 2 {
        return Err(InputError::new(
            path,
            "batches",
            reference.batches_done().to_string(),
            "a reference needs at least 2 finished batches (for its standard error)",
        ));
    }
    Ok(())
}

/// The cache file of `key` under `cache_dir`.
pub fn cache_path(cache_dir: &Path, key: &ReferenceKey) -> PathBuf {
    cache_dir.join(key.file_name())
}

/// One method's row group of the comparison.
#[derive(Clone, Debug, PartialEq)]
pub struct MethodResult {
    /// The method as requested (`pt`, `restir:hybrid`).
    pub method: String,
    /// Samples per pixel per frame actually used (after equal-time calibration).
    pub spp: u32,
    pub replicas: usize,
    /// Mean over replicas.
    pub seconds_per_frame: f64,
    pub frames_rendered: u32,
    pub metrics: Vec<AreaMetrics>,
    /// Seed 001's metric over whole frames, mean over replicas ([`tonemapped_mse`]).
    pub tonemapped_mse: f64,
    pub nonfinite: u64,
}

impl MethodResult {
    /// The row group of `method` from its replicas' final frames; `None` when there is no
    /// replica or a size disagrees with the reference.
    pub fn from_replicas(
        method: &str,
        spp: u32,
        replicas: &[Rendered],
        reference: &Reference,
        regions: &Regions,
    ) -> Option<MethodResult> {
        let images: Vec<_> = replicas.iter().map(|r| r.image.clone()).collect();
        let mean = reference.mean();
        let metrics = area_metrics(&images, &mean, &reference.std_err(), regions)?;
        let k = replicas.len() as f64;
        let tonemapped = images
            .iter()
            .map(|i| tonemapped_mse(i, &mean))
            .sum::<Option<f64>>()?;
        Some(MethodResult {
            method: method.to_string(),
            spp,
            replicas: replicas.len(),
            seconds_per_frame: replicas.iter().map(|r| r.seconds_per_frame).sum::<f64>() / k,
            frames_rendered: replicas
                .iter()
                .map(|r| r.frames_rendered)
                .max()
                .unwrap_or(0),
            metrics,
            tonemapped_mse: tonemapped / k,
            nonfinite: replicas.iter().map(|r| r.nonfinite).sum(),
        })
    }
}

/// Equal time: the path tracer's spp that fits `budget` seconds per frame, from a measured
/// `seconds_per_spp` (at least 1 spp); other methods keep their own cost.
pub fn equal_time_method(method: &Method, budget: f64, seconds_per_spp: f64) -> Method {
    match method {
        Method::Pt { .. } if seconds_per_spp > 0.0 && budget.is_finite() => {
            let spp = (budget / seconds_per_spp).round().clamp(1.0, 1e6) as u32;
            method.with_spp(spp)
        }
        _ => method.clone(),
    }
}

/// Height in pixels of the colour bar under an error map.
pub const COLOUR_BAR_HEIGHT: u32 = 6;

/// Writes `values` (row-major `width × height`) as a false-colour PNG, 0 → dark blue, `max` →
/// yellow (a viridis-like ramp), with a colour bar spanning 0 … `max` left to right in
/// [`COLOUR_BAR_HEIGHT`] rows below the image. Non-finite values are drawn magenta.
pub fn write_false_colour(
    values: &[f64],
    width: u32,
    height: u32,
    max: f64,
    path: &Path,
) -> Result<(), WriteError> {
    let error = |reason: String| WriteError {
        path: path.to_path_buf(),
        reason,
    };
    if values.len() != width as usize * height as usize || width == 0 {
        return Err(error(format!(
            "{} values for a {width}×{height} image",
            values.len()
        )));
    }
    let scale = if max > 0.0 && max.is_finite() {
        max
    } else {
        1.0
    };
    let mut bytes = Vec::with_capacity(values.len() * 3 + (width * COLOUR_BAR_HEIGHT * 3) as usize);
    for &v in values {
        bytes.extend(if v.is_finite() {
            ramp(v / scale)
        } else {
            [255, 0, 255]
        });
    }
    for _ in 0..COLOUR_BAR_HEIGHT {
        for x in 0..width {
            bytes.extend(ramp(x as f64 / (width - 1).max(1) as f64));
        }
    }
    image::save_buffer(
        path,
        &bytes,
        width,
        height + COLOUR_BAR_HEIGHT,
        image::ColorType::Rgb8,
    )
    .map_err(|e| error(e.to_string()))
}

/// A five-stop approximation of viridis for `t` clamped to [0, 1].
fn ramp(t: f64) -> [u8; 3] {
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

/// The per-pixel reference mean as linear RGB `f32` values (for image output).
pub fn reference_pixels(reference: &Reference) -> Vec<glam::Vec3> {
    reference
        .mean()
        .iter()
        .map(|p: &DVec3| p.as_vec3())
        .collect()
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
    fn equal_time_scales_only_the_path_tracer() {
        let pt = Method::parse("pt").unwrap();
        assert_eq!(
            equal_time_method(&pt, 0.1, 0.02),
            Method::parse("pt:5").unwrap()
        );
        assert_eq!(equal_time_method(&pt, 0.001, 0.02), pt, "at least 1 spp");
        let hybrid = Method::parse("restir:hybrid").unwrap();
        assert_eq!(equal_time_method(&hybrid, 0.1, 0.02), hybrid);
    }

    #[test]
    fn cache_key_names_every_field() {
        let key = ReferenceKey {
            scene: "bumpy".into(),
            width: 64,
            height: 48,
            frame: 15,
            spp_per_batch: 16,
            batches: 32,
        };
        assert_eq!(key.file_name(), "ref-bumpy-64x48-f15-32x16spp.rsref");
        assert_eq!(key.spp(), 512);
        assert_ne!(fnv1a(b"a = 1"), fnv1a(b"a = 2"));
    }
}
