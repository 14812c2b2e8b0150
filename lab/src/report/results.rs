//! `results.json` of a comparison (schema `reshift-compare/6`, docs/results-schema.md) as typed
//! structs. Optional and non-finite numbers are written as `null`, never NaN; keys are written
//! in sorted order ([`Results::to_json`]).

use std::collections::BTreeMap;
use std::path::Path;

use engine::clock::Clock;
use serde::Serialize;
use sss::integrator::Reference;

use crate::method_result::{FrameMetrics, Measured, MethodResult};
use crate::metrics::{AreaMetrics, BIAS_CONFIDENCE, REL_EPSILON};
use crate::reference_cache::Provenance;
use crate::regions::{Region, Regions};
use crate::uncertainty::{CONFIDENCE, INTERVAL_METHOD, Interval};

/// The schema name written into [`Results::schema`].
pub const SCHEMA: &str = "reshift-compare/6";

/// The whole document.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Results {
    pub schema: String,
    pub scene: String,
    /// `cpu` or `vulkan (<device>)`.
    pub backend: String,
    /// What `seconds_per_frame` counts ([`Clock::name`]): `process CPU time` on the CPU
    /// backend, `wall time` on Vulkan.
    pub clock: String,
    pub width: u32,
    pub height: u32,
    /// Frames of the trajectory; the tables measure the last, `frame`.
    pub frames: u32,
    pub frame: u32,
    pub replicas: u32,
    /// The seed of the first replica: replica k ran with seed `first_seed + k`.
    pub first_seed: u64,
    pub budget: Budget,
    /// The reference of the last frame.
    pub reference: ReferenceEntry,
    /// The reference of every measured frame, ascending (the last is `reference`).
    pub frame_references: Vec<FrameReferenceEntry>,
    pub rel_epsilon: f64,
    pub bias_confidence: f64,
    /// The confidence of every interval except the bias's.
    pub confidence: f64,
    /// How the intervals are computed ([`INTERVAL_METHOD`]).
    pub interval_method: String,
    /// The method efficiency and MSE ratios are taken against (`null`: none, no ratios).
    pub baseline: Option<String>,
    /// Whether the caller stopped the comparison before every replica was rendered.
    pub interrupted: bool,
    /// Pixels per region at the last frame.
    pub regions: BTreeMap<String, usize>,
    pub error_map_scale: ErrorMapScale,
    pub figures: FigureFiles,
    /// The denoisers of the comparison (`oidn`, `svgf`); each adds a denoised entry per method
    /// to `methods` (`denoiser` set), whose ratios are to the baseline's denoised entry.
    pub denoisers: Vec<String>,
    /// Why a denoiser left out entries, one line each.
    pub denoise_errors: Vec<String>,
    /// The raw entries, then each denoiser's.
    pub methods: Vec<MethodEntry>,
    /// The references' own frame-to-frame change per area, the scale of the entries' `flicker`
    /// (`lab::flicker`); empty without a convergence record.
    pub reference_flicker: Vec<ReferenceFlickerEntry>,
    /// The trajectory video of every raw entry (empty with `--no-video`).
    pub videos: Vec<VideoEntry>,
    /// What the videos leave out, one line each.
    pub video_notes: Vec<String>,
}

/// One method's trajectory video (replica 0), relative to the output folder.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct VideoEntry {
    pub method: String,
    /// Animated PNG, looping.
    pub apng: String,
    /// H.264 MP4 (`null`: `ffmpeg` is not on the PATH).
    pub mp4: Option<String>,
}

/// The references' mean frame-to-frame change of luminance in one area.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ReferenceFlickerEntry {
    pub area: String,
    pub change: f64,
}

/// One entry's flicker in one area, over replicas.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FlickerEntry {
    pub area: String,
    pub flicker: f64,
    pub flicker_ci: Option<Interval>,
}

/// What was run, for [`Results::new`].
pub struct RunEntry {
    pub scene: String,
    pub backend: String,
    /// The clock the renders were timed with.
    pub clock: Clock,
    pub width: u32,
    pub height: u32,
    pub frames: u32,
    pub replicas: u32,
    pub first_seed: u64,
    pub equal_time: Option<f64>,
    pub baseline: Option<String>,
    pub interrupted: bool,
}

/// How methods were budgeted.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Budget {
    /// `equal-spp` or `equal-time`.
    pub mode: String,
    /// The equal-time budget.
    pub seconds_per_frame: Option<f64>,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ReferenceEntry {
    pub path: String,
    pub spp: u64,
    pub batches: u32,
    pub seed: u64,
    /// Whether it was reused rather than computed by this comparison.
    pub cached: bool,
}

