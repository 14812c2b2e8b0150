//! A ReSTIR-shaped chain over a small image of toy pixels: candidates → temporal-like reuse
//! (2 domains, confidence cap) → two spatial-like passes (k neighbours), ping-pong buffers,
//! rayon over pixels. Every random number comes from `StreamKey { pixel, frame, pass, purpose }`.

use rayon::prelude::*;

use super::{LinearSampler, Point, Supports, ToyPixel};
use crate::mis::{Gbh, MAX_DOMAINS, MisScheme};
use crate::resample::{ResampleError, Source, generate_candidates, resample};
use crate::reservoir::{Reservoir, cap_confidence};
use crate::rng::StreamKey;
use crate::shift::Shift;

/// Pass numbers of the stream keys.
const PASS_CANDIDATES: u32 = 0;
const PASS_TEMPORAL: u32 = 1;
const PASS_SPATIAL: [u32; 2] = [2, 3];
/// Purpose numbers of the stream keys.
const PURPOSE_SAMPLE: u32 = 0;
const PURPOSE_NEIGHBOURS: u32 = 1;

/// Shape of the chain.
#[derive(Clone, Copy, Debug)]
pub struct ChainConfig {
    pub width: u32,
    pub height: u32,
    /// Frames run in sequence; each frame's final reservoirs feed the next frame's temporal pass.
    pub frames: u32,
    /// Fresh candidates per pixel and frame (confidence `M` each).
    pub candidates: u32,
    /// Neighbours per spatial pass (at most `MAX_DOMAINS − 1`).
    pub neighbours: usize,
    /// Neighbours are drawn from the `(2r+1)²` window around the pixel, clamped to the image.
    pub radius: i32,
    /// Temporal confidence cap (20 in [001 §5]).
    pub temporal_cap: f32,
    pub supports: Supports,
}

impl Default for ChainConfig {
    fn default() -> Self {
        Self {
            width: 6,
            height: 6,
            frames: 3,
            candidates: 2,
            neighbours: 3,
            radius: 2,
            temporal_cap: 20.0,
            supports: Supports::Equal,
        }
    }
}

/// The toy pixels of every frame of a chain.
pub struct ToyScene {
    pub config: ChainConfig,
    /// `frames[f][pixel]`.
    pub frames: Vec<Vec<ToyPixel>>,
}

impl ToyScene {
    pub fn new(config: ChainConfig) -> Self {
        let count = config.width * config.height;
        let frames = (0..config.frames)
            .map(|f| {
                (0..count)
                    .map(|p| ToyPixel::new(p, f, count, config.supports))
                    .collect()
            })
            .collect();
        Self { config, frames }
    }

    pub fn pixel_count(&self) -> usize {
        (self.config.width * self.config.height) as usize
    }

    /// The domains of the last frame, whose integrals the chain estimates.
    pub fn last_frame(&self) -> &[ToyPixel] {
        self.frames.last().map_or(&[], Vec::as_slice)
    }

    /// Up to `k` distinct in-image neighbours of `pixel` (never itself), drawn uniformly from
    /// the window; the rejection depends on pixel positions only, never on samples.
    fn neighbours(
        &self,
        pixel: u32,
        frame: u32,
        pass: u32,
        seed: u64,
    ) -> ([u32; MAX_DOMAINS], usize) {
        let (w, h, r) = (
            self.config.width as i32,
            self.config.height as i32,
            self.config.radius,
        );
        let k = self.config.neighbours.min(MAX_DOMAINS - 1);
        let mut rng = StreamKey::new(pixel, frame, pass, PURPOSE_NEIGHBOURS).stream(seed);
        let mut chosen = [0u32; MAX_DOMAINS];
        let mut taken = 0;
        let side = (2 * r + 1) as f32;
        for _ in 0..4 * k {
            if taken == k {
                break;
            }
            let dx = (rng.next_f32() * side) as i32 - r;
            let dy = (rng.next_f32() * side) as i32 - r;
            let (x, y) = (pixel as i32 % w + dx, pixel as i32 / w + dy);
            if (dx, dy) == (0, 0) || x < 0 || y < 0 || x >= w || y >= h {
                continue;
            }
            let q = (y * w + x) as u32;
            if !chosen[..taken].contains(&q) {
                chosen[taken] = q;
                taken += 1;
            }
        }
        (chosen, taken)
    }
}

