//! The replica protocol that measures a method's bias per region (DESIGN §3 "Statistics", §7
//! `bias`).
//!
//! * Estimate: N replicas of the method (replica `i` runs with seed `i`, so the replicas draw from
//!   disjoint streams); each replica's final frame is reduced to one scalar per region, the mean
//!   luminance of the region's pixels. Pixels inside a replica are correlated by reuse, so the
//!   replica, not the pixel, is the unit of independence.
//! * Reference: B independent batches of the path tracer at the same frame (same primary hits
//!   x1), reduced the same way; the spread of the batch means is the reference's own standard
//!   error.
//! * Test, per region: [`equivalence`] of the relative bias at confidence `1 − α` with tolerance
//!   δ; across regions, Holm's procedure at family-wise level α on the zero-bias p-values decides
//!   which regions show a significant bias (see [`Protocol`] for the verdict).

use std::fmt::{self, Write as _};

use glam::{DVec3, Vec3};
use rayon::prelude::*;
use restir::stats::{Equivalence, Summary, Verdict, equivalence, holm};
use sss::InputError;
use sss::integrator::pt::{self, PtSettings};
use sss::limits;
use sss::scene::{GBuffer, Scene};

use crate::regions::{Region, Regions};
use engine::{Backend, PipelineError, RunConfig};
use shifts::preset::Preset;

/// Rec. 709 luminance of linear RGB, in `f64` (statistics accumulate in double precision).
pub fn luminance(rgb: Vec3) -> f64 {
    0.2126 * rgb.x as f64 + 0.7152 * rgb.y as f64 + 0.0722 * rgb.z as f64
}

/// Per-pixel luminance images of independent runs, and how many of their values were not
/// finite (the pipeline writes those as 0 and the path tracer leaves them out of its means: a
/// bias either way, which a test must not hide).
#[derive(Clone, Debug, PartialEq)]
pub struct Images {
    pub luminance: Vec<Vec<f64>>,
    pub nonfinite: u64,
}

/// Bytes per pixel one replica keeps until the test: its luminance.
const REPLICA_BYTES_PER_PIXEL: u64 = size_of::<f64>() as u64;
/// Bytes per pixel one reference batch holds: its path-traced image and its luminance.
const BATCH_BYTES_PER_PIXEL: u64 = (size_of::<DVec3>() + size_of::<f64>()) as u64;

/// Bytes a bias test at `pixels` holds: every replica's luminance, every reference batch and one
/// run of `frames` frames (`sss::limits::run_bytes`); `None` on overflow.
pub fn test_bytes(pixels: u64, replicas: u32, batches: u32, frames: u32) -> Option<u64> {
    let kept = (replicas as u64 * REPLICA_BYTES_PER_PIXEL)
        .checked_add(batches as u64 * BATCH_BYTES_PER_PIXEL)?
        .checked_mul(pixels)?;
    kept.checked_add(limits::run_bytes(pixels, frames)?)
}

/// The final frame (`frames − 1`) of replicas `0..replicas` of `preset` on `backend`; replica `i`
/// runs with seed `i`. On the CPU replicas run in parallel; a Vulkan backend runs them one after
/// another on its device. Each is a function of its seed alone.
pub fn replica_images(
    backend: &Backend,
    scene: &Scene,
    preset: &Preset,
    replicas: u64,
    frames: u32,
) -> Result<Images, PipelineError> {
    let replica = |seed| {
        let config = RunConfig {
            seed,
            frames,
            collect_diagnostics: false,
        };
        let mut result = backend.run(scene, preset, &config)?;
        let last = result.frames.pop().ok_or_else(|| {
            PipelineError::Config(format!("run with frames = {frames} returned no frame"))
        })?;
        Ok((
            last.pixels.iter().map(|&p| luminance(p)).collect(),
            result.nan_count,
        ))
    };
    let runs: Vec<(Vec<f64>, u64)> = match backend {
        Backend::Cpu => (0..replicas)
            .into_par_iter()
            .map(replica)
            .collect::<Result<_, PipelineError>>()?,
        Backend::Vulkan(_) => (0..replicas)
            .map(replica)
            .collect::<Result<_, PipelineError>>()?,
    };
    Ok(Images {
        nonfinite: runs.iter().map(|r| r.1).sum(),
        luminance: runs.into_iter().map(|r| r.0).collect(),
    })
}

