//! Paper 004 (Xie et al. 2020) as the rendering method `adaptive`: Burley BSSRDF importance sampling
//! with the approximate inverse CDF `g(ξ)` [004 Eq. 21], weighted by the density of `g(U)` so the
//! estimator stays unbiased, and the single-pass variance-guided (SPVG) sample count per pixel and
//! frame [004 §4.1]. Its GLSL twin is `adaptive.glsl` beside it.
//!
//! **Estimator.** A sample is one path-tracing sample ([`pt::estimate`]) whose techniques draw
//! their radii with [`RadiusSampling::Xie`]: world-space probe rays instead of the paper's
//! screen-space lookups, so the method is unbiased against the path-traced Burley reference and
//! its adaptive counts can be compared with fixed counts of the same estimator. A frame's pixel
//! value is the mean of its `n` samples; `n` depends only on earlier frames, so the value is
//! unbiased given `n`.
//!
//! **Sample count** [004 Eq. 7–15]. Each pixel carries a history `H = (n̄, μ, σ²)` (mean sample
//! count, EMA of the pixel value, EMV of the pixel value) from frame to frame, reprojected with
//! [`GBuffer::reproject`] (nearest pixel, no rejection other than a disocclusion, [004 §4.1.5]).
//! With `k = 2/α − 1` [004 §4.1.2] the count for frame `i` is
//!
//! `n̂ = κΔ + E(n̄)`, `E(n̄) = σ²/σ0² · n̄`, `Δ = (σ² − σ0²)/σ0² · n̄ · (k − 1)` [004 Eq. 13–15],
//! `n = clamp(⌈n̂⌉, b_min, b_max)` [004 Eq. 7].
//!
//! Eq. 15 as printed has `σ − σ0` over `σ0²`, which is not dimensionless; it is read as the
//! correction term of Eq. 13 (`σ² − σ0²`), of which Eq. 14–15 are the κ-limited version. After the
//! frame, with `S` its value: `μ ← (1 − α)μ + αS` [004 Eq. 6], `σ² ← (1 − α)σ² + α(1 − α)(S − μ)²`
//! (old `μ`) [004 Eq. 9], `n̄ ← (1 − α)n̄ + αn` [004 Eq. 8]. A pixel without history (first frame,
//! disocclusion) takes `n = b_min` and starts from `H = (n, S, σ0²)` (α = 1 and `σ² = σ0²`
//! [004 Eq. 16–17]); [`History::COLD`] (all zero) is the paper's cold start of Fig. 2. The value is
//! the gamma-corrected luminance of the pixel estimate ([`perceptual_luminance`], [004 §4.1.2]).
//!
//! The controller runs on translucent pixels only (the paper's subsurface pass); other pixels take
//! `b_min` samples of the path tracer and keep no history.
//!
//! Random numbers: sample `j` of pixel `p` in frame `f` is the path tracer's sample `j`
//! ([`pt::sample_stream`]), so a fixed count `n` gives exactly `pt` with Xie radii at `n` spp.

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use geometry::Hit;
use sss::InputError;
use sss::bssrdf::RadiusSampling;
use sss::color::luminance;
use sss::integrator::pt::{self, PtSettings, SampleMeans, Shading};
use sss::material::Material;
use sss::scene::{GBuffer, Scene};

/// The display gamma of [`perceptual_luminance`].
pub const GAMMA: f32 = 2.2;

/// Parameters of the sample-count controller (defaults: [004 Fig. 1]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdaptiveParams {
    /// EMA weight `α` of the history, in (0, 1].
    pub alpha: f32,
    /// Target variance `σ0²` of a frame's pixel value, > 0.
    pub target_variance: f32,
    /// Correction factor `κ ∈ [0, 1]` [004 Eq. 14].
    pub kappa: f32,
    /// Sample budget per pixel and frame, `1 ≤ b_min ≤ b_max`.
    pub b_min: u32,
    pub b_max: u32,
    /// How the BSSRDF IS techniques draw their radii ([`RadiusSampling::Xie`] in the paper).
    pub radius: RadiusSampling,
}

