//! The ground-truth experiment's outputs: the summary table (translucent pixels, model error per
//! region), the full per-region table, CSV, JSON and the findings.

use std::fmt::Write as _;

use serde_json::{Value, json};

use super::measure::{Measure, RegionMeasure};
use super::{SceneResult, WALK_FAMILY};
use lab::regions::Region;

/// `+3.71% [+2.60, +4.82]`: a relative model error and its interval, in percent.
fn model_error(r: &RegionMeasure) -> String {
    let e = &r.model_error;
    format!(
        "{:+.2}% [{:+.2}, {:+.2}]",
        100.0 * e.value,
        100.0 * e.low,
        100.0 * e.high
    )
}

fn noise(r: &RegionMeasure) -> String {
    format!("{:.2e} ± {:.1e}", r.noise.value, r.noise.half)
}

/// The walk's measure of a scene (the efficiency baseline).
fn walk(result: &SceneResult) -> Option<&Measure> {
    result
        .measures
        .iter()
        .find(|m| m.method.starts_with(&format!("{WALK_FAMILY}:")))
}

fn efficiency(result: &SceneResult, m: &Measure, region: Region) -> String {
    walk(result)
        .and_then(|w| m.efficiency_relative_to(w, region))
        .map_or("-".into(), |[e, low, high]| {
            format!("{e:.2} [{low:.2}, {high:.2}]")
        })
}

fn cell(m: &Measure, region: Region, f: impl Fn(&RegionMeasure) -> String) -> String {
    m.region(region).map_or("-".into(), f)
}

/// Per scene and method: the model error in every region (relative to the ground truth's
/// region mean, 99% CI), the translucent noise, ms/frame and the translucent equal-time
/// efficiency relative to the walk; skipped methods and their reasons after each scene.
pub fn summary(results: &[SceneResult]) -> String {
    let mut out = String::from(
        "| scene | method | model error translucent | lit | penumbra | shadowed | noise (translucent) | ms/frame | efficiency vs walk |\n\
         |---|---|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    for result in results {
        for m in &result.measures {
            let _ = writeln!(
                out,
                "| {} | {} | {} | {} | {} | {} | {} | {:.1} | {} |",
                result.scene,
                m.method,
                cell(m, Region::Translucent, model_error),
                cell(m, Region::Lit, model_error),
                cell(m, Region::Penumbra, model_error),
                cell(m, Region::Shadowed, model_error),
                cell(m, Region::Translucent, noise),
                1e3 * m.seconds.mean,
                efficiency(result, m, Region::Translucent),
            );
        }
    }
    out.push_str(&notes(results));
    out
}

/// Skipped methods and non-finite counts, one line each.
fn notes(results: &[SceneResult]) -> String {
    let mut out = String::new();
    for result in results {
        for (method, reason) in &result.skipped {
            let _ = writeln!(out, "\n{}: {method} skipped: {reason}", result.scene);
        }
        for m in result.measures.iter().filter(|m| m.nonfinite > 0) {
            let _ = writeln!(
                out,
                "\n{}: {} had {} non-finite estimates",
                result.scene, m.method, m.nonfinite
            );
        }
    }
    out
}

/// Every scene, method and region: pixels, the ground truth's region mean ± s.e., the
/// method's, the model error, the noise and the equal-time efficiency relative to the walk.
pub fn full(results: &[SceneResult]) -> String {
    let mut out = String::from(
        "| scene | method | region | px | ground truth ± s.e. | method ± s.e. | model error (99% CI) | noise ± 99% | efficiency vs walk |\n\
         |---|---|---|---:|---:|---:|---:|---:|---:|\n",
    );
    for result in results {
        for m in &result.measures {
            for r in &m.regions {
                let _ = writeln!(
                    out,
                    "| {} | {} | {} | {} | {:.4e} ± {:.1e} | {:.4e} ± {:.1e} | {} | {} | {} |",
                    result.scene,
                    m.method,
                    r.region,
                    r.pixels,
                    r.truth.mean,
                    r.truth.std_err,
                    r.estimate.mean,
                    r.estimate.std_err,
                    model_error(r),
                    noise(r),
                    efficiency(result, m, r.region),
                );
            }
        }
    }
    out.push_str(&notes(results));
    out
}

/// One row per scene, method and region.
pub fn csv(results: &[SceneResult]) -> String {
    let mut out = String::from(
        "scene,method,region,pixels,truth_mean,truth_std_err,mean,std_err,model_error,model_error_ci_low,model_error_ci_high,noise,noise_ci_half,seconds_per_frame,efficiency_vs_walk,efficiency_ci_low,efficiency_ci_high\n",
    );
    for result in results {
        for m in &result.measures {
            for r in &m.regions {
                let e = walk(result).and_then(|w| m.efficiency_relative_to(w, r.region));
                let [eff, low, high] = e
                    .map_or([String::new(), String::new(), String::new()], |e| {
                        e.map(|v| format!("{v:e}"))
                    });
                let _ = writeln!(
                    out,
                    "{},{},{},{},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{eff},{low},{high}",
                    result.scene,
                    m.method,
                    r.region,
                    r.pixels,
                    r.truth.mean,
                    r.truth.std_err,
                    r.estimate.mean,
                    r.estimate.std_err,
                    r.model_error.value,
                    r.model_error.low,
                    r.model_error.high,
                    r.noise.value,
                    r.noise.half,
                    m.seconds.mean,
                );
            }
        }
    }
    out
}