/// The reference of one measured frame.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FrameReferenceEntry {
    pub frame: u32,
    pub spp: u64,
    pub batches: u32,
    pub path: String,
    pub cached: bool,
}

/// The values at the top of the false-colour scales, shared by all methods' error maps.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ErrorMapScale {
    pub absolute: f64,
    pub relative: f64,
    pub low_frequency: f64,
}

/// One method's images, relative to the output folder.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ImageFiles {
    pub final_exr: String,
    pub final_png: String,
    pub abs_error_png: String,
    pub rel_error_png: String,
    /// FLIP per pixel (FLIP's magma map, 0 to 1).
    pub flip_png: String,
    /// The low-frequency error per pixel.
    pub low_frequency_png: String,
}

/// The comparison's figures, relative to the output folder.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FigureFiles {
    /// Reference and methods side by side with insets of each region (paper 001 Fig. 6).
    pub figure: String,
    /// MSE against frame, one panel per region.
    pub convergence: String,
    /// The self-contained HTML report.
    pub report: String,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MethodEntry {
    pub method: String,
    /// The denoiser the last frames passed through (`null`: raw frames).
    pub denoiser: Option<String>,
    /// The denoiser's seconds per frame (included in `seconds_per_frame`).
    pub denoiser_seconds_per_frame: Option<f64>,
    pub denoiser_seconds_per_frame_ci: Option<Interval>,
    pub spp: u32,
    pub mean_spp: f64,
    pub replicas: usize,
    /// Mean over replicas of the seconds per rendered frame on the comparison's `clock`
    /// (efficiencies and equal time count these).
    pub seconds_per_frame: f64,
    pub seconds_per_frame_ci: Option<Interval>,
    /// One timing per replica, by seed.
    pub seconds_per_frame_replicas: Vec<f64>,
    /// The same renders on the wall clock (the denoiser's time not included), reported only.
    pub wall_seconds_per_frame: f64,
    pub wall_seconds_per_frame_ci: Option<Interval>,
    pub wall_seconds_per_frame_replicas: Vec<f64>,
    pub frames_rendered: u32,
    pub nonfinite: u64,
    pub tonemapped_mse: f64,
    pub tonemapped_mse_ci: Option<Interval>,
    pub tonemapped_rmse: f64,
    pub images: ImageFiles,
    pub areas: Vec<AreaEntry>,
    /// The MSE per area at every measured frame, ascending.
    pub convergence: Vec<ConvergenceEntry>,
    /// The change of the error from frame to frame per area (`lab::flicker`); empty without a
    /// convergence record and for denoised entries (their last frame only).
    pub flicker: Vec<FlickerEntry>,
}

/// docs/results-schema.md explains each field.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AreaEntry {
    pub area: String,
    pub pixels: usize,
    pub mse: f64,
    pub mse_ci: Option<Interval>,
    pub rel_mse: f64,
    pub rel_mse_ci: Option<Interval>,
    pub reference_mean: f64,
    pub bias: f64,
    pub bias_ci99: Option<f64>,
    pub relative_bias: Option<f64>,
    pub variance: Option<f64>,
    pub reference_mse: f64,
    pub efficiency: Option<f64>,
    pub efficiency_ci: Option<Interval>,
    pub efficiency_ratio: Option<f64>,
    pub efficiency_ratio_ci: Option<Interval>,
    pub mse_ratio: Option<f64>,
    pub mse_ratio_ci: Option<Interval>,
    /// Mean LDR-FLIP over the area ([`crate::perceptual`]).
    pub flip: Option<f64>,
    pub flip_ci: Option<Interval>,
    /// The low-frequency error ([`crate::perceptual`]).
    pub low_frequency_mse: Option<f64>,
    pub low_frequency_mse_ci: Option<Interval>,
}

/// The errors of one frame.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ConvergenceEntry {
    pub frame: u32,
    pub areas: Vec<ConvergenceArea>,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ConvergenceArea {
    pub area: String,
    pub pixels: usize,
    pub mse: f64,
    pub mse_ci: Option<Interval>,
    pub rel_mse: f64,
    pub rel_mse_ci: Option<Interval>,
    pub reference_mse: f64,
}

