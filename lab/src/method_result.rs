//! One method's row group of a comparison: its metrics per area at every measured frame of its
//! replicas against that frame's reference, its cost per replica, and what follows from both
//! (efficiency and ratios to another method, each with its 95% interval,
//! [`crate::uncertainty`]).

use engine::Image;
use engine::denoise::Denoiser;

use crate::flicker::{AreaFlicker, flicker};
use crate::metrics::{Area, AreaMetrics, area_metrics, tonemapped_mse};
use crate::perceptual::{PerceptualMetrics, perceptual_metrics};
use crate::reference_cache::FrameReference;
use crate::regions::Regions;
use crate::uncertainty::{CONFIDENCE, Estimate, Interval, log_cost};

/// One replica of a method as a comparison keeps it.
#[derive(Clone, Debug)]
pub struct Replica {
    /// Linear RGB of each measured frame, in the comparison's order (the last frame last).
    pub frames: Vec<Image>,
    /// Seconds per rendered frame on the backend's clock ([`engine::clock`]: process CPU time
    /// on the CPU backend), over every frame the replica rendered (with a denoiser's: both).
    pub seconds_per_frame: f64,
    /// Wall-clock seconds per rendered frame of the rendering (a denoiser's not included).
    pub wall_seconds_per_frame: f64,
    /// The denoiser's share of `seconds_per_frame` (0 for a raw frame).
    pub denoiser_seconds_per_frame: f64,
    pub frames_rendered: u32,
    pub nonfinite: u64,
    /// Mean samples per pixel of the last frame ([`Rendered::spp`](methods::Rendered)).
    pub spp: f64,
}

/// The metrics per area at one frame.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameMetrics {
    pub frame: u32,
    pub metrics: Vec<AreaMetrics>,
}

/// A reported number and its [`CONFIDENCE`] interval (`None` with fewer than 2 replicas).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Measured {
    pub value: f64,
    pub ci: Option<Interval>,
}

impl Measured {
    /// The estimate `ĝ` and its interval.
    pub fn of(e: &Estimate) -> Measured {
        Measured {
            value: e.value,
            ci: e.interval(CONFIDENCE),
        }
    }