impl Default for AdaptiveParams {
    /// σ0² = 0.001, κ = 0.2, [b_min, b_max] = [8, 64] [004 Fig. 1], α = 0.2 [004 §5], `g(ξ)` radii.
    fn default() -> Self {
        AdaptiveParams {
            alpha: 0.2,
            target_variance: 0.001,
            kappa: 0.2,
            b_min: 8,
            b_max: 64,
            radius: RadiusSampling::Xie,
        }
    }
}

impl AdaptiveParams {
    /// Checks the ranges above; the error names `adaptive.<field>` and its value.
    pub fn validate(&self) -> Result<(), InputError> {
        let err = |field: &str, value: String, reason: &str| {
            Err(InputError::new(
                "(adaptive parameters)",
                format!("adaptive.{field}"),
                value,
                reason,
            ))
        };
        if !(self.alpha > 0.0 && self.alpha <= 1.0) {
            return err("alpha", self.alpha.to_string(), "must lie in (0, 1]");
        }
        if !(self.target_variance > 0.0 && self.target_variance.is_finite()) {
            return err(
                "target_variance",
                self.target_variance.to_string(),
                "must be finite and > 0",
            );
        }
        if !(0.0..=1.0).contains(&self.kappa) {
            return err("kappa", self.kappa.to_string(), "must lie in [0, 1]");
        }
        if !(1 <= self.b_min && self.b_min <= self.b_max) {
            return err(
                "b_min",
                format!("[{}, {}]", self.b_min, self.b_max),
                "need 1 ≤ b_min ≤ b_max",
            );
        }
        Ok(())
    }

    /// The path-tracing settings of one sample.
    pub fn pt_settings(&self) -> PtSettings {
        PtSettings {
            radius: self.radius,
            ..PtSettings::default()
        }
    }
}

/// The per-pixel history `H = (n̄, μ, σ²)` [004 §4.1.3].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct History {
    /// `n̄`: EMA of the sample count [004 Eq. 8].
    pub mean_count: f32,
    /// `μ`: EMA of the pixel value [004 Eq. 6].
    pub mean: f32,
    /// `σ²`: EMV of the pixel value [004 Eq. 9].
    pub variance: f32,
}

impl History {
    /// The all-zero history of the paper's cold start [004 §4.1.3, Fig. 2].
    pub const COLD: History = History {
        mean_count: 0.0,
        mean: 0.0,
        variance: 0.0,
    };
}

/// The sample count of a pixel with `history` [004 Eq. 7, 13–15]; `b_min` without history.
pub fn sample_count(params: &AdaptiveParams, history: Option<&History>) -> u32 {
    let Some(h) = history else {
        return params.b_min;
    };
    let k = 2.0 / params.alpha - 1.0;
    let ratio = h.variance / params.target_variance;
    let expected = ratio * h.mean_count;
    let correction = (ratio - 1.0) * h.mean_count * (k - 1.0);
    let estimate = params.kappa * correction + expected;
    if !(estimate > params.b_min as f32) {
        params.b_min
    } else if estimate >= params.b_max as f32 {
        params.b_max
    } else {
        estimate.ceil() as u32
    }
}

/// The history after a frame that took `count` samples with value `value` [004 Eq. 6, 8, 9];
/// without history, `(count, value, σ0²)` [004 Eq. 16–17].
pub fn update(
    params: &AdaptiveParams,
    history: Option<&History>,
    count: u32,
    value: f32,
) -> History {
    let Some(h) = history else {
        return History {
            mean_count: count as f32,
            mean: value,
            variance: params.target_variance,
        };
    };
    let alpha = params.alpha;
    let keep = 1.0 - alpha;
    let diff = value - h.mean;
    History {
        mean_count: keep * h.mean_count + alpha * count as f32,
        mean: keep * h.mean + alpha * value,
        variance: keep * h.variance + alpha * keep * (diff * diff),
    }
}

/// The gamma-corrected luminance `Y^(1/2.2)` that the controller tracks [004 §4.1.2]; 0 for `Y ≤ 0`.
pub fn perceptual_luminance(rgb: Vec3) -> f32 {
    let y = luminance(rgb);
    if y > 0.0 { y.powf(1.0 / GAMMA) } else { 0.0 }
}