/// Runs every frame of the chain for one replica (`seed`) and returns the last frame's
/// reservoirs. Temporal reuse uses GBH [001 §5]; the spatial passes use `spatial_mis`.
pub fn run_chain(
    scene: &ToyScene,
    shift: &dyn Shift<ToyPixel>,
    spatial_mis: &dyn MisScheme,
    seed: u64,
) -> Result<Vec<Reservoir<Point>>, ResampleError> {
    let count = scene.pixel_count();
    let cfg = scene.config;
    let mut current = vec![Reservoir::empty(); count];
    let mut scratch = vec![Reservoir::empty(); count];
    let mut previous: Vec<Reservoir<Point>> = Vec::new();
    for (f, domains) in scene.frames.iter().enumerate() {
        let frame = f as u32;
        current
            .par_iter_mut()
            .enumerate()
            .try_for_each(|(p, out)| {
                let key = StreamKey::new(p as u32, frame, PASS_CANDIDATES, PURPOSE_SAMPLE);
                *out = generate_candidates(
                    &domains[p],
                    &LinearSampler,
                    cfg.candidates,
                    &mut key.stream(seed),
                )?;
                Ok::<_, ResampleError>(())
            })?;
        if f > 0 {
            let previous_domains = &scene.frames[f - 1];
            scratch
                .par_iter_mut()
                .enumerate()
                .try_for_each(|(p, out)| {
                    let mut prev = previous[p];
                    prev.confidence =
                        cap_confidence(prev.confidence, current[p].confidence, cfg.temporal_cap);
                    let receiver = Source {
                        domain: &domains[p],
                        reservoir: &current[p],
                    };
                    let temporal = [Source {
                        domain: &previous_domains[p],
                        reservoir: &prev,
                    }];
                    let key = StreamKey::new(p as u32, frame, PASS_TEMPORAL, PURPOSE_SAMPLE);
                    *out = resample(receiver, &temporal, shift, &Gbh, &mut key.stream(seed))?;
                    Ok::<_, ResampleError>(())
                })?;
            std::mem::swap(&mut current, &mut scratch);
        }
        for pass in PASS_SPATIAL {
            scratch
                .par_iter_mut()
                .enumerate()
                .try_for_each(|(p, out)| {
                    let (ids, taken) = scene.neighbours(p as u32, frame, pass, seed);
                    let neighbours: Vec<Source<'_, ToyPixel>> = ids[..taken]
                        .iter()
                        .map(|&q| Source {
                            domain: &domains[q as usize],
                            reservoir: &current[q as usize],
                        })
                        .collect();
                    let receiver = Source {
                        domain: &domains[p],
                        reservoir: &current[p],
                    };
                    let key = StreamKey::new(p as u32, frame, pass, PURPOSE_SAMPLE);
                    *out = resample(
                        receiver,
                        &neighbours,
                        shift,
                        spatial_mis,
                        &mut key.stream(seed),
                    )?;
                    Ok::<_, ResampleError>(())
                })?;
            std::mem::swap(&mut current, &mut scratch);
        }
        previous.clone_from(&current);
    }
    Ok(current)
}

/// Per-replica observations of independent chain runs (replica `i` uses seed `base_seed + i`).
pub struct ReplicaOutputs {
    /// `estimates[replica][pixel]` = `f(Y)·W` of the last frame.
    pub estimates: Vec<Vec<f64>>,
    /// `ucw_cells[replica][pixel · bins² + bin]` = `1_B(Y)·W` on a `bins × bins` grid of the
    /// pixel's support box (so every cell has mass).
    pub ucw_cells: Vec<Vec<f64>>,
    pub bins: usize,
}

/// The cell of `x` on a `bins × bins` grid of the support box `[0, hi₀] × [0, hi₁]`.
pub fn cell_of(x: &Point, support_hi: [f32; 2], bins: usize) -> usize {
    let index = |d: usize| ((x[d] / support_hi[d] * bins as f32) as usize).min(bins - 1);
    index(1) * bins + index(0)
}

