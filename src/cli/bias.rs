//! `reshift bias`: replicas of one method against independent path-traced reference batches
//! (the path tracer with the method's reference settings, `Method::reference`: the dipole
//! profile for `image-space`); per region and colour channel (red, green, blue, luminance) the
//! Welch test of zero bias (Holm across all of them) and the verdict "equivalent within ±δ at
//! 1 − α", "biased" or "inconclusive" (`lab::bias::run`). By default the group-sequential
//! design within `--budget`; `--replicas N` runs a fixed N. Here: the options, parsed into a
//! `lab::bias::BiasPlan`; what it prints: the table with the overall verdict in words, or the
//! JSON of the outcome (schema `reshift-bias/4`, docs/results-schema.md).

use std::time::Duration;

use std::path::PathBuf;

use clap::Args;
use glam::Vec3;
use lab::bias::shard::{BiasShard, run_shard};
use lab::bias::{
    self, BiasOutcome, BiasPlan, BiasRow, PLANNED_POWER, Protocol, Replicas, SequentialEntry,
    Table, Tinted, default_resolution, overall,
};
use lab::limits::MAX_REPLICAS;
use lab::output::{output_dir, write_text};
use lab::shard::{Shard, file_name};
use methods::Method;
use restir::stats::Verdict;
use serde_json::Value;
use sss::InputError;

use super::common::{
    BackendArgs, Bars, CliError, CliResult, command_line, load_scene, parse_resolution,
    with_resolution,
};

#[derive(Args, Clone, Debug)]
pub struct BiasArgs {
    /// Built-in scene name or path to a scene .toml.
    #[arg(long, default_value = "bumpy")]
    pub scene: String,
    /// The method under test, e.g. restir:hybrid.
    #[arg(long)]
    pub method: String,
    /// A fixed number of independent replicas (seeds S..S+N, S = --first-seed), tested once at
    /// level α; without it, the group-sequential design within --budget.
    #[arg(long, conflicts_with = "budget")]
    pub replicas: Option<u32>,
    /// Seed S of the first replica. A test whose seeds do not overlap an earlier test's shares
    /// no random number with it: a confirmatory test of an earlier one's rows.
    #[arg(long, value_name = "S", default_value_t = 0)]
    pub first_seed: u64,
    /// Time the group-sequential design may take, on the backend's clock (process CPU time on
    /// the CPU backend), e.g. 90s, 10m, 1.5h.
    #[arg(long, default_value = "10m")]
    pub budget: String,
    /// Tolerance δ on the relative bias of a region's mean in each channel (0.02 = ±2%).
    #[arg(long, default_value_t = 0.02)]
    pub delta: f64,
    /// Family-wise level α (each CI has confidence 1 − α).
    #[arg(long, default_value_t = 0.01)]
    pub alpha: f64,
    /// Frames of the camera trajectory; the last one is tested.
    #[arg(long, default_value_t = 16)]
    pub frames: u32,
    /// Image size WxH [default: the scene's aspect ratio at about 64x48's 3072 pixels; 64x48
    /// for the built-in 4:3 scenes].
    #[arg(long)]
    pub resolution: Option<String>,
    /// Independent path-traced reference batches.
    #[arg(long, default_value_t = 32)]
    pub reference_batches: u32,
    /// Samples per pixel of one reference batch.
    #[arg(long, default_value_t = 64)]
    pub reference_batch_spp: u32,
    /// A negative control: the method's final frame multiplied per channel by R,G,B (e.g.
    /// 1,1,1.03: blue 3% too bright). Biased by construction; the outcome names the factor.
    #[arg(long, value_name = "R,G,B", conflicts_with = "shard")]
    pub tint: Option<String>,
    /// Print JSON (schema `reshift-bias/4`) instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Render only shard i of n (0-based, i < n): the replicas of seeds S + ⌊i·N/n⌋ .. S +
    /// ⌊(i+1)·N/n⌋ (shard 0 also the reference), written to <out>/shard-i-of-n.json; `reshift merge` of
    /// all n prints what one run prints, bit for bit (docs/cluster.md).
    /// Needs --replicas N (the fixed design).
    #[arg(long, value_name = "i/n")]
    pub shard: Option<String>,
    /// With --shard: the folder of the shard file.
    #[arg(long, requires = "shard", default_value = "out/bias-shards")]
    pub out: PathBuf,
    #[command(flatten)]
    pub backend: BackendArgs,
}