/// The reference: `batches` independent batches of the path tracer (`sss::integrator::pt`, all
/// hits per probe) at `frame`, `spp_per_batch` samples each; batch `b` is samples
/// `b·spp_per_batch ..` under `seed`, so choose a seed no replica uses. Input errors: fewer than
/// two batches (no standard error), no samples per batch, more than 2³² samples per pixel (the
/// sample index is a `u32`).
pub fn reference_images(
    scene: &Scene,
    frame: u32,
    batches: u32,
    spp_per_batch: u32,
    seed: u64,
) -> Result<Images, InputError> {
    let settings = PtSettings::default();
    reference_images_with(&settings, scene, frame, batches, spp_per_batch, seed)
}

/// [`reference_images`] of the path tracer with `settings`: a method's own reference
/// (`lab::methods::Method::reference`, e.g. the dipole profile of `image-space`).
pub fn reference_images_with(
    settings: &PtSettings,
    scene: &Scene,
    frame: u32,
    batches: u32,
    spp_per_batch: u32,
    seed: u64,
) -> Result<Images, InputError> {
    let bad = |field: &str, value: String, reason: &str| {
        Err(InputError::new("(bias reference)", field, value, reason))
    };
    if batches < 2 {
        return bad(
            "batches",
            batches.to_string(),
            "need ≥ 2 for a standard error",
        );
    }
    if spp_per_batch == 0 {
        return bad("spp_per_batch", "0".into(), "must be ≥ 1");
    }
    if batches as u64 * spp_per_batch as u64 > 1 << 32 {
        let value = format!("{batches} × {spp_per_batch}");
        return bad(
            "batches",
            value,
            "batches × spp_per_batch must not exceed 2³² samples per pixel",
        );
    }
    let gbuffer = GBuffer::render(scene, frame);
    let images: Vec<pt::Image> = (0..batches)
        .map(|b| {
            pt::render(
                scene,
                &gbuffer,
                settings,
                seed,
                b * spp_per_batch,
                spp_per_batch,
            )
        })
        .collect();
    Ok(Images {
        nonfinite: images.iter().map(|i| i.nonfinite).sum(),
        luminance: images
            .iter()
            .map(|i| i.pixels.iter().map(|p| luminance(p.as_vec3())).collect())
            .collect(),
    })
}

/// Mean of `values` over the pixels of `region`; `None` when the region is empty or `values`
/// does not cover the classified image.
pub fn region_mean(values: &[f64], regions: &Regions, region: Region) -> Option<f64> {
    if values.len() != regions.len() {
        return None;
    }
    let pixels = regions.pixels(region);
    if pixels.is_empty() {
        return None;
    }
    Some(pixels.iter().map(|&p| values[p]).sum::<f64>() / pixels.len() as f64)
}

/// One region's replica summary.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RegionSummary {
    pub region: Region,
    pub pixels: usize,
    /// Over independent images (replicas or reference batches) of the region's mean luminance.
    pub summary: Summary,
}

/// Per-region summaries of independent per-pixel luminance images (one `Vec` per replica or
/// batch, row-major like `regions`); empty regions are left out. An image of the wrong size
/// counts as a NaN replica, which the tests reject as a defect.
pub fn summarize(images: &[Vec<f64>], regions: &Regions) -> Vec<RegionSummary> {
    Region::ALL
        .into_iter()
        .filter_map(|region| {
            let pixels = regions.count(region);
            (pixels > 0).then(|| {
                let means: Vec<f64> = images
                    .iter()
                    .map(|image| region_mean(image, regions, region).unwrap_or(f64::NAN))
                    .collect();
                RegionSummary {
                    region,
                    pixels,
                    summary: Summary::from_samples(&means),
                }
            })
        })
        .collect()
}

