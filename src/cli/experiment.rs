//! `reshift experiment NAME`: the named reproductions of seed 001's figures
//! (`lab::experiments`); prints the table and the findings (or the JSON) and where the outputs
//! are.

use std::path::PathBuf;

use clap::builder::PossibleValue;
use clap::{Args, ValueEnum};
use lab::experiments::{Experiment, Settings};

use sss::limits;

use super::common::{BackendArgs, Bars, CliResult, command_line, parse_resolution};

/// An experiment name on the command line; the names and their help are
/// `lab::experiments::Experiment`'s.
#[derive(Clone, Copy, Debug)]
pub struct Name(pub Experiment);

/// [`Experiment::ALL`] as [`Name`]s.
const NAMES: [Name; Experiment::ALL.len()] = {
    let mut names = [Name(Experiment::ALL[0]); Experiment::ALL.len()];
    let mut i = 1;
    while i < names.len() {
        names[i] = Name(Experiment::ALL[i]);
        i += 1;
    }
    names
};

impl ValueEnum for Name {
    fn value_variants<'a>() -> &'a [Self] {
        &NAMES
    }

    fn to_possible_value(&self) -> Option<PossibleValue> {
        Some(PossibleValue::new(self.0.name()).help(self.0.about()))
    }
}

#[derive(Args, Clone, Debug)]
pub struct ExperimentArgs {
    pub name: Name,
    /// Independent replicas per method.
    #[arg(long, default_value_t = 16)]
    pub replicas: u32,
    /// Image size WxH.
    #[arg(long, default_value = "128x96")]
    pub resolution: String,
    /// Samples per pixel of the references.
    #[arg(long, default_value_t = 8192)]
    pub reference_spp: u32,
    /// Output folder [default: out/experiment-<name>].
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Folder of cached references.
    #[arg(long, default_value = "out/cache")]
    pub cache: PathBuf,
    /// Print JSON instead of the tables.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub backend: BackendArgs,
}

pub fn command(args: &ExperimentArgs) -> CliResult<()> {
    limits::replicas(command_line(), "--replicas", args.replicas)?;
    let settings = Settings {
        replicas: args.replicas,
        resolution: parse_resolution(&args.resolution)?,
        reference_spp: args.reference_spp,
        out: args.out.clone(),
        cache: args.cache.clone(),
        backend: args.backend.open()?,
    };
    let report = args.name.0.run(&settings, &mut Bars::default())?;
    if args.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&report.json).expect("JSON values")
        );
    } else {
        println!(
            "{}\n{}\nOutputs are in {}",
            report.table,
            report.findings,
            report.out.display()
        );
    }
    Ok(())
}
