//! Seed 004 (Xie et al. 2020) as the rendering method `adaptive`: Burley BSSRDF importance sampling
//! with the approximate inverse CDF `g(ξ)` [004 Eq. 21], weighted by the density of `g(U)` so the
//! estimator stays unbiased, and the single-pass variance-guided (SPVG) sample count per pixel and
//! frame [004 §4.1]. Its GLSL twin is `sss/glsl/adaptive.glsl`.
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

use super::pt::{self, PtSettings, SampleMeans, Shading};
use crate::InputError;
use crate::bssrdf::RadiusSampling;
use crate::color::luminance;
use crate::geometry::Hit;
use crate::material::Material;
use crate::scene::{GBuffer, Scene};

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
mod tests {
    use super::*;
    use restir::rng::StreamKey;
    use restir::stats::{Summary, Verdict, equivalence, welch};
    use std::f32::consts::PI;

    /// `purpose` of the circle-scenario streams.
    const PURPOSE_CIRCLE: u32 = 0xC12C_0004;

    /// The circle scenario's controller [004 §4.1.3]: α = 0.2, σ0 = 0.08, [8, 64] spp.
    fn circle_params(kappa: f32) -> AdaptiveParams {
        AdaptiveParams {
            alpha: 0.2,
            target_variance: 0.08 * 0.08,
            kappa,
            ..AdaptiveParams::default()
        }
    }

    /// One run of the circle scenario: a frame's value is the mean of `n` samples of `4/π` inside
    /// the circle of radius² `radius2` around (0.5, 0.5) and 0 outside, (ξ1, ξ2) uniform in [0, 1)²
    /// (mean 1 and per-sample variance 4/π − 1 for radius² = 0.25). Returns (count, value,
    /// history after the frame) per frame.
    fn circle_run(
        params: &AdaptiveParams,
        run: u32,
        frames: u32,
        start: Option<History>,
        radius2: f32,
    ) -> Vec<(u32, f32, History)> {
        let mut history = start;
        (0..frames)
            .map(|frame| {
                let n = sample_count(params, history.as_ref());
                let mut rng = StreamKey::new(run, frame, 0, PURPOSE_CIRCLE).stream(2020);
                let inside = (0..n)
                    .filter(|_| {
                        let (x, y) = (rng.next_f32() - 0.5, rng.next_f32() - 0.5);
                        x * x + y * y < radius2
                    })
                    .count();
                let value = inside as f32 * (4.0 / PI) / n as f32;
                let h = update(params, history.as_ref(), n, value);
                history = Some(h);
                (n, value, h)
            })
            .collect()
    }

    /// Per-run statistics of frames `50..150` (after the cold start).
    struct Settled {
        mean_count: f64,
        at_budget: f64,
        count_change: f64,
        variance: f64,
        value: f64,
    }

    fn settled(run: &[(u32, f32, History)], b_max: u32) -> Settled {
        let tail = &run[50..];
        let mean = |f: &dyn Fn(&(u32, f32, History)) -> f64| {
            tail.iter().map(f).sum::<f64>() / tail.len() as f64
        };
        Settled {
            mean_count: mean(&|x| x.0 as f64),
            at_budget: mean(&|x| (x.0 == b_max) as u32 as f64),
            count_change: tail
                .windows(2)
                .map(|w| (w[1].0 as f64 - w[0].0 as f64).abs())
                .sum::<f64>()
                / (tail.len() - 1) as f64,
            variance: mean(&|x| x.2.variance as f64),
            value: mean(&|x| x.1 as f64),
        }
    }