/// One frame of the method.
#[derive(Clone, Debug, PartialEq)]
pub struct AdaptiveFrame {
    pub frame: u32,
    /// The pixel estimates (means of their samples).
    pub image: SampleMeans,
    /// Samples taken per pixel (0 without a primary hit).
    pub counts: Vec<u32>,
    /// The history each translucent pixel passes to the next frame (`None` elsewhere).
    pub history: Vec<Option<History>>,
}

impl AdaptiveFrame {
    /// The per-pixel sample counts as an image (the count in every channel).
    pub fn count_image(&self) -> SampleMeans {
        SampleMeans {
            width: self.image.width,
            height: self.image.height,
            pixels: self
                .counts
                .iter()
                .map(|&n| DVec3::splat(n as f64))
                .collect(),
            nonfinite: 0,
        }
    }
}

/// The frame of `gbuffer` given the previous frame's G-buffer and histories (`None` for the first
/// frame): counts from the reprojected histories, samples, new histories. Rayon over rows; a pure
/// function of its inputs, bit-identical for any thread count.
pub fn render_frame(
    scene: &Scene,
    gbuffer: &GBuffer,
    previous: Option<(&GBuffer, &[Option<History>])>,
    params: &AdaptiveParams,
    seed: u64,
) -> AdaptiveFrame {
    let width = gbuffer.width as usize;
    let settings = params.pt_settings();
    let n = gbuffer.pixels.len();
    let mut pixels = vec![DVec3::ZERO; n];
    let mut counts = vec![0u32; n];
    let mut history = vec![None; n];
    let nonfinite = pixels
        .par_chunks_mut(width.max(1))
        .zip(counts.par_chunks_mut(width.max(1)))
        .zip(history.par_chunks_mut(width.max(1)))
        .zip(gbuffer.pixels.par_chunks(width.max(1)))
        .enumerate()
        .map(|(py, (((out, count), next), row))| {
            let mut hits: Vec<Hit> = Vec::new();
            let mut nonfinite = 0;
            for (px, g) in row.iter().enumerate() {
                let Some(g) = g else { continue };
                let pixel = (py * width + px) as u32;
                let translucent =
                    matches!(scene.material_of_object(g.object), Material::Translucent(_));
                let carried = previous
                    .filter(|_| translucent)
                    .and_then(|(prev, histories)| {
                        histories[prev.reproject(&scene.camera, g)? as usize]
                    });
                let spp = sample_count(params, carried.as_ref());
                let shading = Shading::new(scene, g);
                let mut sum = DVec3::ZERO;
                for sample in 0..spp {
                    let mut rng = pt::sample_stream(pixel, gbuffer.frame, sample, seed);
                    let value = pt::estimate(scene, &shading, &settings, &mut rng, &mut hits);
                    if value.is_finite() {
                        sum += value.as_dvec3();
                    } else {
                        nonfinite += 1;
                    }
                }
                let mean = if spp > 0 {
                    sum / spp as f64
                } else {
                    DVec3::ZERO
                };
                out[px] = mean;
                count[px] = spp;
                if translucent {
                    let value = perceptual_luminance(mean.as_vec3());
                    next[px] = Some(update(params, carried.as_ref(), spp, value));
                }
            }
            nonfinite
        })
        .sum();
    AdaptiveFrame {
        frame: gbuffer.frame,
        image: SampleMeans {
            width: gbuffer.width,
            height: gbuffer.height,
            pixels,
            nonfinite,
        },
        counts,
        history,
    }
}

/// Frames `0..frames` of the scene's camera trajectory, each handed to `each` as it is done;
/// returns the last (`None` for no frames).
pub fn run(
    scene: &Scene,
    params: &AdaptiveParams,
    seed: u64,
    frames: u32,
    mut each: impl FnMut(&AdaptiveFrame),
) -> Option<AdaptiveFrame> {
    let mut previous: Option<(GBuffer, AdaptiveFrame)> = None;
    for frame in 0..frames {
        let gbuffer = GBuffer::render(scene, frame);
        let out = render_frame(
            scene,
            &gbuffer,
            previous.as_ref().map(|(g, f)| (g, f.history.as_slice())),
            params,
            seed,
        );
        each(&out);
        previous = Some((gbuffer, out));
    }
    previous.map(|(_, f)| f)
}

#[cfg(test)]
mod tests;
