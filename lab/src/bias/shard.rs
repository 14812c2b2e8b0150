//! Shards of a fixed-N bias test (`reshift bias --replicas N --shard i/n`, docs/cluster.md):
//! shard `i` renders the replicas of its seeds ([`crate::shard::seeds`]) and keeps of each what
//! the test needs, its mean per region in linear RGB ([`BiasShard`], schema [`SHARD_SCHEMA`]);
//! shard 0 also keeps the reference batches' region means. [`merge`] puts the means back in
//! seed order and makes the outcome from them as [`super::run`] does, so the merged outcome is
//! that of one run bit for bit, whatever the order of the shards.

use std::path::{Path, PathBuf};

use engine::Backend;
use glam::DVec3;
use methods::Method;
use serde::{Deserialize, Serialize};
use serde_json::Value;

use super::job::{Counts, Setup, outcome, reference, render_replicas};
use super::outcome::{BiasOutcome, NonFinite};
use super::{BiasPlan, Protocol, Replicas, bias_rows, region_means, summaries};
use crate::error::Error;
use crate::progress::Progress;
use crate::reference_cache::REFERENCE_SEED;
use crate::regions::{Region, Regions};
use crate::scenes::{load_scene, with_resolution};
use crate::shard::{CODE_VERSION, Exact, Part, Shard, check_set, seeds};

/// The schema name of a bias shard file.
pub const SHARD_SCHEMA: &str = "reshift-bias-shard/1";

/// Everything that determines a bias test's outcome: shards of different plans do not merge.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ShardPlan {
    /// The version of the code (`reshift --version`).
    pub version: String,
    /// The scene's cache key: its built-in name, or the scene file's stem and text hash.
    pub scene: String,
    pub method: String,
    /// `WxH`.
    pub resolution: String,
    pub frames: u32,
    /// N: the seeds `S..S+N` over all shards.
    pub replicas: u32,
    /// S, the seed of the first replica (absent in shards that predate it: 0).
    #[serde(default)]
    pub first_seed: u64,
    pub delta: Exact,
    pub alpha: Exact,
    pub reference_batches: u32,
    pub reference_batch_spp: u32,
    pub reference_seed: u64,
    /// `cpu` or `vulkan (<device>)`: the backends' images differ in their last bits.
    pub backend: String,
    /// The shard count n.
    pub shards: u32,
    /// The non-empty regions of the tested frame and their pixel counts, in table order.
    pub regions: Vec<(String, usize)>,
}

/// One shard of a bias test as its file holds it.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct BiasShard {
    /// [`SHARD_SCHEMA`].
    pub schema: String,
    /// This shard's index i (its count n is the plan's `shards`).
    pub index: u32,
    pub plan: ShardPlan,
    /// The scene as named when the shard ran (a built-in name or a scene file's path), for the
    /// merge to load its camera; the plan's `scene` checks that it is the same scene.
    pub scene_path: String,
    /// Per replica of the shard's seeds, in seed order.
    pub replicas: Vec<ReplicaMeans>,
    /// Non-finite values of the shard's replicas.
    pub nonfinite: u64,
    /// Shard 0 only: the reference batches' region means.
    pub reference: Option<ReferenceMeans>,
}

/// One replica's (or reference batch's) mean of every region of the plan, in its order.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ReplicaMeans {
    pub seed: u64,
    /// Linear RGB per region.
    pub means: Vec<[Exact; 3]>,
}

/// The reference batches' region means and their non-finite values.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ReferenceMeans {
    /// Batch `b` in `seed`, its index.
    pub batches: Vec<ReplicaMeans>,
    pub nonfinite: u64,
}

impl Part for BiasShard {
    fn plan(&self) -> Value {
        serde_json::to_value(&self.plan).expect("plain data serializes")
    }

    fn shard(&self) -> Shard {
        Shard {
            index: self.index,
            count: self.plan.shards,
        }
    }
}

/// Per image, its region means as the shard file keeps them (the regions of `regions`).
fn image_means(images: &[Vec<DVec3>], regions: &Regions, first: u64) -> Vec<ReplicaMeans> {
    let per_region = region_means(images, regions);
    (0..images.len())
        .map(|k| ReplicaMeans {
            seed: first + k as u64,
            means: per_region
                .iter()
                .map(|(_, _, m)| m[k].to_array().map(Exact))
                .collect(),
        })
        .collect()
}