/// Runs `bias` and prints the table (or the JSON), or with `--shard` writes the shard file; a
/// test stopped by Ctrl-C prints the replicas rendered so far and fails.
pub fn command(args: &BiasArgs) -> CliResult<()> {
    if let Some(text) = &args.shard {
        let shard = Shard::parse(text, "--shard")?;
        if args.replicas.is_none() {
            return Err(CliError(format!(
                "--shard {text}: a shard needs a fixed number of replicas (--replicas N), not the \
                 budgeted design"
            )));
        }
        let (plan, scene_key) = plan(args)?;
        return write_shard(args, &plan, &scene_key, shard);
    }
    let (plan, _) = plan(args)?;
    let outcome = bias::run(&plan, &mut Bars::default())?;
    print(&plan, &outcome, args.json);
    if outcome.interrupted {
        return Err(CliError(format!(
            "interrupted after {} replicas",
            outcome.replicas
        )));
    }
    Ok(())
}

/// The table (or the JSON) of `outcome`.
fn print(plan: &BiasPlan, outcome: &BiasOutcome, json: bool) {
    if json {
        println!("{}", outcome.to_json_pretty());
    } else {
        print_table(plan, outcome);
    }
}

/// Renders `shard` of `plan` and writes its file into `--out`.
fn write_shard(args: &BiasArgs, plan: &BiasPlan, scene_key: &str, shard: Shard) -> CliResult<()> {
    let part = run_shard(plan, scene_key, &args.scene, shard, &mut Bars::default())?;
    let path = output_dir(&args.out)?.join(file_name(shard));
    let text = serde_json::to_string_pretty(&part).expect("plain data serializes");
    write_text(&path, &text)?;
    println!(
        "shard {}/{} of {} replicas: written to {}",
        shard.index,
        shard.count,
        part.plan.replicas,
        path.display()
    );
    Ok(())
}

/// `reshift merge` of bias shard files (their JSON): prints what one run prints.
pub fn merge(files: Vec<(PathBuf, Value)>, json: bool) -> CliResult<()> {
    let parts = files
        .into_iter()
        .map(|(path, value)| Ok((path.clone(), lab::shard::parse::<BiasShard>(&path, value)?)))
        .collect::<Result<Vec<_>, lab::Error>>()?;
    let (plan, outcome) = bias::shard::merge(parts)?;
    print(&plan, &outcome, json);
    Ok(())
}

/// The plan of `args`, checked with errors that name the options, and the scene's cache key.
fn plan(args: &BiasArgs) -> CliResult<(BiasPlan, String)> {
    let mut method = Method::parse(&args.method)?;
    if let Some(text) = &args.tint {
        let factor = parse_tint(text)?;
        method = Method::new(Tinted { method, factor });
    }
    let loaded = load_scene(&args.scene)?;
    let resolution = match &args.resolution {
        Some(text) => parse_resolution(text)?,
        None => default_resolution(loaded.scene.camera.width(), loaded.scene.camera.height()),
    };
    let plan = BiasPlan {
        scene: with_resolution(loaded.scene, Some(resolution)),
        spec: method.name(),
        method,
        replicas: match args.replicas {
            Some(n) => Replicas::Fixed(n),
            None => Replicas::Budget(parse_budget(&args.budget)?),
        },
        first_seed: args.first_seed,
        frames: args.frames,
        protocol: Protocol {
            delta: args.delta,
            alpha: args.alpha,
        },
        reference_batches: args.reference_batches,
        reference_batch_spp: args.reference_batch_spp,
        backend: args.backend.open()?,
        reference: None,
    };
    plan.validate(command_line())?;
    Ok((plan, loaded.key))
}

/// Three finite factors ≥ 0, `R,G,B`.
fn parse_tint(text: &str) -> CliResult<Vec3> {
    let factors: Vec<f32> = text
        .split(',')
        .map(|f| {
            f.trim()
                .parse::<f32>()
                .ok()
                .filter(|f| f.is_finite() && *f >= 0.0)
        })
        .collect::<Option<_>>()
        .unwrap_or_default();
    match factors[..] {
        [r, g, b] => Ok(Vec3::new(r, g, b)),
        _ => {
            let reason = "expected three finite factors ≥ 0, R,G,B, such as 1,1,1.03";
            Err(InputError::new(command_line(), "--tint", format!("{text:?}"), reason).into())
        }
    }
}

