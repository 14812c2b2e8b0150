//! The default bias test: the group-sequential design of `sequential` planned and run within a
//! time budget ([`run`], `reshift bias` without `--replicas`).
//!
//! 1. Reference: `plan.reference_batches` batches, timed.
//! 2. Pilot: [`PILOT`] replicas (the first `PILOT` seeds, part of the sample), timed; per row the
//!    per-replica CV and the reference's relative standard error `ρ`.
//! 3. Plan, per row: the reference batches `B` that bring the reference's share of the CI,
//!    `z_{1−α/2}·ρ`, down to δ/4 (`ρ ∝ 1/√B`), and the replicas `N` that make the row equivalent
//!    with probability [`PLANNED_POWER`] if it had no bias, at the level of the design's last
//!    look ([`replicas_for`], CV × [`CV_MARGIN`]). Rows are **planned for** cheapest first
//!    while the planned rows' `N_max` (for all of them together) and largest `B` fit the budget
//!    left.
//! 4. The reference grows to the planned rows' largest `B`; the looks of `sequential` follow at
//!    `N_max/4, …, N_max`, testing every row (a row not planned for may still be decided) and
//!    ending once every planned row is decided. Before each look, its replicas are rendered
//!    only if the measured seconds per replica say they fit in the budget; otherwise the looks
//!    end. Every row left undecided reports what a test of it alone would need.
//!
//! The budget and every time count the backend's clock (`engine::clock`: process CPU time on
//! the CPU backend). Given the plan (the planned rows, `B`, `N_max`), the outcome is a function
//! of the seeds; the plan itself depends on measured times, so a budget near a row's cost may
//! judge it on one run and not on the next.

use std::time::Duration;

use engine::clock::{Clock, Stopwatch};
use glam::DVec3;
use restir::stats::{
    EquivalencePlan, Summary, Verdict, equivalence, normal_quantile, replicas_for,
};

use super::job::{Counts, Setup, chunk, outcome, render_chunk};
use super::outcome::{
    BiasOutcome, LookEntry, Needs, NonFinite, PLANNED_POWER, RowDesign, SequentialEntry,
};
use super::plan::BiasPlan;
use super::sequential::{Schedule, looks};
use super::summary::{channel_summary, region_means};
use super::{BiasRow, Channel, RegionSummary, reference_batches, summarize};
use crate::error::Error;
use crate::limits::MAX_REPLICAS;
use crate::progress::Progress;
use crate::reference_cache::REFERENCE_SEED;
use crate::regions::Region;

/// Replicas rendered before the design is planned.
pub const PILOT: usize = 32;
/// Safety factor on the pilot's per-replica CVs: their own relative standard error with 32
/// replicas is `1/√(2·31)` ≈ 13%.
pub const CV_MARGIN: f64 = 1.25;

/// The region means of the replicas rendered so far, and what rendering them cost.
struct Replicas {
    /// Per non-empty region (table order): the region, its pixels, its mean in each replica.
    means: Vec<(Region, usize, Vec<DVec3>)>,
    nonfinite: u64,
    seconds: f64,
    interrupted: bool,
}

impl Replicas {
    fn len(&self) -> usize {
        self.means.first().map_or(0, |m| m.2.len())
    }

    /// Seconds per replica so far.
    fn per_replica(&self) -> f64 {
        self.seconds / self.len().max(1) as f64
    }

    /// Renders replicas up to replica `n − 1` (`job::chunk` at a time) unless a stop is
    /// requested.
    fn extend(
        &mut self,
        plan: &BiasPlan,
        setup: &Setup,
        watch: &Stopwatch,
        n: usize,
        progress: &mut dyn Progress,
    ) -> Result<(), Error> {
        while self.len() < n {
            if progress.stop_requested() {
                self.interrupted = true;
                return Ok(());
            }
            let seeds = self.len() as u64..(n as u64).min(self.len() as u64 + chunk(plan));
            let before = watch.read().seconds;
            let rendered = render_chunk(plan, plan.seeds(seeds))?;
            self.seconds += watch.read().seconds - before;
            for (rgb, nonfinite) in rendered {
                self.nonfinite += nonfinite;
                for (all, one) in self
                    .means
                    .iter_mut()
                    .zip(region_means(&[rgb], &setup.regions))
                {
                    all.2.extend(one.2);
                }
                progress.step();
            }
        }
        Ok(())
    }

