//! `reshift experiment NAME`: the named reproductions of paper 001's figures
//! (the `experiments` crate); prints the table and the findings (or the JSON) and where the outputs
//! are.

use std::path::PathBuf;

use clap::builder::PossibleValue;
use clap::{Args, ValueEnum};
use experiments::{Experiment, Settings};
use sss::InputError;

use super::common::{BackendArgs, Bars, CliResult, command_line, parse_resolution};

/// An experiment name on the command line; the names and their help are
/// `experiments::Experiment`'s.
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
    /// Independent replicas per method [default: 16; ablation 4; paper-ajax* 8].
    #[arg(long)]
    pub replicas: Option<u32>,
    /// Image size WxH [default: 128x96; ground-truth and model-gap 32x24; paper-ajax* 360x540].
    #[arg(long)]
    pub resolution: Option<String>,
    /// Samples per pixel of the references [default: 8192; ablation 1024; paper-ajax* 2048]; ground-truth: of the
    /// random walk [4096]; model-gap: of each estimator over all replicas [256].
    #[arg(long)]
    pub reference_spp: Option<u32>,
    /// Comma-separated scenes, for ground-truth [default: every built-in scene and
    /// sphere-<material> for every measured material] and model-gap [7 scenes]; ablation takes
    /// one [bumpy].
    #[arg(long, visible_alias = "scene", value_delimiter = ',')]
    pub scenes: Vec<String>,
    /// Comma-separated ReSTIR methods, for ablation: each is varied one knob at a time
    /// [default: restir:hybrid].
    #[arg(long, value_delimiter = ',')]
    pub methods: Vec<String>,
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
    let defaults = args.name.0.defaults();
    if !args.scenes.is_empty() && !args.name.0.takes_scenes() {
        return Err(InputError::new(
            "(command line)",
            "--scenes",
            args.scenes.join(","),
            format!("experiment {} runs its own scenes", args.name.0.name()),
        )
        .into());
    }
    if !args.methods.is_empty() && !args.name.0.takes_methods() {
        return Err(InputError::new(
            "(command line)",
            "--methods",
            args.methods.join(","),
            format!("experiment {} runs its own methods", args.name.0.name()),
        )
        .into());
    }
    let replicas = args.replicas.unwrap_or(defaults.replicas);
    lab::limits::replicas(command_line(), "--replicas", replicas)?;
    let resolution = match &args.resolution {
        Some(text) => parse_resolution(text)?,
        None => defaults.resolution,
    };
    let settings = Settings {
        replicas,
        resolution,
        reference_spp: args.reference_spp.unwrap_or(defaults.reference_spp),
        out: args.out.clone(),
        cache: args.cache.clone(),
        backend: args.backend.open()?,
        scenes: args.scenes.clone(),
        methods: args.methods.clone(),
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
