//! The ablation's tables (`table.md`, `findings.md`, `telemetry.md`) and its rows as JSON.

use serde_json::{Value, json};

use lab::method_result::Measured;
use lab::regions::Region;
use lab::report::tables::{verdict_word, with_ci};
use lab::telemetry;

use super::rows::CPU_ONLY;
use super::{FRAMES, Measurement, Settings};

/// One telemetry table per row ([`telemetry::markdown`]).
pub(super) fn telemetry_markdown(measured: &[Measurement]) -> String {
    let mut out = String::from(
        "Reuse telemetry of the last frame per region: means over replicas with 95% intervals \
         (delta method). Runs with diagnostics on, same seeds as the timed runs (CPU backend \
         only). \"moved in last by\": the pass that last replaced the pixel's sample; \
         \"m₀\": the MIS weight of the pixel's own sample in that pass; \"pixels sharing x2\": \
         the mean number of pixels whose final sample has the pixel's entry point.\n",
    );
    for m in measured {
        let v = &m.variation;
        out.push_str(&format!(
            "\n### {} (`{}`, {}, {}×{})\n\n",
            v.label,
            v.spec,
            v.framing.name(),
            v.resolution.0,
            v.resolution.1
        ));
        match &m.telemetry {
            Some(t) => out.push_str(&telemetry::markdown(t)),
            None => out.push_str("No telemetry: the backend records none (CPU backend only).\n"),
        }
    }
    out
}

/// `ratio [lo, hi] lower|higher|inconclusive` for a ratio where below 1 is lower, or `-`.
fn ratio_cell(m: &Option<Measured>) -> String {
    let Some(m) = m else { return "-".into() };
    let word = match m.ci {
        Some(i) if i.below(1.0) => "lower",
        Some(i) if i.above(1.0) => "higher",
        _ => "inconclusive",
    };
    format!("{} {word}", with_ci(Some(*m)))
}

/// `ratio [lo, hi] verdict`, or `-`.
fn cell(m: &Option<Measured>) -> String {
    match m {
        Some(m) => format!("{} {}", with_ci(Some(*m)), verdict_word(m)),
        None => "-".into(),
    }
}

pub(super) fn markdown(measured: &[Measurement], scene: &str, settings: &Settings) -> String {
    let (w, h) = settings.resolution;
    let header = "| variation | method | camera | size | translucent | lit | penumbra | shadowed |\n\
                  |---|---|---|---|---:|---:|---:|---:|\n";
    let mut over_pt = format!(
        "Efficiency 1/(MSE·s) over 1-spp `pt`, frame {} of `{scene}`, {} replicas, reference {} spp; \
         95% intervals by the delta method over replicas (paired by seed, log scale); verdict \
         *better* / *worse* when the interval excludes 1, else *inconclusive*. Wall times on a \
         shared machine: their intervals hold the spread within the run, not a load change \
         between methods.\n\n| variation | method | camera | size | translucent | lit | penumbra | shadowed | ms/frame (pt) |\n\
         |---|---|---|---|---:|---:|---:|---:|---:|\n",
        FRAMES - 1,
        settings.replicas,
        settings.reference_spp
    );
    let mut over_default = format!(
        "\nEfficiency over the unmodified preset (same camera, {w}×{h}, paired by seed):\n\n{header}"
    );
    let mut mse_over_default = format!(
        "\nMSE over the unmodified preset at equal spp (same camera, {w}×{h}, paired by seed; the \
         MSEs are deterministic, the times are not), and time per frame over it:\n\n\
         | variation | method | camera | size | translucent | lit | penumbra | shadowed | time/frame |\n\
         |---|---|---|---|---:|---:|---:|---:|---:|\n"
    );
    for m in measured {
        let v = &m.variation;
        let lead = format!(
            "| {} | {} | {} | {}×{} |",
            v.label,
            v.spec,
            v.framing.name(),
            v.resolution.0,
            v.resolution.1
        );
        let cells = |ms: &[Option<Measured>]| ms.iter().map(cell).collect::<Vec<_>>().join(" | ");
        let (ms, pt_ms) = &m.milliseconds;
        over_pt.push_str(&format!(
            "{lead} {} | {} ({}) |\n",
            cells(&m.over_pt),
            with_ci(Some(*ms)),
            with_ci(*pt_ms)
        ));
        if let Some(d) = &m.over_default {
            over_default.push_str(&format!("{lead} {} |\n", cells(d)));
        }
        if let Some((mse, time)) = &m.mse_over_default {
            let mse: Vec<String> = mse.iter().map(ratio_cell).collect();
            mse_over_default.push_str(&format!(
                "{lead} {} | {} |\n",
                mse.join(" | "),
                ratio_cell(time)
            ));
        }
    }
    let mut notes = String::new();
    if !matches!(settings.backend, engine::Backend::Cpu) {
        notes.push_str("\nNot varied:\n\n");
        for modifier in CPU_ONLY {
            notes.push_str(&format!(
                "- {}: left out, it has no Vulkan kernel (CPU backend only)\n",
                &modifier[1..]
            ));
        }
    }
    format!("{over_pt}{over_default}{mse_over_default}{notes}")
}