    /// The summary of row `row` (region-major, channels in [`Channel::ALL`] order) over the
    /// first `n` replicas.
    fn summary(&self, row: usize, n: usize) -> Summary {
        channel_summary(&self.means[row / 4].2[..n], Channel::ALL[row % 4])
    }
}

/// What a test of one row would need: `(N, B)` with the seconds of a fresh test, or `None`
/// when the row cannot be planned (no spread, or no `B` within [`MAX_REPLICAS`]).
struct Cost {
    replicas: usize,
    batches: u32,
    seconds: f64,
}

/// The costs of the sequential design.
struct Prices {
    per_replica: f64,
    per_batch: f64,
    /// The reference target on `ρ`: `δ/(4·z_{1−α/2})`.
    rho_target: f64,
    delta: f64,
    last_level: f64,
}

impl Prices {
    /// The plan of a row with per-replica CV `cv` against a reference of relative s.e. `rho`
    /// from `batches` batches, and the batches it needs.
    fn plan(&self, cv: f64, rho: f64, batches: u32) -> Option<(EquivalencePlan, f64, u32)> {
        if !(cv.is_finite() && cv > 0.0 && rho.is_finite() && rho > 0.0) {
            return None;
        }
        let ratio = (rho / self.rho_target).powi(2);
        let needed = (batches as f64 * ratio).ceil().max(batches as f64);
        if needed > MAX_REPLICAS as f64 {
            return None;
        }
        let needed = needed as u32;
        let plan = EquivalencePlan {
            delta: self.delta,
            alpha: self.last_level,
            reference_rel_se: rho * (batches as f64 / needed as f64).sqrt(),
            reference_n: needed as usize,
        };
        Some((plan, CV_MARGIN * cv, needed))
    }

    /// What a fresh test of this row alone would need.
    fn cost(&self, cv: f64, rho: f64, batches: u32) -> Option<Cost> {
        let (plan, cv, needed) = self.plan(cv, rho, batches)?;
        let n = replicas_for(&[(plan, cv)], PLANNED_POWER, MAX_REPLICAS as usize)?;
        Some(Cost {
            replicas: n,
            batches: needed,
            seconds: n as f64 * self.per_replica + needed as f64 * self.per_batch,
        })
    }
}

/// The per-replica CV of row `row` (region-major, channels in [`Channel::ALL`] order) and the
/// relative standard error of its reference; NaN where either side has no spread.
fn spread(replicas: &Replicas, reference: &[RegionSummary], row: usize) -> (f64, f64) {
    let e = replicas.summary(row, replicas.len());
    let r = reference[row / 4].channel(Channel::ALL[row % 4]);
    if e.no_spread() || r.no_spread() {
        return (f64::NAN, f64::NAN);
    }
    (e.variance.sqrt() / e.mean.abs(), r.std_err / r.mean.abs())
}