    /// [004 Fig. 2], R = 64 runs of 150 frames from the cold start H = 0 for κ = 0 and κ = 1:
    /// * the cold start: frame 0 takes b_min and every run then hits b_max within 10 frames (μ
    ///   climbs from 0, so the EMV overestimates);
    /// * settled (frames 50–149), κ = 0 spends n̄ within 15% of n* = (4/π − 1)/σ0² ≈ 42.7, the
    ///   count that meets σ0², and the local variance σ² stays within [0.75, 2]·σ0² for both;
    /// * κ = 1 takes more samples, sits at b_max more often and changes its count more from frame
    ///   to frame than κ = 0 (single-frame peaks vs increases smoothed over frames): each a Welch
    ///   test over the runs, p < 1e-3.
    #[test]
    fn circle_scenario_reproduces_fig_2() {
        const R: u32 = 64;
        let target = circle_params(0.0).target_variance as f64;
        let n_star = (4.0 / std::f64::consts::PI - 1.0) / target;
        let runs = |kappa: f32| -> Vec<Settled> {
            let params = circle_params(kappa);
            (0..R)
                .map(|run| {
                    let trace = circle_run(&params, run, 150, Some(History::COLD), 0.25);
                    assert_eq!(trace[0].0, params.b_min, "κ = {kappa}, run {run}: frame 0");
                    assert!(
                        trace[1..=10].iter().any(|x| x.0 == params.b_max),
                        "κ = {kappa}, run {run}: no cold-start peak"
                    );
                    settled(&trace, params.b_max)
                })
                .collect()
        };
        let (smooth, peaky) = (runs(0.0), runs(1.0));
        let summary = |runs: &[Settled], f: fn(&Settled) -> f64| {
            Summary::from_samples(&runs.iter().map(f).collect::<Vec<_>>())
        };
        let count0 = summary(&smooth, |s| s.mean_count);
        assert!(
            (count0.mean / n_star - 1.0).abs() < 0.15,
            "κ = 0 settles at n̄ = {} (n* = {n_star})",
            count0.mean
        );
        for (kappa, runs) in [(0, &smooth), (1, &peaky)] {
            let v = summary(runs, |s| s.variance).mean / target;
            eprintln!("circle, frames 50–149, κ = {kappa}: σ²/σ0² = {v:.3}");
            assert!((0.75..2.0).contains(&v), "κ = {kappa}: σ²/σ0² = {v}");
        }
        for (what, f) in [
            (
                "mean count",
                (|s: &Settled| s.mean_count) as fn(&Settled) -> f64,
            ),
            ("frames at b_max", |s| s.at_budget),
            ("count change per frame", |s| s.count_change),
        ] {
            let (a, b) = (summary(&peaky, f), summary(&smooth, f));
            let test = welch(&a, &b);
            eprintln!(
                "circle, frames 50–149, {what}: κ = 0 {:.3} ± {:.3}, κ = 1 {:.3} ± {:.3}",
                b.mean, b.std_err, a.mean, a.std_err
            );
            assert!(
                a.mean > b.mean && test.p_value < 1e-3,
                "{what}: κ = 1 {} vs κ = 0 {} (p = {})",
                a.mean,
                b.mean,
                test.p_value
            );
        }
    }

    /// [004 Fig. 3, Eq. 16–17]: starting without history (a disocclusion) instead of from H = 0
    /// removes the cold-start peak: frame 1 takes exactly b_min, and frames 1–3 take fewer samples
    /// than from the cold start (Welch over R = 64 runs, p < 1e-3).
    #[test]
    fn disocclusion_start_removes_the_cold_start_peak() {
        const R: u32 = 64;
        let params = circle_params(0.2);
        let early = |start: Option<History>| -> Summary {
            let means: Vec<f64> = (0..R)
                .map(|run| {
                    let trace = circle_run(&params, run, 4, start, 0.25);
                    if start.is_none() {
                        assert_eq!((trace[0].0, trace[1].0), (params.b_min, params.b_min));
                    }
                    trace[1..].iter().map(|x| x.0 as f64).sum::<f64>() / 3.0
                })
                .collect();
            Summary::from_samples(&means)
        };
        let (disoccluded, cold) = (early(None), early(Some(History::COLD)));
        let test = welch(&cold, &disoccluded);
        assert!(
            cold.mean > disoccluded.mean && test.p_value < 1e-3,
            "frames 1–3: cold start {} vs disocclusion {} (p = {})",
            cold.mean,
            disoccluded.mean,
            test.p_value
        );
    }