/// A time such as `90s`, `10m` or `1.5h` (a number ≥ 0 and a unit s, m or h).
fn parse_budget(text: &str) -> CliResult<Duration> {
    let unit = |suffix: char| match suffix {
        's' => Some(1.0),
        'm' => Some(60.0),
        'h' => Some(3600.0),
        _ => None,
    };
    let parsed = text.trim().char_indices().last().and_then(|(at, suffix)| {
        let seconds = unit(suffix)? * text.trim()[..at].parse::<f64>().ok()?;
        Duration::try_from_secs_f64(seconds).ok()
    });
    parsed.ok_or_else(|| {
        let reason = "expected a time such as 90s, 10m or 1.5h";
        InputError::new(command_line(), "--budget", format!("{text:?}"), reason).into()
    })
}

/// The test as a Markdown table between a header line (what ran) and the verdict and plan lines.
fn print_table(plan: &BiasPlan, outcome: &BiasOutcome) {
    let protocol = outcome.protocol();
    let reference = &outcome.reference;
    let design = match outcome.sequential {
        Some(_) => "group-sequential: α spent over the looks by Lan–DeMets O'Brien–Fleming, Holm across all rows at each look's level".to_string(),
        None => format!("{}% CIs, Holm across all rows", 100.0 * outcome.confidence),
    };
    println!(
        "# bias of {} on {} ({}, frame {}): N = {} replicas vs {} reference batches × {} spp ({} profile); per region and channel, δ = ±{}%, α = {} ({design})\n",
        plan.method,
        outcome.scene,
        outcome.resolution,
        outcome.frames - 1,
        outcome.replicas,
        reference.batches,
        reference.spp_per_batch,
        reference.profile,
        100.0 * protocol.delta,
        protocol.alpha,
    );
    println!("{}", Table(&outcome.rows));
    if let Some(sequential) = &outcome.sequential {
        print_sequential(sequential);
    }
    println!(
        "verdict: {}; non-finite values: {} in replicas, {} in the reference",
        verdict_line(&outcome.rows, &protocol),
        outcome.nonfinite.replicas,
        outcome.nonfinite.reference
    );
    let goal = format!(
        "every row equivalent within ±{}% with probability ≥ {PLANNED_POWER} if the method had no bias",
        100.0 * protocol.delta
    );
    match &outcome.planned.replicas {
        Ok(n) => println!("planned: N = {n} for {goal} (from this run's per-replica CVs)"),
        Err(why) => println!("planned: no N for {goal}: {why}"),
    }
}

/// The looks, the rows left undecided with what they would need, and the budget.
fn print_sequential(s: &SequentialEntry) {
    for (k, look) in s.looks.iter().enumerate() {
        let what = if look.taken {
            format!("{} equivalent, {} biased", look.equivalent, look.biased)
        } else {
            "not taken".to_string()
        };
        println!(
            "look {}: N = {}, level {:.2e} ({:.4}% CIs): {what}",
            k + 1,
            look.n,
            look.level,
            100.0 * (1.0 - look.level)
        );
    }
    for row in s.rows.iter() {
        let Some(needs) = row.needs else { continue };
        let state = if row.planned {
            "not decided"
        } else {
            "not decided (not planned for: its reference or replicas exceed the budget)"
        };
        let cost = match (needs.replicas, needs.reference_batches, needs.minutes) {
            (Some(n), Some(b), Some(minutes)) => format!(
                "needs N = {n} replicas and {b} reference batches, ≈ {minutes:.1} min of {}",
                s.clock
            ),
            _ => format!(
                "cannot be planned (no spread, or more than {MAX_REPLICAS} replicas or reference batches)"
            ),
        };
        println!("{} {}: {state}: {cost}", row.region, row.channel);
    }
    println!(
        "budget: {:.0} of {:.0} s used ({}); {:.3} s per replica, {:.3} s per reference batch; pilot {} replicas, N_max = {}, reference error ≤ δ/4 in planned rows",
        s.used_seconds,
        s.budget_seconds,
        s.clock,
        s.seconds_per_replica,
        s.seconds_per_reference_batch,
        s.pilot,
        s.n_max
    );
}

/// The overall verdict in words: `equivalent within ±δ at 99% in every region and channel`,
/// `biased (in k of n rows)` or `inconclusive (k of n rows not decided)`.
fn verdict_line(rows: &[BiasRow], protocol: &Protocol) -> String {
    let count = |v| rows.iter().filter(|r| r.verdict == v).count();
    let verdict = overall(rows);
    match verdict {
        Verdict::Equivalent => {
            format!("{} in every region and channel", protocol.describe(verdict))
        }
        Verdict::Biased => format!("biased (in {} of {} rows)", count(verdict), rows.len()),
        Verdict::Inconclusive => format!(
            "inconclusive ({} of {} rows not decided)",
            count(verdict),
            rows.len()
        ),
    }
}