/// What the intervals decide: per region, the rows more or less efficient than the unmodified
/// preset, and whether issue 10's bar is met (lower bound ≥ 5 over `pt` in penumbra and
/// shadow, > 1 over all translucent pixels).
pub(super) fn findings(measured: &[Measurement]) -> String {
    let mut out = String::from(
        "| region | more efficient than the unmodified preset | less efficient | rows whose lower bound over pt clears the bar |\n|---|---|---|---|\n",
    );
    for (i, region) in Region::ALL.iter().enumerate() {
        // Issue 10's bar: translucent > 1, penumbra and shadowed ≥ 5; none for lit.
        let bar = match region {
            Region::Translucent => Some((1.0, false)),
            Region::Penumbra | Region::Shadowed => Some((5.0, true)),
            Region::Lit | Region::Disoccluded => None,
        };
        let decided = |word: &str| {
            let labels: Vec<&str> = measured
                .iter()
                .filter(|m| {
                    m.over_default
                        .as_ref()
                        .and_then(|d| d[i].as_ref())
                        .is_some_and(|r| verdict_word(r) == word)
                })
                .map(|m| m.variation.spec.as_str())
                .collect();
            list(&labels)
        };
        let cleared = match bar {
            None => "no bar".to_string(),
            Some((bar, inclusive)) => {
                let clear: Vec<String> = measured
                    .iter()
                    .filter(|m| {
                        m.over_pt[i]
                            .and_then(|r| r.ci)
                            .is_some_and(|ci| if inclusive { ci.lo >= bar } else { ci.lo > bar })
                    })
                    .map(|m| format!("{} ({})", m.variation.spec, m.variation.label))
                    .collect();
                let clear: Vec<&str> = clear.iter().map(String::as_str).collect();
                let sign = if inclusive { "≥" } else { ">" };
                format!("{sign} {bar}: {}", list(&clear))
            }
        };
        out.push_str(&format!(
            "| {region} | {} | {} | {cleared} |\n",
            decided("better"),
            decided("worse"),
        ));
    }
    out
}

fn list(labels: &[&str]) -> String {
    if labels.is_empty() {
        "none".into()
    } else {
        labels.join(", ")
    }
}

/// `{value, lo, hi}` and, for an efficiency ratio, its verdict.
fn measured_json(m: &Option<Measured>, efficiency: bool) -> Value {
    match m {
        Some(m) => {
            let mut v = json!({
                "value": m.value,
                "lo": m.ci.map(|i| i.lo),
                "hi": m.ci.map(|i| i.hi).filter(|h| h.is_finite()),
            });
            if efficiency {
                v["verdict"] = json!(verdict_word(m));
            }
            v
        }
        None => Value::Null,
    }
}

pub(super) fn row_json(m: &Measurement) -> Value {
    let by_region = |ms: &[Option<Measured>], efficiency: bool| {
        Region::ALL
            .iter()
            .zip(ms)
            .map(|(r, m)| (r.name().to_string(), measured_json(m, efficiency)))
            .collect::<serde_json::Map<_, _>>()
    };
    let v = &m.variation;
    json!({
        "variation": v.label,
        "method": v.spec,
        "camera": v.framing.name(),
        "width": v.resolution.0,
        "height": v.resolution.1,
        "efficiency_over_pt": by_region(&m.over_pt, true),
        "efficiency_over_default": m.over_default.as_deref().map(|d| by_region(d, true)),
        "ms_per_frame": measured_json(&Some(m.milliseconds.0), false),
        "pt_ms_per_frame": measured_json(&m.milliseconds.1, false),
        "mse_over_default": m.mse_over_default.as_ref().map(|(mse, _)| by_region(mse, false)),
        "time_over_default": m.mse_over_default.as_ref().map(|(_, t)| measured_json(t, false)),
        "telemetry": m.telemetry.as_deref().map(telemetry::json),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ablation::{Framing, Variation};
    use lab::uncertainty::Interval;

    fn measured(lo: f64, value: f64, hi: f64) -> Option<Measured> {
        Some(Measured {
            value,
            ci: Some(Interval { lo, hi }),
        })
    }

    /// Issue 10's bar is decided by lower bounds: translucent strictly above 1, penumbra and
    /// shadowed at least 5, lit has none; rows above or below the unmodified preset by their
    /// intervals, an interval containing 1 in neither list.
    #[test]
    fn findings_decide_by_lower_bounds() {
        let row = |spec: &str, over_pt: [Option<Measured>; 5], over_default| Measurement {
            variation: Variation {
                label: spec.into(),
                spec: spec.into(),
                framing: Framing::SCENE,
                resolution: (8, 6),
            },
            over_pt: over_pt.to_vec(),
            over_default,
            milliseconds: (measured(1.0, 1.0, 1.0).unwrap(), None),
            mse_over_default: None,
            telemetry: None,
        };
        let rows = [
            row(
                "a",
                [
                    measured(1.01, 1.2, 1.4),
                    measured(2.0, 3.0, 4.0),
                    measured(5.0, 6.0, 7.0),
                    measured(4.9, 8.0, 12.0),
                    measured(0.2, 0.3, 0.4),
                ],
                Some(vec![
                    measured(1.1, 1.2, 1.3),
                    measured(0.8, 1.0, 1.2),
                    None,
                    None,
                    None,
                ]),
            ),
            row(
                "b",
                [
                    measured(0.9, 1.2, 1.5),
                    None,
                    None,
                    measured(5.0, 6.0, 7.0),
                    None,
                ],
                Some(vec![measured(0.5, 0.6, 0.7), None, None, None, None]),
            ),
        ];
        let text = findings(&rows);
        let line = |region: &str| {
            text.lines()
                .find(|l| l.starts_with(&format!("| {region} |")))
                .unwrap()
                .to_string()
        };
        assert_eq!(line("translucent"), "| translucent | a | b | > 1: a (a) |");
        assert_eq!(line("lit"), "| lit | none | none | no bar |");
        assert_eq!(line("penumbra"), "| penumbra | none | none | ≥ 5: a (a) |");
        assert_eq!(line("shadowed"), "| shadowed | none | none | ≥ 5: b (b) |");
        assert_eq!(
            line("disoccluded"),
            "| disoccluded | none | none | no bar |"
        );
    }
}