    /// The converged mean of the circle scenario is 1: a frame's value is unbiased given its count,
    /// and the count depends only on earlier frames. Per run, the mean value of frames 50–149;
    /// equivalence with 1 at δ = 1%, 99% CI, R = 32 runs, for κ = 0, 0.2 and 1. Power: a run's
    /// mean has σ ≈ 0.011 (101 frames of ≥ 8 samples of variance 0.27, EMA-correlated counts), so
    /// R ≥ (t_{0.995,31} σ/δ)² ≈ 9 runs keep the CI inside ±δ. Negative control near δ: the circle
    /// grown to 1.02× its area (mean 1.02) is found biased.
    #[test]
    fn circle_scenario_converges_to_the_true_mean() {
        const R: u32 = 32;
        const DELTA: f64 = 0.01;
        let one = Summary::exact(1.0);
        let runs = |kappa: f32, radius2: f32| -> Summary {
            let means: Vec<f64> = (0..R)
                .map(|run| {
                    settled(
                        &circle_run(&circle_params(kappa), run, 150, None, radius2),
                        64,
                    )
                    .value
                })
                .collect();
            Summary::from_samples(&means)
        };
        for kappa in [0.0, 0.2, 1.0] {
            let e = equivalence(&runs(kappa, 0.25), &one, DELTA, 0.99);
            assert_eq!(e.verdict, Verdict::Equivalent, "κ = {kappa}: {e:?}");
        }
        let control = equivalence(&runs(0.2, 0.25 * 1.02), &one, DELTA, 0.99);
        assert_eq!(control.verdict, Verdict::Biased, "control: {control:?}");
    }

    /// Eq. 13–15 by hand: at σ² = σ0² the count keeps n̄; at σ² = 2σ0², n̄ = 10, α = 0.2
    /// (k − 1 = 8): E(n̄) = 20, Δ = 80, so κ = 0 → 20, κ = 0.2 → 36, κ = 1 → 100 → b_max. No
    /// history, the cold history and a NaN variance take b_min.
    #[test]
    fn sample_count_follows_the_equations() {
        let params = |kappa| AdaptiveParams {
            kappa,
            target_variance: 0.01,
            ..AdaptiveParams::default()
        };
        let h = |variance| History {
            mean_count: 10.0,
            mean: 0.5,
            variance,
        };
        assert_eq!(sample_count(&params(0.7), Some(&h(0.01))), 10);
        assert_eq!(sample_count(&params(0.0), Some(&h(0.02))), 20);
        assert_eq!(sample_count(&params(0.2), Some(&h(0.02))), 36);
        assert_eq!(sample_count(&params(1.0), Some(&h(0.02))), 64);
        assert_eq!(
            sample_count(&params(0.2), Some(&h(0.0121))),
            16,
            "⌈12.1 + 0.2·16.8⌉"
        );
        assert_eq!(sample_count(&params(0.2), None), 8);
        assert_eq!(sample_count(&params(0.2), Some(&History::COLD)), 8);
        assert_eq!(sample_count(&params(0.2), Some(&h(f32::NAN))), 8);
        assert_eq!(
            sample_count(&params(1.0), Some(&h(0.001))),
            8,
            "Δ < 0 clamps to b_min"
        );
    }

    /// Eq. 6, 8, 9 against an f64 recomputation; the disocclusion start (Eq. 16–17); α = 1 keeps
    /// only the current frame.
    #[test]
    fn update_is_the_ema_and_emv() {
        let params = AdaptiveParams::default();
        let h = History {
            mean_count: 12.0,
            mean: 0.4,
            variance: 0.003,
        };
        let next = update(&params, Some(&h), 20, 0.55);
        let (a, diff) = (0.2f64, 0.55f64 - 0.4);
        let want = [
            0.8 * 12.0 + a * 20.0,
            0.8 * 0.4 + a * 0.55,
            0.8 * 0.003 + a * 0.8 * diff * diff,
        ];
        let got = [next.mean_count, next.mean, next.variance];
        for (g, w) in got.iter().zip(want) {
            assert!((*g as f64 - w).abs() <= 1e-6 * w, "{got:?} vs {want:?}");
        }
        assert_eq!(
            update(&params, None, 8, 0.3),
            History {
                mean_count: 8.0,
                mean: 0.3,
                variance: params.target_variance
            }
        );
        let last_only = AdaptiveParams {
            alpha: 1.0,
            ..params
        };
        let h1 = update(&last_only, Some(&h), 9, 0.7);
        assert_eq!((h1.mean_count, h1.mean, h1.variance), (9.0, 0.7, 0.0));
    }