/// Runs `replicas` independent chains in parallel.
pub fn run_replicas(
    scene: &ToyScene,
    shift: &dyn Shift<ToyPixel>,
    spatial_mis: &dyn MisScheme,
    replicas: usize,
    base_seed: u64,
    bins: usize,
) -> Result<ReplicaOutputs, ResampleError> {
    let domains = scene.last_frame();
    let runs: Vec<(Vec<f64>, Vec<f64>)> = (0..replicas)
        .into_par_iter()
        .map(|i| {
            let finals = run_chain(scene, shift, spatial_mis, base_seed + i as u64)?;
            let mut cells = vec![0.0f64; finals.len() * bins * bins];
            let estimates = finals
                .iter()
                .zip(domains)
                .enumerate()
                .map(|(p, (r, d))| match r.y {
                    Some(y) => {
                        cells[p * bins * bins + cell_of(&y, d.support_hi, bins)] = r.ucw as f64;
                        d.integrand(&y) as f64 * r.ucw as f64
                    }
                    None => 0.0,
                })
                .collect();
            Ok((estimates, cells))
        })
        .collect::<Result<_, ResampleError>>()?;
    let (estimates, ucw_cells) = runs.into_iter().unzip();
    Ok(ReplicaOutputs {
        estimates,
        ucw_cells,
        bins,
    })
}

/// `|B ∩ supp p̂|` for every cell of [`ReplicaOutputs::ucw_cells`].
pub fn ucw_expected(scene: &ToyScene, bins: usize) -> Vec<f64> {
    scene
        .last_frame()
        .iter()
        .flat_map(|d| {
            let [h0, h1] = d.support_hi.map(|s| s as f64 / bins as f64);
            (0..bins * bins).map(move |b| {
                let lo = [(b % bins) as f64 * h0, (b / bins) as f64 * h1];
                d.support_overlap(lo, [lo[0] + h0, lo[1] + h1])
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mis::DefensivePairwise;
    use crate::toy::shifts::Scaling;

    /// The same seed gives bit-identical reservoirs with 1 and 2 rayon threads.
    #[test]
    fn chain_is_bit_identical_across_thread_counts() {
        let scene = ToyScene::new(ChainConfig::default());
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| run_chain(&scene, &Scaling, &DefensivePairwise, 99))
                .unwrap()
        };
        let bits = |rs: Vec<Reservoir<Point>>| -> Vec<[u32; 4]> {
            rs.iter()
                .map(|r| {
                    let y = r.y.unwrap_or([f32::NAN; 2]);
                    [
                        y[0].to_bits(),
                        y[1].to_bits(),
                        r.ucw.to_bits(),
                        r.confidence.to_bits(),
                    ]
                })
                .collect()
        };
        let one = bits(run(1));
        assert_eq!(one, bits(run(2)));
        assert!(
            one.iter().any(|b| f32::from_bits(b[2]) > 0.0),
            "chain selected nothing"
        );
        let other_seed = run_chain(&scene, &Scaling, &DefensivePairwise, 100).unwrap();
        assert_ne!(one, bits(other_seed), "the seed has no effect");
    }

    /// With the cap, no confidence exceeds `(cap + 1)·M·(k + 1)²` (candidates + capped temporal,
    /// then two spatial passes). Negative control: without the cap (∞) some pixel exceeds it.
    #[test]
    fn temporal_cap_bounds_confidence() {
        let cfg = ChainConfig::default();
        let bound = (cfg.temporal_cap + 1.0)
            * cfg.candidates as f32
            * ((cfg.neighbours + 1) as f32).powi(2);
        let max_confidence = |cap: f32| {
            let scene = ToyScene::new(ChainConfig {
                temporal_cap: cap,
                ..cfg
            });
            let finals = run_chain(&scene, &Scaling, &DefensivePairwise, 5).unwrap();
            for r in &finals {
                assert!(r.ucw.is_finite() && r.ucw >= 0.0 && r.confidence.is_finite());
            }
            finals.iter().map(|r| r.confidence).fold(0.0, f32::max)
        };
        let capped = max_confidence(cfg.temporal_cap);
        assert!(capped <= bound, "max confidence {capped} > {bound}");
        let uncapped = max_confidence(f32::INFINITY);
        assert!(
            uncapped > bound,
            "negative control: uncapped max {uncapped} ≤ {bound}"
        );
    }
}
