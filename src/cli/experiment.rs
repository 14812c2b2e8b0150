//! `reshift experiment NAME`: the named reproductions of seed 001's figures
//! (`lab::experiments`); prints the table and the findings (or the JSON) and where the outputs
//! are.

use std::path::PathBuf;

use clap::{Args, ValueEnum};
use lab::experiments::{Experiment, Settings};

use super::common::{BackendArgs, Bars, CliResult, parse_resolution};

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Name {
    /// Fig. 6: the four shifts vs. path tracing at equal time, one large light (`bumpy`).
    ShiftComparison,
    /// Fig. 7: the shift comparison with 512 small lights (`many-lights`).
    ManyLights,
    /// Fig. 8: hybrid and sequential vs. path tracing on the ten measured materials (`materials`).
    Materials,
    /// Fig. 9: the gain of hybrid / sequential over equal-time path tracing vs. the mean free path.
    MfpScaling,
    /// Fig. 4: where the hybrid criterion picks reconnection, per region.
    HybridMap,
    /// Fig. 5: the fraction of improved samples, hybrid vs. sequential.
    ImprovedFraction,
    /// Fig. 10: reconnection vs. delayed reconnection in the sequential scheme's temporal pass.
    TemporalShift,
}

impl From<Name> for Experiment {
    fn from(name: Name) -> Experiment {
        match name {
            Name::ShiftComparison => Experiment::ShiftComparison,
            Name::ManyLights => Experiment::ManyLights,
            Name::Materials => Experiment::Materials,
            Name::MfpScaling => Experiment::MfpScaling,
            Name::HybridMap => Experiment::HybridMap,
            Name::ImprovedFraction => Experiment::ImprovedFraction,
            Name::TemporalShift => Experiment::TemporalShift,
        }
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
    let settings = Settings {
        replicas: args.replicas,
        resolution: parse_resolution(&args.resolution)?,
        reference_spp: args.reference_spp,
        out: args.out.clone(),
        cache: args.cache.clone(),
        backend: args.backend.open()?,
    };
    let report = Experiment::from(args.name).run(&settings, &mut Bars::default())?;
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