    #[test]
    fn perceptual_luminance_is_gamma_corrected() {
        assert_eq!(perceptual_luminance(Vec3::ONE), 1.0);
        assert_eq!(perceptual_luminance(Vec3::new(-1.0, 0.0, 0.0)), 0.0);
        let y = luminance(Vec3::new(0.2, 0.1, 0.05));
        assert_eq!(
            perceptual_luminance(Vec3::new(0.2, 0.1, 0.05)),
            y.powf(1.0 / 2.2)
        );
    }

    #[test]
    fn bad_parameters_are_typed_errors() {
        assert_eq!(AdaptiveParams::default().validate(), Ok(()));
        type Case = (fn(&mut AdaptiveParams), &'static str);
        let cases: [Case; 6] = [
            (|p| p.alpha = 0.0, "adaptive.alpha"),
            (|p| p.alpha = f32::NAN, "adaptive.alpha"),
            (|p| p.target_variance = -1.0, "adaptive.target_variance"),
            (|p| p.kappa = 1.5, "adaptive.kappa"),
            (|p| p.b_min = 0, "adaptive.b_min"),
            (|p| p.b_max = 4, "adaptive.b_min"),
        ];
        for (break_it, field) in cases {
            let mut p = AdaptiveParams::default();
            break_it(&mut p);
            assert_eq!(p.validate().unwrap_err().field, field);
        }
    }

    fn small_bumpy() -> Scene {
        let mut scene = Scene::builtin("bumpy").expect("built-in scene");
        scene.camera = scene.camera.with_resolution(40, 30);
        scene
    }

    /// With b_min = b_max = 3 every pixel takes 3 samples and the frame equals the path tracer with
    /// Xie radii at 3 spp, bit for bit (the same streams).
    #[test]
    fn a_fixed_budget_is_the_path_tracer() {
        let scene = small_bumpy();
        let params = AdaptiveParams {
            b_min: 3,
            b_max: 3,
            ..AdaptiveParams::default()
        };
        let first = GBuffer::render(&scene, 0);
        let f0 = render_frame(&scene, &first, None, &params, 9);
        let second = GBuffer::render(&scene, 1);
        let f1 = render_frame(
            &scene,
            &second,
            Some((&first, f0.history.as_slice())),
            &params,
            9,
        );
        let pt = pt::render(&scene, &second, &params.pt_settings(), 9, 0, 3);
        assert_eq!(f1.image, pt);
        for (count, g) in f1.counts.iter().zip(&second.pixels) {
            assert_eq!(*count, if g.is_some() { 3 } else { 0 });
        }
    }

    /// Three frames on 1 and 2 threads are bit-identical and finite; with the camera at rest
    /// (frames 15–17: only the jitter moves), every translucent pixel that reprojects onto itself
    /// takes the count its own history asks for.
    #[test]
    fn frames_are_deterministic_and_carry_their_history() {
        let scene = small_bumpy();
        let params = AdaptiveParams::default();
        let frames = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let mut out: Vec<(GBuffer, AdaptiveFrame)> = Vec::new();
                for frame in 15..18 {
                    let g = GBuffer::render(&scene, frame);
                    let previous = out.last().map(|(g, f)| (g, f.history.as_slice()));
                    let f = render_frame(&scene, &g, previous, &params, 4);
                    out.push((g, f));
                }
                out
            })
        };
        let (one, two) = (frames(1), frames(2));
        assert!(
            one.iter().zip(&two).all(|(a, b)| a.1 == b.1),
            "1 vs 2 threads"
        );
        let (g16, f16) = &one[1];
        let (g17, f17) = &one[2];
        let mut carried = 0;
        for (p, g) in g17.pixels.iter().enumerate() {
            let Some(g) = g else { continue };
            assert!(f17.image.pixels[p].is_finite());
            if f17.history[p].is_none() {
                continue;
            }
            if g16.reproject(&scene.camera, g) == Some(p as u32) {
                carried += 1;
                assert_eq!(
                    f17.counts[p],
                    sample_count(&params, f16.history[p].as_ref()),
                    "pixel {p}"
                );
            }
        }
        assert!(carried > 100, "only {carried} pixels carried their history");
        assert_eq!(f17.image.nonfinite, 0);
        let counts = f17.count_image();
        assert_eq!(counts.pixels[0].x, f17.counts[0] as f64);
    }
}