/// The rows to plan for, with their `N_max` and reference batches: cheapest first (each row's
/// cost alone), while the chosen rows' `N_max` (planned for all of them together) and largest
/// reference fit in `left` seconds beyond the `batches` and replicas already rendered.
fn choose(
    replicas: &Replicas,
    reference: &[RegionSummary],
    prices: &Prices,
    batches: u32,
    left: f64,
) -> (Vec<usize>, usize, u32) {
    let rows = 4 * replicas.means.len();
    let mut order: Vec<(usize, f64)> = (0..rows)
        .filter_map(|row| {
            let (cv, rho) = spread(replicas, reference, row);
            Some((row, prices.cost(cv, rho, batches)?.seconds))
        })
        .collect();
    order.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
    let mut chosen: (Vec<usize>, usize, u32) = (Vec::new(), 0, batches);
    for (row, _) in order {
        let candidate: Vec<usize> = chosen.0.iter().copied().chain([row]).collect();
        let planned: Vec<(EquivalencePlan, f64, u32)> = candidate
            .iter()
            .filter_map(|&r| {
                let (cv, rho) = spread(replicas, reference, r);
                prices.plan(cv, rho, batches)
            })
            .collect();
        let tests: Vec<(EquivalencePlan, f64)> = planned.iter().map(|p| (p.0, p.1)).collect();
        let Some(n) = replicas_for(&tests, PLANNED_POWER, MAX_REPLICAS as usize) else {
            break;
        };
        let b = planned.iter().map(|p| p.2).max().unwrap_or(batches);
        let seconds = (b - batches) as f64 * prices.per_batch
            + n.saturating_sub(replicas.len()) as f64 * prices.per_replica;
        if seconds > left {
            break;
        }
        chosen = (candidate, n, b);
    }
    chosen
}

