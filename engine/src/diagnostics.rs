//! Diagnostic images of a run (paper 001 Fig. 4, 5, 10): which shift the hybrid criterion picks,
//! the fraction of shifted samples that beat the canonical one, shift-failure rates per pass,
//! and intersections per probe. Counters are summed over all frames; the reuse [`Telemetry`]
//! records the last frame.

mod telemetry;

pub(crate) use telemetry::Recorder;
pub use telemetry::{FAIL_KINDS, PassTelemetry, Telemetry};

use glam::Vec3;

use crate::candidates::ProbeCounts;
use crate::image::Image;
use crate::reuse::ShiftCounts;

/// The hybrid criterion [001 §4.1] applied to a pixel's canonical sample.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum HybridChoice {
    /// No canonical sample (or x1 not translucent).
    #[default]
    None,
    Reconnection,
    Delayed,
}

/// Per-pixel counters summed over frames.
#[derive(Clone, Debug)]
pub(crate) struct Counters {
    width: u32,
    height: u32,
    /// Frames whose canonical sample the criterion sends to reconnection / to delayed.
    hybrid: Vec<[u32; 2]>,
    probes: Vec<ProbeCounts>,
    /// One buffer per reuse pass, with the pass's label.
    passes: Vec<(String, Vec<ShiftCounts>)>,
}

impl Counters {
    pub(crate) fn new(width: u32, height: u32, pass_labels: Vec<String>) -> Counters {
        let n = width as usize * height as usize;
        Counters {
            width,
            height,
            hybrid: vec![[0; 2]; n],
            probes: vec![ProbeCounts::default(); n],
            passes: pass_labels
                .into_iter()
                .map(|l| (l, vec![ShiftCounts::default(); n]))
                .collect(),
        }
    }

    pub(crate) fn add_candidates(&mut self, per_pixel: &[(ProbeCounts, HybridChoice)]) {
        for ((probes, hybrid), (p, h)) in
            self.probes.iter_mut().zip(&mut self.hybrid).zip(per_pixel)
        {
            probes.probes += p.probes;
            probes.hits += p.hits;
            match h {
                HybridChoice::Reconnection => hybrid[0] += 1,
                HybridChoice::Delayed => hybrid[1] += 1,
                HybridChoice::None => {}
            }
        }
    }

    /// Adds the counts of reuse pass number `reuse_pass` (0 = the first pass after candidates).
    pub(crate) fn add_shifts(&mut self, reuse_pass: usize, per_pixel: &[ShiftCounts]) {
        for (acc, c) in self.passes[reuse_pass].1.iter_mut().zip(per_pixel) {
            acc.shifted += c.shifted;
            acc.failed += c.failed;
            acc.improved += c.improved;
        }
    }

    pub(crate) fn finish(&self) -> Diagnostics {
        let image = |value: &dyn Fn(usize) -> Vec3| Image {
            width: self.width,
            height: self.height,
            pixels: (0..self.hybrid.len()).map(value).collect(),
        };
        let ratio = |num: u64, den: u64| {
            if den > 0 {
                num as f64 / den as f64
            } else {
                0.0
            }
        };
        let hybrid_choice = image(&|i| {
            let [rec, del] = self.hybrid[i];
            let n = rec + del;
            if n == 0 {
                return Vec3::ZERO;
            }
            let blue = Vec3::new(0.0, 0.0, 1.0);
            let yellow = Vec3::new(1.0, 1.0, 0.0);
            yellow.lerp(blue, rec as f32 / n as f32)
        });
        let hits_per_probe = image(&|i| {
            let p = self.probes[i];
            Vec3::splat(ratio(p.hits as u64, p.probes as u64) as f32)
        });
        let total_probes = self.probes.iter().map(|p| p.probes as u64).sum();
        let total_hits = self.probes.iter().map(|p| p.hits as u64).sum();
        let improved_fraction = image(&|i| {
            let (improved, succeeded) = self.passes.iter().fold((0u64, 0u64), |(a, b), (_, c)| {
                let c = c[i];
                (a + c.improved as u64, b + (c.shifted - c.failed) as u64)
            });
            Vec3::splat(ratio(improved, succeeded) as f32)
        });
        let failures = self
            .passes
            .iter()
            .map(|(label, counts)| {
                let shifted: u64 = counts.iter().map(|c| c.shifted as u64).sum();
                let failed: u64 = counts.iter().map(|c| c.failed as u64).sum();
                PassFailures {
                    label: label.clone(),
                    rate: ratio(failed, shifted),
                    shifted,
                    image: image(&|i| {
                        Vec3::splat(ratio(counts[i].failed as u64, counts[i].shifted as u64) as f32)
                    }),
                }
            })
            .collect();
        Diagnostics {
            hybrid_choice,
            improved_fraction,
            failures,
            hits_per_probe,
            mean_hits_per_probe: ratio(total_hits, total_probes),
            probes: total_probes,
            telemetry: None,
        }
    }
}

/// The shift-failure rate of one reuse pass.
#[derive(Clone, Debug, PartialEq)]
pub struct PassFailures {
    /// [`crate::PassSpec::label`] of the pass.
    pub label: String,
    /// Failed shifts / shifted neighbour samples, over all pixels and frames.
    pub rate: f64,
    /// Neighbour samples shifted in this pass, over all pixels and frames.
    pub shifted: u64,
    /// Per-pixel failure rate (grey).
    pub image: Image,
}

/// Diagnostics of a run, summed over its frames.
#[derive(Clone, Debug, PartialEq)]
pub struct Diagnostics {
    /// Which shift the hybrid criterion picks for each pixel's canonical sample [001 Fig. 4]:
    /// blue = reconnection, yellow = delayed, blended by the fraction of frames; black = none.
    pub hybrid_choice: Image,
    /// Fraction of successfully shifted neighbour samples `T(x_i)` whose target in the receiver
    /// exceeds the canonical sample's, `p̂(T(x_i)) > p̂(x)`, over all reuse passes [001 Fig. 5, 10].
    pub improved_fraction: Image,
    /// Shift-failure rates per reuse pass.
    pub failures: Vec<PassFailures>,
    /// Probe hits per BSSRDF sample (grey), and its mean over the image.
    pub hits_per_probe: Image,
    pub mean_hits_per_probe: f64,
    /// BSSRDF samples (probes) traced, over all pixels and frames.
    pub probes: u64,
    /// The reuse telemetry of the last frame (CPU backend; `None` on the Vulkan backend).
    pub telemetry: Option<Telemetry>,
}

impl Diagnostics {
    /// Every diagnostic image with a file-name stem: `hybrid-choice`, `improved-fraction`,
    /// `hits-per-probe`, and `failures-<pass>` per reuse pass (`:` in labels becomes `-`).
    pub fn images(&self) -> Vec<(String, &Image)> {
        let mut images = vec![
            ("hybrid-choice".to_string(), &self.hybrid_choice),
            ("improved-fraction".to_string(), &self.improved_fraction),
            ("hits-per-probe".to_string(), &self.hits_per_probe),
        ];
        for (i, f) in self.failures.iter().enumerate() {
            let label = f.label.replace(':', "-");
            images.push((format!("failures-{}-{label}", i + 1), &f.image));
        }
        images
    }
}