/// Renders shard `shard` of `plan` (the scene named `scene_path`, cache key `scene_key`): the
/// replicas of its seeds and, for shard 0, the reference. A stop request before the last
/// replica is [`Error::Interrupted`]: a shard is written whole or not at all.
pub fn run_shard(
    plan: &BiasPlan,
    scene_key: &str,
    scene_path: &str,
    shard: Shard,
    progress: &mut dyn Progress,
) -> Result<BiasShard, Error> {
    plan.validate(Path::new("(bias plan)"))?;
    let Replicas::Fixed(replicas) = plan.replicas else {
        return Err(Error::Invalid(
            "a shard needs a fixed number of replicas (--replicas N), not a budget".into(),
        ));
    };
    let setup = Setup::of(plan);
    let regions = &setup.regions;
    let reference = match shard.index {
        0 => {
            let images = reference(plan)?;
            Some(ReferenceMeans {
                batches: image_means(&images.rgb, regions, 0),
                nonfinite: images.nonfinite,
            })
        }
        _ => None,
    };
    let seeds = seeds(shard, replicas, plan.first_seed);
    progress.begin(&plan.method.name(), seeds.end - seeds.start, 0);
    let images = render_replicas(plan, seeds.clone(), progress);
    progress.end();
    let images = images?;
    if (images.rgb.len() as u64) < seeds.end - seeds.start {
        return Err(Error::Interrupted(format!(
            "shard {}/{} interrupted after {} of its {} replicas; nothing written",
            shard.index,
            shard.count,
            images.rgb.len(),
            seeds.end - seeds.start
        )));
    }
    let (width, height) = (plan.scene.camera.width(), plan.scene.camera.height());
    Ok(BiasShard {
        schema: SHARD_SCHEMA.to_string(),
        index: shard.index,
        plan: ShardPlan {
            version: CODE_VERSION.to_string(),
            scene: scene_key.to_string(),
            method: plan.spec.clone(),
            resolution: format!("{width}x{height}"),
            frames: plan.frames,
            replicas,
            first_seed: plan.first_seed,
            delta: Exact(plan.protocol.delta),
            alpha: Exact(plan.protocol.alpha),
            reference_batches: plan.reference_batches,
            reference_batch_spp: plan.reference_batch_spp,
            reference_seed: REFERENCE_SEED,
            backend: plan.backend.to_string(),
            shards: shard.count,
            regions: region_means(&[], regions)
                .into_iter()
                .map(|(r, pixels, _)| (r.name().to_string(), pixels))
                .collect(),
        },
        scene_path: scene_path.to_string(),
        replicas: image_means(&images.rgb, regions, seeds.start),
        nonfinite: images.nonfinite,
        reference,
    })
}