/// Tolerance and level of the bias test.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Protocol {
    /// Tolerance δ on the relative bias of a region mean.
    pub delta: f64,
    /// Each region's CI has confidence `1 − alpha`; Holm controls the family-wise rate of false
    /// "biased" findings across regions at `alpha`.
    pub alpha: f64,
}

impl Protocol {
    /// A region's verdict: `Unbiased` ⇔ its `1 − α` CI lies inside ±δ; otherwise `Biased` if
    /// the CI lies outside [−δ, δ] or Holm rejects zero bias, `Inconclusive` if neither.
    fn verdict(&self, e: &Equivalence, holm_rejected: bool) -> Verdict {
        if e.ci_low > -self.delta && e.ci_high < self.delta {
            Verdict::Unbiased
        } else if e.ci_low >= self.delta || e.ci_high <= -self.delta || holm_rejected {
            Verdict::Biased
        } else {
            Verdict::Inconclusive
        }
    }
}

/// One row of a bias table: a method in one region.
#[derive(Clone, Debug, PartialEq)]
pub struct BiasRow {
    pub method: String,
    pub region: Region,
    pub pixels: usize,
    pub estimate: Summary,
    pub reference: Summary,
    pub equivalence: Equivalence,
    /// Whether Holm's procedure across the method's regions rejects zero bias here.
    pub holm_rejected: bool,
    pub verdict: Verdict,
}

impl BiasRow {
    /// Half-width of the CI of the relative bias.
    pub fn ci_half_width(&self) -> f64 {
        0.5 * (self.equivalence.ci_high - self.equivalence.ci_low)
    }
}

/// The bias table rows of `method`: its replicas' per-region summaries against the reference's,
/// for every region both have.
pub fn bias_rows(
    method: &str,
    replicas: &[RegionSummary],
    reference: &[RegionSummary],
    protocol: &Protocol,
) -> Vec<BiasRow> {
    let pairs: Vec<(&RegionSummary, &RegionSummary)> = replicas
        .iter()
        .filter_map(|e| {
            let r = reference.iter().find(|r| r.region == e.region)?;
            Some((e, r))
        })
        .collect();
    let tests: Vec<Equivalence> = pairs
        .iter()
        .map(|(e, r)| equivalence(&e.summary, &r.summary, protocol.delta, 1.0 - protocol.alpha))
        .collect();
    let p_values: Vec<f64> = tests.iter().map(|t| t.p_zero_bias).collect();
    let rejected = holm(&p_values, protocol.alpha);
    pairs
        .iter()
        .zip(tests)
        .zip(rejected)
        .map(|(((e, r), test), holm_rejected)| BiasRow {
            method: method.to_string(),
            region: e.region,
            pixels: e.pixels,
            estimate: e.summary,
            reference: r.summary,
            verdict: protocol.verdict(&test, holm_rejected),
            equivalence: test,
            holm_rejected,
        })
        .collect()
}

/// The rows as a Markdown table (relative bias and CI in percent).
pub struct Table<'a>(pub &'a [BiasRow]);

impl fmt::Display for Table<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "| method | region | pixels | N | mean | reference ± s.e. | bias | CI | ±half | δ | p(bias=0) | Holm | verdict |"
        )?;
        writeln!(
            f,
            "|---|---|---:|---:|---:|---:|---:|---|---:|---:|---:|---|---|"
        )?;
        for row in self.0 {
            let e = &row.equivalence;
            let mut line = String::new();
            write!(
                line,
                "| {} | {} | {} | {} | {:.5} | {:.5} ± {:.5} | {:+.2}% | [{:+.2}%, {:+.2}%] | {:.2}% | {}% | {:.2e} | {} | {} |",
                row.method,
                row.region,
                row.pixels,
                e.n,
                row.estimate.mean,
                row.reference.mean,
                row.reference.std_err,
                100.0 * e.relative_bias,
                100.0 * e.ci_low,
                100.0 * e.ci_high,
                100.0 * row.ci_half_width(),
                100.0 * e.delta,
                e.p_zero_bias,
                if row.holm_rejected { "reject" } else { "-" },
                verdict_word(row.verdict),
            )?;
            writeln!(f, "{line}")?;
        }
        Ok(())
    }
}