impl Results {
    /// The document of `methods` (with their images) on `scene`: the schema name and the
    /// metric constants filled in.
    pub fn new(
        run: RunEntry,
        reference: ReferenceEntry,
        frame_references: Vec<FrameReferenceEntry>,
        regions: &Regions,
        error_map_scale: ErrorMapScale,
        figures: FigureFiles,
        denoisers: Vec<String>,
        denoise_errors: Vec<String>,
        methods: Vec<MethodEntry>,
    ) -> Results {
        Results {
            schema: SCHEMA.into(),
            scene: run.scene,
            backend: run.backend,
            clock: run.clock.name().into(),
            width: run.width,
            height: run.height,
            frames: run.frames,
            frame: run.frames - 1,
            replicas: run.replicas,
            first_seed: run.first_seed,
            budget: Budget::new(run.equal_time),
            reference,
            frame_references,
            rel_epsilon: REL_EPSILON,
            bias_confidence: BIAS_CONFIDENCE,
            confidence: CONFIDENCE,
            interval_method: INTERVAL_METHOD.into(),
            baseline: run.baseline,
            interrupted: run.interrupted,
            regions: region_counts(regions),
            error_map_scale,
            figures,
            denoisers,
            denoise_errors,
            methods,
            reference_flicker: Vec::new(),
            videos: Vec::new(),
            video_notes: Vec::new(),
        }
    }

    /// The document as a JSON value: keys sorted, non-finite numbers `null`.
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::to_value(self).expect("plain data serializes")
    }

    /// [`Results::to_json`] pretty-printed, as written to `results.json`.
    pub fn to_json_pretty(&self) -> String {
        serde_json::to_string_pretty(&self.to_json()).expect("JSON values")
    }
}

impl Budget {
    /// `equal-time` with `seconds_per_frame`, or `equal-spp`.
    pub fn new(equal_time: Option<f64>) -> Budget {
        Budget {
            mode: if equal_time.is_some() {
                "equal-time"
            } else {
                "equal-spp"
            }
            .into(),
            seconds_per_frame: equal_time,
        }
    }
}

impl ReferenceEntry {
    pub fn new(reference: &Reference, path: &Path, cached: bool) -> ReferenceEntry {
        ReferenceEntry {
            path: path.display().to_string(),
            spp: reference.batches_done() as u64 * reference.config.spp_per_batch as u64,
            batches: reference.batches_done(),
            seed: reference.config.seed,
            cached,
        }
    }
}

impl FrameReferenceEntry {
    pub fn new(p: &Provenance) -> FrameReferenceEntry {
        FrameReferenceEntry {
            frame: p.frame,
            spp: p.spp,
            batches: p.batches,
            path: p.path.display().to_string(),
            cached: p.cached,
        }
    }
}

/// `(value, interval)` of an optional measured number.
fn split(m: Option<Measured>) -> (Option<f64>, Option<Interval>) {
    (m.map(|m| m.value), m.and_then(|m| m.ci))
}

impl MethodEntry {
    /// The entry of `r`, with ratios to `baseline` when there is one.
    pub fn new(
        r: &MethodResult,
        baseline: Option<&MethodResult>,
        images: ImageFiles,
    ) -> MethodEntry {
        let seconds = Measured::of(&r.seconds);
        let wall = Measured::of(&r.wall_seconds);
        let tonemapped = Measured::of(&r.tonemapped_mse);
        let (denoiser_seconds, denoiser_seconds_ci) =
            split(r.denoiser_seconds.as_ref().map(Measured::of));
        MethodEntry {
            method: r.method.clone(),
            denoiser: r.denoiser.map(|d| d.name().to_string()),
            denoiser_seconds_per_frame: denoiser_seconds,
            denoiser_seconds_per_frame_ci: denoiser_seconds_ci,
            spp: r.spp,
            mean_spp: r.mean_spp,
            replicas: r.replicas,
            seconds_per_frame: seconds.value,
            seconds_per_frame_ci: seconds.ci,
            seconds_per_frame_replicas: r.seconds.influences().to_vec(),
            wall_seconds_per_frame: wall.value,
            wall_seconds_per_frame_ci: wall.ci,
            wall_seconds_per_frame_replicas: r.wall_seconds.influences().to_vec(),
            frames_rendered: r.frames_rendered,
            nonfinite: r.nonfinite,
            tonemapped_mse: tonemapped.value,
            tonemapped_mse_ci: tonemapped.ci,
            tonemapped_rmse: tonemapped.value.max(0.0).sqrt(),
            images,
            areas: r
                .metrics
                .iter()
                .map(|m| AreaEntry::new(m, r, baseline))
                .collect(),
            convergence: r.convergence.iter().map(ConvergenceEntry::new).collect(),
            flicker: r
                .flicker
                .iter()
                .map(|f| {
                    let m = Measured::of(&f.flicker);
                    FlickerEntry {
                        area: f.area.name().to_string(),
                        flicker: m.value,
                        flicker_ci: m.ci,
                    }
                })
                .collect(),
        }
    }
}