/// The outcome of the whole test from its shards (each with its file, in any order) and the plan
/// it ran, as [`super::run`] would have returned them: after [`check_set`], the replicas' means
/// in seed order and shard 0's reference. Shards whose seeds or region counts are not their
/// plan's are refused with one line naming the file.
pub fn merge(parts: Vec<(PathBuf, BiasShard)>) -> Result<(BiasPlan, BiasOutcome), Error> {
    let parts = check_set(parts)?;
    let (first_path, first) = &parts[0];
    let bad = |path: &Path, what: String| Error::Invalid(format!("{}: {what}", path.display()));
    let p = &first.plan;
    let regions: Vec<(Region, usize)> = p
        .regions
        .iter()
        .map(|(name, pixels)| {
            let region = Region::ALL.into_iter().find(|r| r.name() == name);
            region
                .map(|r| (r, *pixels))
                .ok_or_else(|| bad(first_path, format!("unknown region {name:?}")))
        })
        .collect::<Result<_, _>>()?;
    let well_formed = |path: &Path, list: &[ReplicaMeans], expected: std::ops::Range<u64>| {
        let seeds: Vec<u64> = list.iter().map(|r| r.seed).collect();
        if seeds != expected.clone().collect::<Vec<_>>() {
            return Err(bad(
                path,
                format!(
                    "holds seeds {:?}, its part is {}..{}",
                    seeds, expected.start, expected.end
                ),
            ));
        }
        match list.iter().find(|r| r.means.len() != regions.len()) {
            Some(r) => Err(bad(
                path,
                format!(
                    "seed {} has {} region means, the plan {} regions",
                    r.seed,
                    r.means.len(),
                    regions.len()
                ),
            )),
            None => Ok(()),
        }
    };
    let reference = first
        .reference
        .as_ref()
        .ok_or_else(|| bad(first_path, "shard 0 holds no reference".into()))?;
    well_formed(
        first_path,
        &reference.batches,
        0..p.reference_batches as u64,
    )?;
    for (path, part) in &parts {
        well_formed(
            path,
            &part.replicas,
            seeds(part.shard(), p.replicas, p.first_seed),
        )?;
    }
    let replicas: Vec<&ReplicaMeans> = parts.iter().flat_map(|(_, s)| &s.replicas).collect();
    let summarized = |list: &[&ReplicaMeans]| {
        summaries(
            regions
                .iter()
                .enumerate()
                .map(|(k, &(region, pixels))| {
                    let means = list
                        .iter()
                        .map(|r| DVec3::from_array(r.means[k].map(|x| x.0)))
                        .collect();
                    (region, pixels, means)
                })
                .collect(),
        )
    };
    let plan = rebuilt_plan(first_path, first)?;
    let rows = bias_rows(
        &plan.method.name(),
        &summarized(&replicas),
        &summarized(&reference.batches.iter().collect::<Vec<_>>()),
        &plan.protocol,
    );
    let counts = Counts {
        replicas: replicas.len(),
        reference_batches: plan.reference_batches,
        nonfinite: NonFinite {
            replicas: parts.iter().map(|(_, s)| s.nonfinite).sum(),
            reference: reference.nonfinite,
        },
        interrupted: false,
    };
    let outcome = outcome(&plan, &Setup::of(&plan), counts, rows, None);
    Ok((plan, outcome))
}

