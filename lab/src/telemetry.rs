//! Reuse telemetry per region (issue 10): the [`engine::diagnostics::Telemetry`] of the last
//! frame of K replicas reduced per region of [`Region::ALL`] to one number per replica, and to
//! its mean over replicas with a 95% interval (the delta method, [`crate::uncertainty`]).
//! Where a pixel's final sample came from, per reuse pass the shift failure rate (all kinds and
//! by kind) and the MIS weight left to the pixel's own sample, the confidence histogram, and the
//! mean number of pixels holding the pixel's x2. The CPU backend records it; the Vulkan backend
//! has none.

use engine::diagnostics::{FAIL_KINDS, Telemetry};
use restir::shift::Fail;
use serde_json::{Value, json};

use crate::method_result::Measured;
use crate::regions::{Region, Regions};
use crate::report::tables::with_ci;
use crate::uncertainty::Estimate;

/// Upper edges of the confidence histogram's buckets; the last bucket is `c ≥ 32`.
pub const CONFIDENCE_EDGES: [f32; 6] = [1.5, 2.5, 4.5, 8.5, 16.5, 32.0];

/// One reuse pass in one region.
#[derive(Clone, Debug)]
pub struct PassSummary {
    pub label: String,
    /// Fraction of pixels with a final sample that this pass moved in last.
    pub moved_in: Option<Estimate>,
    /// Failed / shifted neighbour samples.
    pub failure_rate: Option<Estimate>,
    /// Per [`Fail`] kind, failed of that kind / shifted.
    pub failure_by_kind: Vec<(String, Option<Estimate>)>,
    /// Mean `m_0(y_0)` of the pixel's own sample where it had a positive weight.
    pub canonical_mis: Option<Estimate>,
}

/// The telemetry of one region.
#[derive(Clone, Debug)]
pub struct RegionSummary {
    pub region: Region,
    pub pixels: usize,
    /// Fraction of pixels with a final sample that kept their own candidate.
    pub own: Option<Estimate>,
    pub passes: Vec<PassSummary>,
    /// Fraction of pixels with a final sample per confidence bucket ([`CONFIDENCE_EDGES`]).
    pub confidence: Vec<Option<Estimate>>,
    /// Mean over pixels with a final sample of the pixels holding the same x2 (1 = unique).
    pub sharing: Option<Estimate>,
}

/// `value(run)` over the replicas `runs`; `None` if a replica has no value.
fn over_replicas(
    runs: &[Telemetry],
    value: impl Fn(&Telemetry) -> Option<f64>,
) -> Option<Estimate> {
    let values: Vec<f64> = runs.iter().map(value).collect::<Option<_>>()?;
    (!values.is_empty()).then(|| Estimate::mean(&values))
}

/// `num / den`, `None` for an empty denominator.
fn ratio(num: f64, den: f64) -> Option<f64> {
    (den > 0.0).then(|| num / den)
}

/// The summary of `runs` (replicas of one method) per region of the last frame's `regions`.
pub fn summarise(runs: &[Telemetry], regions: &Regions) -> Vec<RegionSummary> {
    let labels: Vec<String> = runs
        .first()
        .map(|t| t.passes.iter().map(|p| p.label.clone()).collect())
        .unwrap_or_default();
    Region::ALL
        .iter()
        .map(|&region| {
            let pixels = regions.pixels(region);
            let with_sample =
                |t: &Telemetry| pixels.iter().filter(|&&p| t.origin[p].is_some()).count() as f64;
            let origin_share = |pass: u32| {
                over_replicas(runs, |t| {
                    let n = pixels
                        .iter()
                        .filter(|&&p| t.origin[p] == Some(pass))
                        .count();
                    ratio(n as f64, with_sample(t))
                })
            };
            let passes = labels
                .iter()
                .enumerate()
                .map(|(i, label)| {
                    let failed = |t: &Telemetry, kind: Option<usize>| {
                        let pass = &t.passes[i];
                        let (mut failed, mut shifted) = (0u64, 0u64);
                        for &p in &pixels {
                            shifted += pass.shifted[p] as u64;
                            failed += match kind {
                                Some(k) => pass.failed_by[p][k] as u64,
                                None => pass.failed_by[p].iter().map(|&n| n as u64).sum(),
                            };
                        }
                        ratio(failed as f64, shifted as f64)
                    };
                    PassSummary {
                        label: label.clone(),
                        moved_in: origin_share(i as u32 + 1),
                        failure_rate: over_replicas(runs, |t| failed(t, None)),
                        failure_by_kind: (0..FAIL_KINDS)
                            .map(|k| {
                                let name = format!("{:?}", Fail::ALL[k]);
                                (name, over_replicas(runs, |t| failed(t, Some(k))))
                            })
                            .collect(),
                        canonical_mis: over_replicas(runs, |t| {
                            let m: Vec<f64> = pixels
                                .iter()
                                .filter_map(|&p| t.passes[i].canonical_mis[p])
                                .map(f64::from)
                                .collect();
                            ratio(m.iter().sum(), m.len() as f64)
                        }),
                    }
                })
                .collect();
            let confidence = (0..=CONFIDENCE_EDGES.len())
                .map(|b| {
                    over_replicas(runs, |t| {
                        let n = pixels
                            .iter()
                            .filter_map(|&p| t.confidence[p])
                            .filter(|&c| bucket(c) == b)
                            .count();
                        ratio(n as f64, with_sample(t))
                    })
                })
                .collect();
            RegionSummary {
                region,
                pixels: pixels.len(),
                own: origin_share(0),
                passes,
                confidence,
                sharing: over_replicas(runs, |t| {
                    let total: f64 = pixels.iter().map(|&p| t.sharing[p] as f64).sum();
                    ratio(total, with_sample(t))
                }),
            }
        })
        .collect()
}