/// Runs the budgeted test of `plan` (see the module's header).
pub(super) fn run(
    plan: &BiasPlan,
    budget: Duration,
    progress: &mut dyn Progress,
) -> Result<BiasOutcome, Error> {
    let watch = Stopwatch::start(&plan.backend);
    let budget = budget.as_secs_f64();
    let protocol = plan.protocol;
    let setup = Setup::of(plan);
    let spp = plan.reference_batch_spp;
    let extend_reference = |range| {
        let (settings, scene) = (&setup.settings, &plan.scene);
        reference_batches(settings, scene, setup.frame, range, spp, REFERENCE_SEED)
    };
    let before = watch.read().seconds;
    let mut reference = extend_reference(0..plan.reference_batches)?;
    let per_batch = (watch.read().seconds - before) / plan.reference_batches as f64;

    let name = plan.method.name();
    let mut replicas = Replicas {
        means: region_means(&[], &setup.regions),
        nonfinite: 0,
        seconds: 0.0,
        interrupted: false,
    };
    progress.begin(&name, PILOT as u64, 0);
    let pilot = replicas.extend(plan, &setup, &watch, PILOT, progress);
    progress.end();
    pilot?;
    if replicas.len() < 2 {
        return Err(Error::Interrupted(
            "interrupted before 2 replicas finished".into(),
        ));
    }
    let z = normal_quantile(1.0 - 0.5 * protocol.alpha);
    let prices = Prices {
        per_replica: replicas.per_replica(),
        per_batch,
        rho_target: protocol.delta / (4.0 * z),
        delta: protocol.delta,
        last_level: Schedule::last_level(protocol.alpha),
    };
    let summaries = summarize(&reference.rgb, &setup.regions);
    let left = budget - watch.read().seconds;
    let batches = plan.reference_batches;
    let (mut planned_rows, n_max, batches_max) =
        choose(&replicas, &summaries, &prices, batches, left);
    planned_rows.sort_unstable();
    let rows = 4 * replicas.means.len();
    if batches_max > batches {
        let more = extend_reference(batches..batches_max)?;
        reference.rgb.extend(more.rgb);
        reference.nonfinite += more.nonfinite;
    }
    let summaries = summarize(&reference.rgb, &setup.regions);

    // The looks.
    let schedule = Schedule::new(n_max, replicas.len(), protocol.alpha);
    let mut failure = None;
    progress.begin(&name, n_max as u64, replicas.len() as u64);
    let (states, taken) = if planned_rows.is_empty() {
        (Vec::new(), Vec::new())
    } else {
        let aim: Vec<bool> = (0..rows).map(|row| planned_rows.contains(&row)).collect();
        looks(&schedule, protocol.delta, &aim, |n| {
            let more = n.saturating_sub(replicas.len()) as f64 * replicas.per_replica();
            if failure.is_some() || watch.read().seconds + more > budget {
                return None;
            }
            if let Err(e) = replicas.extend(plan, &setup, &watch, n, progress) {
                failure = Some(e);
            }
            if failure.is_some() || replicas.interrupted {
                return None;
            }
            let at = |row: usize| {
                let r = summaries[row / 4].channel(Channel::ALL[row % 4]);
                (replicas.summary(row, n), *r)
            };
            Some((0..rows).map(at).collect())
        })
    };
    progress.end();
    if let Some(e) = failure {
        return Err(e);
    }

    // The rows, in table order, with what an undecided one would need.
    let prices = Prices {
        per_replica: replicas.per_replica(),
        ..prices
    };
    let batches_now = reference.rgb.len() as u32;
    let mut table = Vec::with_capacity(rows);
    let mut designs = Vec::with_capacity(rows);
    for row in 0..rows {
        let (region, pixels, _) = replicas.means[row / 4];
        let channel = Channel::ALL[row % 4];
        let state = states.get(row).filter(|s| s.test.is_some());
        let reference_summary = *summaries[row / 4].channel(channel);
        let (estimate, test, holm_rejected, verdict, look) = match state {
            Some(s) => (
                s.estimate.expect("looked at"),
                s.test.expect("looked at"),
                s.holm_rejected,
                s.verdict,
                s.decided_at.map(|k| k + 1),
            ),
            None => {
                let estimate = replicas.summary(row, replicas.len());
                let confidence = 1.0 - protocol.alpha;
                let test = equivalence(&estimate, &reference_summary, protocol.delta, confidence);
                (estimate, test, false, Verdict::Inconclusive, None)
            }
        };
        let needs = (verdict == Verdict::Inconclusive).then(|| {
            let (cv, rho) = spread(&replicas, &summaries, row);
            let cost = prices.cost(cv, rho, batches_now);
            Needs {
                replicas: cost.as_ref().map(|c| c.replicas),
                reference_batches: cost.as_ref().map(|c| c.batches),
                minutes: cost.as_ref().map(|c| c.seconds / 60.0),
            }
        });
        table.push(BiasRow {
            method: name.clone(),
            region,
            channel,
            pixels,
            estimate,
            reference: reference_summary,
            equivalence: test,
            holm_rejected,
            verdict,
        });
        designs.push(RowDesign {
            region: region.name(),
            channel: channel.name(),
            planned: planned_rows.contains(&row),
            look,
            needs,
        });
    }
    let looks = schedule
        .n
        .iter()
        .zip(&schedule.levels)
        .enumerate()
        .map(|(k, (&n, &level))| {
            let done = taken.get(k);
            LookEntry {
                n,
                level,
                taken: done.is_some(),
                equivalent: done.map_or(0, |l| l.equivalent),
                biased: done.map_or(0, |l| l.biased),
            }
        })
        .filter(|_| n_max > 0)
        .collect();
    let sequential = SequentialEntry {
        spending: "lan-demets-obrien-fleming",
        clock: Clock::of(&plan.backend).name(),
        budget_seconds: budget,
        used_seconds: watch.read().seconds,
        seconds_per_replica: prices.per_replica,
        seconds_per_reference_batch: per_batch,
        pilot: PILOT,
        reference_target: protocol.delta / 4.0,
        n_max,
        looks,
        rows: designs,
    };
    let counts = Counts {
        replicas: replicas.len(),
        reference_batches: batches_now,
        nonfinite: NonFinite {
            replicas: replicas.nonfinite,
            reference: reference.nonfinite,
        },
        interrupted: replicas.interrupted,
    };
    Ok(outcome(plan, &setup, counts, table, Some(sequential)))
}