    /// `exp(ĝ)` of an estimate on the log scale, and its interval.
    pub fn of_log(e: &Estimate) -> Measured {
        Measured {
            value: e.value.exp(),
            ci: e.exp_interval(CONFIDENCE),
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct MethodResult {
    /// The method as requested (`pt`, `restir:hybrid`).
    pub method: String,
    /// The denoiser its last frames passed through (`None`: the raw frames).
    pub denoiser: Option<Denoiser>,
    /// Samples per pixel per frame actually used (after equal-time calibration); for a method
    /// that chooses counts per pixel, the most a pixel may take.
    pub spp: u32,
    /// Mean over replicas of the mean samples per pixel of the final frame
    /// ([`Rendered::spp`]): `spp` unless the method chooses counts per pixel (`adaptive`).
    pub mean_spp: f64,
    pub replicas: usize,
    /// Seconds per rendered frame on the backend's clock ([`engine::clock`]) over replicas (one
    /// timing per replica, over every frame it rendered), the denoiser's included at equal
    /// time. Efficiencies count these; their per-replica spread is in every efficiency's
    /// interval ([`crate::uncertainty::log_cost`]).
    pub seconds: Estimate,
    /// Wall-clock seconds per rendered frame of the rendering over replicas (reported beside
    /// `seconds`, counted nowhere).
    pub wall_seconds: Estimate,
    /// The denoiser's seconds per frame over replicas (`None` for raw frames).
    pub denoiser_seconds: Option<Estimate>,
    pub frames_rendered: u32,
    /// The metrics at the last frame.
    pub metrics: Vec<AreaMetrics>,
    /// Paper 001's metric over whole last frames, over replicas ([`tonemapped_mse`]).
    pub tonemapped_mse: Estimate,
    /// FLIP and the low-frequency error per area at the last frame.
    pub perceptual: Vec<PerceptualMetrics>,
    pub nonfinite: u64,
    /// The metrics at every measured frame, ascending; the last is [`MethodResult::metrics`].
    pub convergence: Vec<FrameMetrics>,
    /// The change of the error from frame to frame per area ([`crate::flicker`]); empty unless
    /// the measured frames are consecutive (a convergence record).
    pub flicker: Vec<AreaFlicker>,
}

impl MethodResult {
    /// The row group of `method` from its replicas, whose frames are those of `references`
    /// (one [`Regions`] each, same order, the last frame last); `None` when there is no replica
    /// or a size disagrees with a reference.
    pub fn from_replicas(
        method: &str,
        spp: u32,
        replicas: &[Replica],
        references: &[(FrameReference, Regions)],
    ) -> Option<MethodResult> {
        let convergence = references
            .iter()
            .enumerate()
            .map(|(i, (reference, regions))| {
                let images: Vec<Image> = replicas
                    .iter()
                    .map(|r| r.frames.get(i).cloned())
                    .collect::<Option<_>>()?;
                Some(FrameMetrics {
                    frame: reference.frame,
                    metrics: area_metrics(&images, reference, regions)?,
                })
            })
            .collect::<Option<Vec<_>>>()?;
        let (last_reference, last_regions) = references.last()?;
        let tonemapped = replicas
            .iter()
            .map(|r| tonemapped_mse(r.frames.last()?, &last_reference.mean))
            .collect::<Option<Vec<f64>>>()?;
        let finals: Vec<&Image> = replicas
            .iter()
            .map(|r| r.frames.last())
            .collect::<Option<_>>()?;
        let perceptual = perceptual_metrics(&finals, last_reference, last_regions)?;
        let seconds: Vec<f64> = replicas.iter().map(|r| r.seconds_per_frame).collect();
        let wall: Vec<f64> = replicas.iter().map(|r| r.wall_seconds_per_frame).collect();
        let trajectories: Vec<&[Image]> = replicas.iter().map(|r| &r.frames[..]).collect();
        Some(MethodResult {
            method: method.to_string(),
            denoiser: None,
            spp,
            mean_spp: replicas.iter().map(|r| r.spp).sum::<f64>() / replicas.len() as f64,
            replicas: replicas.len(),
            seconds: Estimate::mean(&seconds),
            wall_seconds: Estimate::mean(&wall),
            denoiser_seconds: None,
            frames_rendered: replicas.iter().map(|r| r.frames_rendered).max()?,
            metrics: convergence.last()?.metrics.clone(),
            tonemapped_mse: Estimate::mean(&tonemapped),
            perceptual,
            nonfinite: replicas.iter().map(|r| r.nonfinite).sum(),
            convergence,
            flicker: flicker(&trajectories, references).unwrap_or_default(),
        })
    }

    /// The row of `method` whose last frames passed through `denoiser`: `replicas` hold the
    /// denoised last frame each, measured against the last of `references`. `counted`: seconds
    /// per frame of the denoiser that its time per frame adds (equal time: a frame costs its
    /// rendering and its denoising). The caller passes one figure for every method of a
    /// denoiser: the filter's cost does not depend on the method, so a per-replica timing would
    /// add only the machine's noise to the ratios.
    pub fn denoised(
        method: &str,
        spp: u32,
        denoiser: Denoiser,
        replicas: &[Replica],
        references: &[(FrameReference, Regions)],
        counted: Option<f64>,
    ) -> Option<MethodResult> {
        let last = references.len().checked_sub(1)?;
        let mut row = MethodResult::from_replicas(method, spp, replicas, &references[last..])?;
        if let Some(c) = counted {
            let seconds: Vec<f64> = replicas.iter().map(|r| r.seconds_per_frame + c).collect();
            row.seconds = Estimate::mean(&seconds);
        }
        let seconds: Vec<f64> = replicas
            .iter()
            .map(|r| r.denoiser_seconds_per_frame)
            .collect();
        row.denoiser = Some(denoiser);
        row.denoiser_seconds = Some(Estimate::mean(&seconds));
        Some(row)
    }

    /// The row's name: the method, with `+<denoiser>` for denoised frames.
    pub fn label(&self) -> String {
        match self.denoiser {
            Some(d) => format!("{}+{d}", self.method),
            None => self.method.clone(),
        }
    }

    /// FLIP and the low-frequency error of `area` at the last frame, if it is not empty.
    pub fn perceptual(&self, area: Area) -> Option<&PerceptualMetrics> {
        self.perceptual.iter().find(|m| m.area == area)
    }

    /// The flicker in `area`, if it was measured.
    pub fn flicker(&self, area: Area) -> Option<Measured> {
        let f = self.flicker.iter().find(|f| f.area == area)?;
        Some(Measured::of(&f.flicker))
    }

    /// The metrics of `area` at the last frame, if it is not empty.
    pub fn area(&self, area: Area) -> Option<&AreaMetrics> {
        self.metrics.iter().find(|m| m.area == area)
    }

    /// Efficiency `1 / (MSE · seconds per frame)` in `area`; `None` unless the MSE is positive
    /// (after the reference's variance is subtracted).
    pub fn efficiency(&self, area: Area) -> Option<Measured> {
        let cost = log_cost(&self.area(area)?.mse, &self.seconds)?;
        let m = Measured::of_log(&cost);
        Some(Measured {
            value: 1.0 / m.value,
            ci: m.ci.map(|i| i.reciprocal()),
        })
    }

    /// `efficiency(self) / efficiency(baseline)` in `area` = `(MSE_b · s_b) / (MSE · s)`, paired
    /// by replica seed; > 1 means `self` is more efficient.
    pub fn efficiency_ratio(&self, baseline: &MethodResult, area: Area) -> Option<Measured> {
        Some(Measured::of_log(&baseline.log_cost_ratio(self, area)?))
    }

    /// `MSE(self) / MSE(other)` in `area`, paired by replica seed; < 1 means `self` has the
    /// lower error.
    pub fn mse_ratio(&self, other: &MethodResult, area: Area) -> Option<Measured> {
        Some(Measured::of_log(&self.log_mse_ratio(other, area)?))
    }

    /// `ln(MSE(self) / MSE(other))` in `area`, paired by replica seed.
    pub fn log_mse_ratio(&self, other: &MethodResult, area: Area) -> Option<Estimate> {
        self.area(area)?
            .mse
            .ln()?
            .minus(&other.area(area)?.mse.ln()?)
    }

    /// `ln((MSE · s)(self) / (MSE · s)(other))` in `area`, paired by replica seed: the
    /// inverse efficiency ratio; below 0 means `self` is more efficient.
    pub fn log_cost_ratio(&self, other: &MethodResult, area: Area) -> Option<Estimate> {
        let own = log_cost(&self.area(area)?.mse, &self.seconds)?;
        own.minus(&log_cost(&other.area(area)?.mse, &other.seconds)?)
    }
}