/// The confidence bucket of `c` ([`CONFIDENCE_EDGES`]).
pub fn bucket(c: f32) -> usize {
    CONFIDENCE_EDGES
        .iter()
        .position(|&edge| c < edge)
        .unwrap_or(CONFIDENCE_EDGES.len())
}

/// The bucket names: `≈1`, `≈2`, `3–4`, `5–8`, `9–16`, `17–31`, `≥32`.
fn bucket_names() -> Vec<String> {
    let mut names = vec!["≈1".to_string(), "≈2".to_string()];
    let mut lo = 2.5f32;
    for &hi in &CONFIDENCE_EDGES[2..] {
        names.push(format!("{}–{}", lo.ceil(), hi.ceil() - 1.0));
        lo = hi;
    }
    names.push(format!("≥{}", CONFIDENCE_EDGES[CONFIDENCE_EDGES.len() - 1]));
    names
}

fn shown(e: &Option<Estimate>) -> String {
    with_ci(e.as_ref().map(Measured::of))
}

/// `label: value [lo, hi]` per item with a positive estimate, joined by `<br>`; `-` if none.
fn listed<'a>(items: impl Iterator<Item = (String, &'a Option<Estimate>)>) -> String {
    let cells: Vec<String> = items
        .filter(|(_, e)| e.as_ref().is_some_and(|e| e.value > 0.0))
        .map(|(label, e)| format!("{label}: {}", shown(e)))
        .collect();
    if cells.is_empty() {
        "-".into()
    } else {
        cells.join("<br>")
    }
}

/// The telemetry of one method as a Markdown table, one row per region.
pub fn markdown(summary: &[RegionSummary]) -> String {
    let mut out = String::from(
        "| region | px | kept own sample | moved in last by | shift failures (kinds) | m₀ of own sample | confidence c | pixels sharing x2 |\n|---|---:|---:|---|---|---|---|---:|\n",
    );
    let names = bucket_names();
    for s in summary {
        let moved = listed(s.passes.iter().map(|p| (p.label.clone(), &p.moved_in)));
        let failures: Vec<String> = s
            .passes
            .iter()
            .map(|p| {
                let kinds = listed(p.failure_by_kind.iter().map(|(k, e)| (k.clone(), e)));
                format!("{}: {} ({kinds})", p.label, shown(&p.failure_rate))
            })
            .collect();
        let mis = listed(s.passes.iter().map(|p| (p.label.clone(), &p.canonical_mis)));
        let confidence = listed(names.iter().cloned().zip(&s.confidence));
        out.push_str(&format!(
            "| {} | {} | {} | {moved} | {} | {mis} | {confidence} | {} |\n",
            s.region,
            s.pixels,
            shown(&s.own),
            failures.join("<br>"),
            shown(&s.sharing)
        ));
    }
    out
}

fn estimate_json(e: &Option<Estimate>) -> Value {
    match e.as_ref().map(Measured::of) {
        Some(m) => json!({
            "value": m.value,
            "lo": m.ci.map(|i| i.lo),
            "hi": m.ci.map(|i| i.hi),
        }),
        None => Value::Null,
    }
}

