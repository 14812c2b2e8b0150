//! One method's row group of a comparison: its metrics per area at every measured frame of its
//! replicas against that frame's reference, its cost per replica, and what follows from both
//! (efficiency and ratios to another method, each with its 95% interval,
//! [`crate::uncertainty`]).

use engine::Image;

use crate::metrics::{Area, AreaMetrics, area_metrics, tonemapped_mse};
use crate::reference_cache::FrameReference;
use crate::regions::Regions;
use crate::uncertainty::{CONFIDENCE, Estimate, Interval, log_cost};

/// One replica of a method as a comparison keeps it.
#[derive(Clone, Debug)]
pub struct Replica {
    /// Linear RGB of each measured frame, in the comparison's order (the last frame last).
    pub frames: Vec<Image>,
    /// Wall-clock seconds per rendered frame.
    pub seconds_per_frame: f64,
    pub frames_rendered: u32,
    pub nonfinite: u64,
    /// Mean samples per pixel of the last frame ([`Rendered::spp`](crate::methods::Rendered)).
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
    /// Samples per pixel per frame actually used (after equal-time calibration); for a method
    /// that chooses counts per pixel, the most a pixel may take.
    pub spp: u32,
    /// Mean over replicas of the mean samples per pixel of the final frame
    /// ([`Rendered::spp`]): `spp` unless the method chooses counts per pixel (`adaptive`).
    pub mean_spp: f64,
    pub replicas: usize,
    /// Wall-clock seconds per rendered frame over replicas (one timing per replica).
    pub seconds: Estimate,
    pub frames_rendered: u32,
    /// The metrics at the last frame.
    pub metrics: Vec<AreaMetrics>,
    /// Seed 001's metric over whole last frames, over replicas ([`tonemapped_mse`]).
    pub tonemapped_mse: Estimate,
    pub nonfinite: u64,
    /// The metrics at every measured frame, ascending; the last is [`MethodResult::metrics`].
    pub convergence: Vec<FrameMetrics>,
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
        let (last_reference, _) = references.last()?;
        let tonemapped = replicas
            .iter()
            .map(|r| tonemapped_mse(r.frames.last()?, &last_reference.mean))
            .collect::<Option<Vec<f64>>>()?;
        let seconds: Vec<f64> = replicas.iter().map(|r| r.seconds_per_frame).collect();
        Some(MethodResult {
            method: method.to_string(),
            spp,
            mean_spp: replicas.iter().map(|r| r.spp).sum::<f64>() / replicas.len() as f64,
            replicas: replicas.len(),
            seconds: Estimate::mean(&seconds),
            frames_rendered: replicas.iter().map(|r| r.frames_rendered).max()?,
            metrics: convergence.last()?.metrics.clone(),
            tonemapped_mse: Estimate::mean(&tonemapped),
            nonfinite: replicas.iter().map(|r| r.nonfinite).sum(),
            convergence,
        })
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
