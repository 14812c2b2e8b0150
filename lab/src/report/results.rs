//! `results.json` of a comparison (schema `reshift-compare/1`, docs/results-schema.md) as typed
//! structs. Optional and non-finite numbers are written as `null`, never NaN; keys are written
//! in sorted order ([`Results::to_json`]).

use std::collections::BTreeMap;
use std::path::Path;

use serde::Serialize;
use sss::integrator::Reference;

use crate::method_result::MethodResult;
use crate::metrics::{AreaMetrics, BIAS_CONFIDENCE, REL_EPSILON, efficiency};
use crate::regions::{Region, Regions};

/// The schema name written into [`Results::schema`].
pub const SCHEMA: &str = "reshift-compare/1";

/// The whole document.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Results {
    pub schema: String,
    pub scene: String,
    /// `cpu` or `vulkan (<device>)`.
    pub backend: String,
    pub width: u32,
    pub height: u32,
    /// Frames of the trajectory; errors are measured on the last, `frame`.
    pub frames: u32,
    pub frame: u32,
    pub replicas: u32,
    pub budget: Budget,
    pub reference: ReferenceEntry,
    pub rel_epsilon: f64,
    pub bias_confidence: f64,
    /// Whether the caller stopped the comparison before every replica was rendered.
    pub interrupted: bool,
    /// Pixels per region.
    pub regions: BTreeMap<String, usize>,
    pub error_map_scale: ErrorMapScale,
    pub methods: Vec<MethodEntry>,
}

/// What was run, for [`Results::new`].
pub struct RunEntry {
    pub scene: String,
    pub backend: String,
    pub width: u32,
    pub height: u32,
    pub frames: u32,
    pub replicas: u32,
    pub equal_time: Option<f64>,
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

/// The values at the top of the false-colour scales, shared by all methods' error maps.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ErrorMapScale {
    pub absolute: f64,
    pub relative: f64,
}

/// One method's images, relative to the output folder.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ImageFiles {
    pub final_exr: String,
    pub final_png: String,
    pub abs_error_png: String,
    pub rel_error_png: String,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MethodEntry {
    pub method: String,
    pub spp: u32,
    pub mean_spp: f64,
    pub replicas: usize,
    pub seconds_per_frame: f64,
    pub frames_rendered: u32,
    pub nonfinite: u64,
    pub tonemapped_mse: f64,
    pub tonemapped_rmse: f64,
    pub images: ImageFiles,
    pub areas: Vec<AreaEntry>,
}

/// docs/results-schema.md explains each field.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AreaEntry {
    pub area: String,
    pub pixels: usize,
    pub mse: f64,
    pub mse_ci99: Option<f64>,
    pub rel_mse: f64,
    pub reference_mean: f64,
    pub bias: f64,
    pub bias_ci99: Option<f64>,
    pub relative_bias: Option<f64>,
    pub variance: Option<f64>,
    pub reference_mse: f64,
    pub efficiency: Option<f64>,
}

impl Results {
    /// The document of `methods` (with their images) on `scene`: the schema name and the
    /// metric constants filled in.
    pub fn new(
        run: RunEntry,
        reference: ReferenceEntry,
        regions: &Regions,
        error_map_scale: ErrorMapScale,
        methods: Vec<MethodEntry>,
    ) -> Results {
        Results {
            schema: SCHEMA.into(),
            scene: run.scene,
            backend: run.backend,
            width: run.width,
            height: run.height,
            frames: run.frames,
            frame: run.frames - 1,
            replicas: run.replicas,
            budget: Budget::new(run.equal_time),
            reference,
            rel_epsilon: REL_EPSILON,
            bias_confidence: BIAS_CONFIDENCE,
            interrupted: run.interrupted,
            regions: region_counts(regions),
            error_map_scale,
            methods,
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

impl MethodEntry {
    pub fn new(r: &MethodResult, images: ImageFiles) -> MethodEntry {
        MethodEntry {
            method: r.method.clone(),
            spp: r.spp,
            mean_spp: r.mean_spp,
            replicas: r.replicas,
            seconds_per_frame: r.seconds_per_frame,
            frames_rendered: r.frames_rendered,
            nonfinite: r.nonfinite,
            tonemapped_mse: r.tonemapped_mse,
            tonemapped_rmse: r.tonemapped_mse.sqrt(),
            images,
            areas: r
                .metrics
                .iter()
                .map(|m| AreaEntry::new(m, r.seconds_per_frame))
                .collect(),
        }
    }
}

impl AreaEntry {
    pub fn new(m: &AreaMetrics, seconds_per_frame: f64) -> AreaEntry {
        AreaEntry {
            area: m.area.name().to_string(),
            pixels: m.pixels,
            mse: m.mse,
            mse_ci99: m.mse_ci,
            rel_mse: m.rel_mse,
            reference_mean: m.reference_mean,
            bias: m.bias,
            bias_ci99: m.bias_ci,
            relative_bias: (m.reference_mean > 0.0).then(|| m.bias / m.reference_mean),
            variance: m.variance,
            reference_mse: m.reference_mse,
            efficiency: efficiency(m.mse, seconds_per_frame),
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
            mse_ci99: None,
            rel_mse: 0.5,
            reference_mean: 0.0,
            bias: f64::INFINITY,
            bias_ci99: None,
            relative_bias: None,
            variance: Some(0.25),
            reference_mse: 0.0,
            efficiency: Some(f64::NAN),
        };
        let json = serde_json::to_value(&area).unwrap();
        assert!(json["mse"].is_null() && json["bias"].is_null());
        assert!(json["bias_ci99"].is_null() && json["efficiency"].is_null());
        assert_eq!(json["variance"], 0.25);
        let keys: Vec<&String> = json.as_object().unwrap().keys().collect();
        assert!(keys.windows(2).all(|w| w[0] < w[1]), "{keys:?}");
    }
}