/// The summary as JSON, one object per region.
pub fn json(summary: &[RegionSummary]) -> Value {
    let names = bucket_names();
    summary
        .iter()
        .map(|s| {
            json!({
                "region": s.region.name(),
                "pixels": s.pixels,
                "kept_own_sample": estimate_json(&s.own),
                "pixels_sharing_x2": estimate_json(&s.sharing),
                "confidence": names.iter().zip(&s.confidence)
                    .map(|(n, e)| (n.clone(), estimate_json(e)))
                    .collect::<serde_json::Map<_, _>>(),
                "passes": s.passes.iter().map(|p| json!({
                    "label": p.label,
                    "moved_in_last": estimate_json(&p.moved_in),
                    "failure_rate": estimate_json(&p.failure_rate),
                    "failure_by_kind": p.failure_by_kind.iter()
                        .map(|(k, e)| (k.clone(), estimate_json(e)))
                        .collect::<serde_json::Map<_, _>>(),
                    "canonical_mis_weight": estimate_json(&p.canonical_mis),
                })).collect::<Vec<_>>(),
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use engine::{Preset, RunConfig};
    use sss::scene::{GBuffer, Scene};

    #[test]
    fn confidence_buckets() {
        assert_eq!(bucket(1.0), 0);
        assert_eq!(bucket(2.0), 1);
        assert_eq!(bucket(4.0), 2);
        assert_eq!(bucket(20.0), 5);
        assert_eq!(bucket(40.0), 6);
        assert_eq!(
            bucket_names(),
            ["≈1", "≈2", "3–4", "5–8", "9–16", "17–31", "≥32"]
        );
    }

    /// On a tiny `bumpy` with two replicas: the origin fractions of every region sum to 1, the
    /// confidence histogram sums to 1, failure kinds sum to the failure rate, and every value
    /// has an interval. Control: reconnection shares x2 more than delayed reconnection, which
    /// re-derives x2 at the receiver (translucent, by the replicas' means).
    #[test]
    fn region_summaries_are_consistent() {
        let mut scene = Scene::builtin("bumpy").unwrap();
        scene.camera = scene.camera.with_resolution(24, 18);
        let regions = Regions::classify(&scene, &GBuffer::render(&scene, 3), 1);
        let runs = |name: &str| -> Vec<Telemetry> {
            (0..2)
                .map(|seed| {
                    let config = RunConfig {
                        seed,
                        frames: 4,
                        collect_diagnostics: true,
                    };
                    engine::run(&scene, &Preset::named(name).unwrap(), &config)
                        .unwrap()
                        .diagnostics
                        .unwrap()
                        .telemetry
                        .unwrap()
                })
                .collect()
        };
        let reconnection = summarise(&runs("reconnection"), &regions);
        for s in &reconnection {
            if s.pixels == 0 {
                continue;
            }
            let origins = s.own.as_ref().unwrap().value
                + s.passes
                    .iter()
                    .map(|p| p.moved_in.as_ref().unwrap().value)
                    .sum::<f64>();
            assert!((origins - 1.0).abs() < 1e-9, "{}: {origins}", s.region);
            let histogram: f64 = s.confidence.iter().map(|e| e.as_ref().unwrap().value).sum();
            assert!((histogram - 1.0).abs() < 1e-9, "{}: {histogram}", s.region);
            for p in &s.passes {
                let Some(rate) = &p.failure_rate else {
                    continue;
                };
                let kinds: f64 = p
                    .failure_by_kind
                    .iter()
                    .map(|(_, e)| e.as_ref().unwrap().value)
                    .sum();
                assert!((kinds - rate.value).abs() < 1e-9, "{}", p.label);
                assert!(Measured::of(rate).ci.is_some());
            }
        }
        let delayed = summarise(&runs("delayed"), &regions);
        let sharing = |s: &[RegionSummary]| s[0].sharing.as_ref().unwrap().value;
        println!(
            "sharing: reconnection {}, delayed {}",
            sharing(&reconnection),
            sharing(&delayed)
        );
        assert!(sharing(&reconnection) > sharing(&delayed));
        let table = markdown(&reconnection);
        assert_eq!(table.lines().count(), 2 + Region::ALL.len(), "{table}");
        assert!(table.contains("spatial4:reconnection"), "{table}");
        assert_eq!(
            json(&reconnection).as_array().unwrap().len(),
            Region::ALL.len()
        );
    }
}