impl AreaEntry {
    pub fn new(m: &AreaMetrics, r: &MethodResult, baseline: Option<&MethodResult>) -> AreaEntry {
        let (mse, rel) = (Measured::of(&m.mse), Measured::of(&m.rel_mse));
        let (efficiency, efficiency_ci) = split(r.efficiency(m.area));
        let (efficiency_ratio, efficiency_ratio_ci) =
            split(baseline.and_then(|b| r.efficiency_ratio(b, m.area)));
        let (mse_ratio, mse_ratio_ci) = split(baseline.and_then(|b| r.mse_ratio(b, m.area)));
        let perceptual = r.perceptual(m.area);
        let (flip, flip_ci) = split(perceptual.map(|p| Measured::of(&p.flip)));
        let (low_frequency_mse, low_frequency_mse_ci) =
            split(perceptual.map(|p| Measured::of(&p.low_frequency)));
        AreaEntry {
            area: m.area.name().to_string(),
            pixels: m.pixels,
            mse: mse.value,
            mse_ci: mse.ci,
            rel_mse: rel.value,
            rel_mse_ci: rel.ci,
            reference_mean: m.reference_mean,
            bias: m.bias,
            bias_ci99: m.bias_ci,
            relative_bias: (m.reference_mean > 0.0).then(|| m.bias / m.reference_mean),
            variance: m.variance,
            reference_mse: m.reference_mse,
            efficiency,
            efficiency_ci,
            efficiency_ratio,
            efficiency_ratio_ci,
            mse_ratio,
            mse_ratio_ci,
            flip,
            flip_ci,
            low_frequency_mse,
            low_frequency_mse_ci,
        }
    }
}

impl ConvergenceEntry {
    pub fn new(f: &FrameMetrics) -> ConvergenceEntry {
        ConvergenceEntry {
            frame: f.frame,
            areas: f
                .metrics
                .iter()
                .map(|m| {
                    let (mse, rel) = (Measured::of(&m.mse), Measured::of(&m.rel_mse));
                    ConvergenceArea {
                        area: m.area.name().to_string(),
                        pixels: m.pixels,
                        mse: mse.value,
                        mse_ci: mse.ci,
                        rel_mse: rel.value,
                        rel_mse_ci: rel.ci,
                        reference_mse: m.reference_mse,
                    }
                })
                .collect(),
        }
    }
}

/// Pixels per region, by region name.
pub fn region_counts(regions: &Regions) -> BTreeMap<String, usize> {
    Region::ALL
        .iter()
        .map(|&r| (r.name().to_string(), regions.count(r)))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A non-finite or missing number is `null`; keys come out sorted.
    #[test]
    fn numbers_that_do_not_exist_are_null() {
        let area = AreaEntry {
            area: "image".into(),
            pixels: 4,
            mse: f64::NAN,
            mse_ci: Some(Interval {
                lo: 0.5,
                hi: f64::INFINITY,
            }),
            rel_mse: 0.5,
            rel_mse_ci: None,
            reference_mean: 0.0,
            bias: f64::INFINITY,
            bias_ci99: None,
            relative_bias: None,
            variance: Some(0.25),
            reference_mse: 0.0,
            efficiency: Some(f64::NAN),
            efficiency_ci: None,
            efficiency_ratio: None,
            efficiency_ratio_ci: None,
            mse_ratio: None,
            mse_ratio_ci: None,
            flip: None,
            flip_ci: None,
            low_frequency_mse: None,
            low_frequency_mse_ci: None,
        };
        let json = serde_json::to_value(&area).unwrap();
        assert!(json["mse"].is_null() && json["bias"].is_null());
        assert!(json["bias_ci99"].is_null() && json["efficiency"].is_null());
        assert_eq!(json["mse_ci"]["lo"], 0.5);
        assert!(json["mse_ci"]["hi"].is_null() && json["rel_mse_ci"].is_null());
        assert_eq!(json["variance"], 0.25);
        let keys: Vec<&String> = json.as_object().unwrap().keys().collect();
        assert!(keys.windows(2).all(|w| w[0] < w[1]), "{keys:?}");
    }
}