/// `null` for a non-finite number.
fn number(v: f64) -> Value {
    serde_json::Number::from_f64(v).map_or(Value::Null, Value::Number)
}

/// One scene of `results.json`.
pub fn scene_json(result: &SceneResult) -> Value {
    let methods: Vec<Value> = result
        .measures
        .iter()
        .map(|m| {
            let regions: Vec<Value> = m
                .regions
                .iter()
                .map(|r| {
                    let e = walk(result).and_then(|w| m.efficiency_relative_to(w, r.region));
                    json!({
                        "region": r.region.name(),
                        "pixels": r.pixels,
                        "truth_mean": number(r.truth.mean),
                        "truth_std_err": number(r.truth.std_err),
                        "mean": number(r.estimate.mean),
                        "std_err": number(r.estimate.std_err),
                        "model_error": number(r.model_error.value),
                        "model_error_ci": [number(r.model_error.low), number(r.model_error.high)],
                        "noise": number(r.noise.value),
                        "noise_ci_half": number(r.noise.half),
                        "efficiency_vs_walk": e.map(|e| e.map(number)),
                    })
                })
                .collect();
            json!({
                "method": m.method,
                "replicas": m.replicas,
                "seconds_per_frame": number(m.seconds.mean),
                "seconds_std_err": number(m.seconds.std_err),
                "nonfinite": m.nonfinite,
                "regions": regions,
            })
        })
        .collect();
    json!({
        "scene": result.scene,
        "truth": {
            "file": result.truth.path.display().to_string(),
            "cached": result.truth.cached,
            "batches": result.truth.batches.len(),
            "spp_per_batch": result.truth.key.spp_per_batch,
        },
        "methods": methods,
        "skipped": result.skipped,
    })
}

/// `[low, high]` of `|b|` for a CI `[ci_low, ci_high]` of `b`.
fn magnitude(r: &RegionMeasure) -> [f64; 2] {
    let (low, high) = (r.model_error.low, r.model_error.high);
    if low > 0.0 {
        [low, high]
    } else if high < 0.0 {
        [-high, -low]
    } else {
        [0.0, high.max(-low)]
    }
}

/// The methods of `result` whose model error in `region` is detected (its interval excludes 0).
pub fn detected(result: &SceneResult, region: Region) -> Vec<&str> {
    result
        .measures
        .iter()
        .filter(|m| {
            m.region(region)
                .is_some_and(|r| r.model_error.is_detected())
        })
        .map(|m| m.method.as_str())
        .collect()
}

/// What the numbers say, per scene: which methods have a detected model error over translucent
/// pixels; whether single-scatter's model error is smaller than the
/// BSSRDF path tracer's over translucent pixels (`yes` / **no** only when the intervals of
/// `|model error|` are disjoint, else inconclusive), and whether the walk's own replicas agree
/// with the ground truth (their 99% CI contains 0).
pub fn findings(results: &[SceneResult]) -> String {
    let mut out = String::from("| scene | finding | holds | measured |\n|---|---|---|---|\n");
    let family = |result: &SceneResult, family: &str| {
        result
            .measures
            .iter()
            .find(|m| m.method.starts_with(&format!("{family}:")))
            .and_then(|m| m.region(Region::Translucent))
            .cloned()
    };
    for result in results {
        let flagged = detected(result, Region::Translucent);
        let _ = writeln!(
            out,
            "| {} | model error detected (translucent, 99% CI excludes 0) | {} | {} |",
            result.scene,
            if flagged.is_empty() { "none" } else { "yes" },
            flagged.join(", ")
        );
        if let (Some(ss), Some(pt)) = (family(result, "single-scatter"), family(result, "pt")) {
            let ([ss_low, ss_high], [pt_low, pt_high]) = (magnitude(&ss), magnitude(&pt));
            let holds = if ss_high < pt_low {
                "yes"
            } else if pt_high < ss_low {
                "**no**"
            } else {
                "inconclusive"
            };
            let _ = writeln!(
                out,
                "| {} | single-scatter is closer to the random walk than pt (translucent) | {holds} | {} vs {} |",
                result.scene,
                model_error(&ss),
                model_error(&pt)
            );
        }
        if let Some(w) = family(result, WALK_FAMILY) {
            let e = &w.model_error;
            let holds = if e.low <= 0.0 && 0.0 <= e.high {
                "yes"
            } else {
                "**no**"
            };
            let _ = writeln!(
                out,
                "| {} | the walk's replicas agree with the ground truth (control) | {holds} | {} |",
                result.scene,
                model_error(&w)
            );
        }
    }
    out
}