/// The [`BiasPlan`] a shard ran: its scene loaded again (and checked to be the same by its
/// cache key) at the plan's resolution, its method parsed. Its backend is the CPU's: a merge
/// renders nothing, and the shards' backend is in their plan.
fn rebuilt_plan(path: &Path, shard: &BiasShard) -> Result<BiasPlan, Error> {
    let p = &shard.plan;
    let loaded = load_scene(&shard.scene_path)?;
    if loaded.key != p.scene {
        return Err(Error::Invalid(format!(
            "{}: field 'scene' is {:?}, but {} is now {:?}: the scene changed since the shards ran",
            path.display(),
            p.scene,
            shard.scene_path,
            loaded.key
        )));
    }
    let resolution = p
        .resolution
        .split_once('x')
        .and_then(|(w, h)| Some((w.parse().ok()?, h.parse().ok()?)))
        .ok_or_else(|| {
            Error::Invalid(format!(
                "{}: field 'resolution' is {:?}, not WxH",
                path.display(),
                p.resolution
            ))
        })?;
    Ok(BiasPlan {
        scene: with_resolution(loaded.scene, Some(resolution)),
        spec: p.method.clone(),
        method: Method::parse(&p.method)?,
        replicas: Replicas::Fixed(p.replicas),
        first_seed: p.first_seed,
        frames: p.frames,
        protocol: Protocol {
            delta: p.delta.0,
            alpha: p.alpha.0,
        },
        reference_batches: p.reference_batches,
        reference_batch_spp: p.reference_batch_spp,
        backend: Backend::Cpu,
        reference: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::progress::Silent;
    use crate::scenes::with_resolution;
    use sss::scene::Scene;

    /// A tiny test: 16×12, 2 frames, 4 replicas, 4 reference batches.
    fn plan(method: &str) -> BiasPlan {
        BiasPlan {
            scene: with_resolution(Scene::builtin("bumpy").unwrap(), Some((16, 12))),
            spec: method.to_string(),
            method: Method::parse(method).unwrap(),
            replicas: Replicas::Fixed(4),
            first_seed: 0,
            frames: 2,
            protocol: Protocol {
                delta: 0.05,
                alpha: 0.01,
            },
            reference_batches: 4,
            reference_batch_spp: 2,
            backend: Backend::Cpu,
            reference: None,
        }
    }

    /// Every shard of `plan` in `count` parts, each through its JSON file text.
    fn shards(plan: &BiasPlan, count: u32) -> Vec<(PathBuf, BiasShard)> {
        (0..count)
            .map(|index| {
                let shard = Shard { index, count };
                let part = run_shard(plan, "bumpy", "bumpy", shard, &mut Silent).unwrap();
                let text = serde_json::to_string(&part).unwrap();
                let path = PathBuf::from(crate::shard::file_name(shard));
                (path, serde_json::from_str(&text).unwrap())
            })
            .collect()
    }

    /// 2 shards in both orders and 3 shards (one of a single replica) merge to the JSON of one
    /// run, bit for bit (every number of the outcome is in it, written shortest-exact).
    #[test]
    fn merged_shards_are_bit_identical_to_one_run() {
        let plan = plan("restir:hybrid");
        let whole = super::super::run(&plan, &mut Silent)
            .unwrap()
            .to_json_pretty();
        let two = shards(&plan, 2);
        let mut reversed = two.clone();
        reversed.reverse();
        for parts in [two, reversed, shards(&plan, 3)] {
            let (merged_plan, outcome) = merge(parts).unwrap();
            assert_eq!(outcome.to_json_pretty(), whole);
            assert_eq!(merged_plan.method, plan.method);
        }
    }

    /// A test from a first seed S: its shards hold seeds S + ⌊i·N/n⌋.., merge into the whole run
    /// bit for bit, and its outcome records S and differs from the test of seeds 0..N. A first
    /// seed whose replicas pass the largest seed is one line naming `--first-seed`.
    #[test]
    fn a_test_from_a_first_seed_shards_and_merges() {
        let seeded = BiasPlan {
            first_seed: 5,
            ..plan("restir:reconnection")
        };
        let whole = super::super::run(&seeded, &mut Silent).unwrap();
        assert_eq!(whole.first_seed, 5);
        let parts = shards(&seeded, 2);
        let held: Vec<Vec<u64>> = (parts.iter())
            .map(|(_, p)| p.replicas.iter().map(|r| r.seed).collect())
            .collect();
        assert_eq!(held, [vec![5, 6], vec![7, 8]]);
        let (merged_plan, merged) = merge(parts).unwrap();
        assert_eq!(merged_plan.first_seed, 5);
        assert_eq!(merged.to_json_pretty(), whole.to_json_pretty());
        let from_zero = super::super::run(&plan("restir:reconnection"), &mut Silent);
        let from_zero = from_zero.unwrap();
        assert_ne!(from_zero.rows, whole.rows);
        let overflowing = BiasPlan {
            first_seed: u64::MAX - 2,
            ..plan("restir:reconnection")
        };
        let line = overflowing
            .validate(Path::new("test"))
            .unwrap_err()
            .to_string();
        assert!(line.contains("--first-seed"), "{line}");
    }

    /// Shards of another method or seed count refuse to merge, naming the field; shard 0 alone
    /// holds the reference.
    #[test]
    fn shards_of_different_plans_refuse_to_merge() {
        let plan = plan("pt");
        let mut parts = shards(&plan, 2);
        assert!(parts[0].1.reference.is_some() && parts[1].1.reference.is_none());
        parts[1].1.plan.method = "restir:hybrid".into();
        let error = merge(parts.clone()).err().unwrap().to_string();
        assert_eq!(
            error,
            "shard-1-of-2.json: field 'method' is \"restir:hybrid\", shard-0-of-2.json has \"pt\""
        );
        parts[1].1.plan.method = "pt".into();
        parts[1].1.plan.replicas = 5;
        let error = merge(parts.clone()).err().unwrap().to_string();
        assert!(
            error.starts_with("shard-1-of-2.json: field 'replicas' is 5"),
            "{error}"
        );
        parts[1].1.plan.replicas = 4;
        parts[1].1.replicas.pop();
        let error = merge(parts).err().unwrap().to_string();
        assert_eq!(
            error,
            "shard-1-of-2.json: holds seeds [2], its part is 2..4"
        );
    }
}
