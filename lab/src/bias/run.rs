//! A bias test as a job ([`run`]): replicas of one method against independent batches of the
//! path tracer with the method's reference settings, per region and channel; the job of
//! `reshift bias`. A fixed number of replicas runs here ([`Replicas::Fixed`]); a budget runs the
//! group-sequential design of `budgeted` ([`Replicas::Budget`]).

use std::path::Path;

use super::bias_rows;
use super::job::{Counts, Setup, outcome, reference, render_replicas};
use super::outcome::{BiasOutcome, NonFinite};
use super::plan::{BiasPlan, Replicas};
use super::{budgeted, summarize};
use crate::error::Error;
use crate::progress::Progress;

/// Runs the bias test of `plan`, reporting to `progress` (one phase, the replicas, named after
/// the method). The regions and the reference are those of the last frame; replica `i` renders
/// with seed `first_seed + i`, several at once on the CPU (`job::chunk`). A stop request ends the replicas after
/// the current chunk:
/// the outcome of those rendered ([`BiasOutcome::interrupted`]), or [`Error::Interrupted`]
/// before two.
pub fn run(plan: &BiasPlan, progress: &mut dyn Progress) -> Result<BiasOutcome, Error> {
    plan.validate(Path::new("(bias plan)"))?;
    match plan.replicas {
        Replicas::Fixed(n) => fixed(plan, n, progress),
        Replicas::Budget(budget) => budgeted::run(plan, budget, progress),
    }
}

/// [`Replicas::Fixed`]: `n` replicas, one test of every row at level α.
fn fixed(plan: &BiasPlan, n: u32, progress: &mut dyn Progress) -> Result<BiasOutcome, Error> {
    let setup = Setup::of(plan);
    let reference = reference(plan)?;
    let name = plan.method.name();
    progress.begin(&name, n as u64, 0);
    let replicas = render_replicas(plan, plan.seeds(0..n as u64), progress);
    progress.end();
    let replicas = replicas?;
    if replicas.rgb.len() < 2 {
        return Err(Error::Interrupted(
            "interrupted before 2 replicas finished".into(),
        ));
    }
    let rows = bias_rows(
        &name,
        &summarize(&replicas.rgb, &setup.regions),
        &summarize(&reference.rgb, &setup.regions),
        &plan.protocol,
    );
    let counts = Counts {
        replicas: replicas.rgb.len(),
        reference_batches: plan.reference_batches,
        nonfinite: NonFinite {
            replicas: replicas.nonfinite,
            reference: reference.nonfinite,
        },
        interrupted: replicas.rgb.len() < n as usize,
    };
    Ok(outcome(plan, &setup, counts, rows, None))
}