fn verdict_word(v: Verdict) -> &'static str {
    match v {
        Verdict::Unbiased => "unbiased",
        Verdict::Biased => "BIASED",
        Verdict::Inconclusive => "inconclusive",
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::regions::VISIBILITY_SAMPLES;
    use restir::rng::{Stream, StreamKey};

    const PROTOCOL: Protocol = Protocol {
        delta: 0.03,
        alpha: 0.01,
    };

    /// Each replica adds its luminance, each batch its image and luminance; sizes past `u64`
    /// are `None`, not a wrapped small number.
    #[test]
    fn test_bytes_counts_replicas_batches_and_the_run() {
        let pixels = 64 * 48;
        let base = test_bytes(pixels, 2, 2, 16).unwrap();
        assert_eq!(test_bytes(pixels, 3, 2, 16), Some(base + pixels * 8));
        assert_eq!(test_bytes(pixels, 2, 3, 16), Some(base + pixels * 32));
        assert_eq!(
            test_bytes(pixels, 2, 2, 17),
            Some(base + pixels * limits::IMAGE_BYTES_PER_PIXEL)
        );
        assert_eq!(test_bytes(u64::MAX / 4, 2, 2, 1), None);
    }

    /// 12 × 10 pixels: a row of non-translucent pixels, then lit, penumbra and shadowed bands.
    fn regions() -> Regions {
        let (w, h) = (12, 10);
        let visible = (0..w * h)
            .map(|p| match p / w {
                0 => None,
                1..=3 => Some(VISIBILITY_SAMPLES),
                4..=6 => Some(VISIBILITY_SAMPLES / 2),
                _ => Some(0),
            })
            .collect();
        Regions::from_visible_samples(w, h, visible).expect("consistent")
    }

    /// The true radiance of pixel `p`: 1 lit, 0.5 penumbra, 0.1 shadowed, 3 elsewhere.
    fn truth(regions: &Regions, p: usize) -> f64 {
        match regions.visible_samples(p) {
            None => 3.0,
            Some(0) => 0.1,
            Some(VISIBILITY_SAMPLES) => 1.0,
            Some(_) => 0.5,
        }
    }

    /// An image of `truth · (1 + shadow_bias·1[shadowed]) · (1 + common·g + 0.1·u)`, with `g`
    /// one standard normal per image (pixels correlated by reuse) and `u` one per pixel.
    fn image(regions: &Regions, s: &mut Stream, common: f64, shadow_bias: f64) -> Vec<f64> {
        let common = common * normal(s);
        (0..regions.len())
            .map(|p| {
                let bias = if regions.contains(Region::Shadowed, p) {
                    shadow_bias
                } else {
                    0.0
                };
                truth(regions, p) * (1.0 + bias) * (1.0 + common + 0.1 * normal(s))
            })
            .collect()
    }

    fn normal(s: &mut Stream) -> f64 {
        let radius = (-2.0 * (1.0 - s.next_f64()).ln()).sqrt();
        radius * (std::f64::consts::TAU * s.next_f64()).cos()
    }

    /// `n` replicas (3% common factor) or, with `reference`, `n` independent batches.
    fn images(
        regions: &Regions,
        seed: u64,
        n: usize,
        reference: bool,
        shadow_bias: f64,
    ) -> Vec<Vec<f64>> {
        let mut s = StreamKey::new(0, 0, 0xB1A5, 0).stream(seed);
        let common = if reference { 0.0 } else { 0.03 };
        (0..n)
            .map(|_| image(regions, &mut s, common, shadow_bias))
            .collect()
    }

    #[test]
    fn region_means_skip_outside_pixels() {
        let regions = regions();
        let exact: Vec<f64> = (0..regions.len()).map(|p| truth(&regions, p)).collect();
        let mean = |r| region_mean(&exact, &regions, r).expect("non-empty");
        assert_eq!(mean(Region::Lit), 1.0);
        assert!((mean(Region::Shadowed) - 0.1).abs() < 1e-15);
        assert!((mean(Region::Translucent) - (36.0 + 18.0 + 0.1 * 36.0) / 108.0).abs() < 1e-12);
        assert_eq!(region_mean(&exact[1..], &regions, Region::Lit), None);
        let nothing = Regions::from_visible_samples(2, 1, vec![None, None]).expect("consistent");
        assert_eq!(
            region_mean(&[1.0, 2.0], &nothing, Region::Translucent),
            None
        );
        assert!(summarize(&[vec![1.0, 2.0]], &nothing).is_empty());
        assert!(Regions::from_visible_samples(2, 1, vec![None]).is_none());
    }

    /// δ = 3%, α = 0.01 (99% CIs, Holm across the 4 regions), N = 64 replicas (3% common
    /// factor per image, so s.e. ≈ 0.45% per region) against B = 64 reference batches (s.e. ≈
    /// 0.2%): an unbiased estimator is Unbiased in every region; the negative control, +10% in
    /// the shadowed band only, is Biased there and still Unbiased in lit and penumbra.
    #[test]
    fn unbiased_passes_and_shadow_bias_is_detected() {
        let regions = regions();
        let reference = summarize(&images(&regions, 1, 64, true, 0.0), &regions);
        let good = bias_rows(
            "good",
            &summarize(&images(&regions, 2, 64, false, 0.0), &regions),
            &reference,
            &PROTOCOL,
        );
        assert_eq!(good.len(), 4);
        for row in &good {
            assert_eq!(row.verdict, Verdict::Unbiased, "{}", Table(&good));
        }
        let bad = bias_rows(
            "shadow +10%",
            &summarize(&images(&regions, 3, 64, false, 0.10), &regions),
            &reference,
            &PROTOCOL,
        );
        let shadowed = bad
            .iter()
            .find(|r| r.region == Region::Shadowed)
            .expect("row");
        assert_eq!(shadowed.verdict, Verdict::Biased, "{}", Table(&bad));
        assert!(shadowed.holm_rejected, "{}", Table(&bad));
        for row in bad
            .iter()
            .filter(|r| matches!(r.region, Region::Lit | Region::Penumbra))
        {
            assert_eq!(row.verdict, Verdict::Unbiased, "{}", Table(&bad));
        }
        let table = Table(&bad).to_string();
        assert_eq!(table.lines().count(), 2 + 4, "{table}");
        assert!(
            table.contains("| shadow +10% | shadowed | 36 | 64 |"),
            "{table}"
        );
    }

    #[test]
    fn reference_settings_are_validated() {
        let scene = Scene::builtin("half-shadow").expect("built-in");
        let field = |b, k| {
            reference_images(&scene, 0, b, k, 1)
                .map(|_| ())
                .unwrap_err()
                .field
        };
        assert_eq!(field(1, 4), "batches");
        assert_eq!(field(2, 0), "spp_per_batch");
        assert_eq!(field(1 << 16, 1 << 17), "batches");
    }

    /// Holm, not the per-region level, decides "Biased": a p-value of 0.008 is significant at
    /// α = 0.01 alone; when Holm does not reject it, a CI that overlaps ±δ is Inconclusive.
    #[test]
    fn holm_guards_against_false_findings() {
        let e = Equivalence {
            n: 10,
            relative_bias: 0.015,
            ci_low: 0.001,
            ci_high: 0.039,
            delta: 0.03,
            confidence: 0.99,
            p_zero_bias: 0.008,
            verdict: Verdict::Biased,
        };
        assert_eq!(PROTOCOL.verdict(&e, false), Verdict::Inconclusive);
        assert_eq!(PROTOCOL.verdict(&e, true), Verdict::Biased);
        let outside = Equivalence { ci_low: 0.031, ..e };
        assert_eq!(PROTOCOL.verdict(&outside, false), Verdict::Biased);
        let inside = Equivalence {
            ci_high: 0.029,
            ..e
        };
        assert_eq!(PROTOCOL.verdict(&inside, true), Verdict::Unbiased);
    }
}
