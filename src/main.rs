//! The `reshift` command line (DESIGN §7): render, reference/merge, compare, bias, experiment,
//! gpu-report, view, scenes, methods, shifts, and the toy GRIS bias table. Errors print one line `reshift: …` and exit 1.

mod cli;
mod toy;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

use cli::common::{CliError, install_interrupt_handler};

#[derive(Parser)]
#[command(
    name = "reshift",
    version,
    about = "ReSTIR with pluggable shift mappings for subsurface scattering: render, compare, test bias",
    long_about = None
)]
struct Cli {
    /// The asset directory: where scenes find the meshes they name with `asset = "…"` (paper
    /// 001's public assets, e.g. a clone of its assets repository); overrides RESHIFT_ASSETS.
    #[arg(long, global = true, value_name = "DIR")]
    assets: Option<std::path::PathBuf>,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// List the built-in scenes.
    Scenes(cli::ListArgs),
    /// List the rendering methods and the ReSTIR presets.
    Methods(cli::ListArgs),
    /// List the registered shifts (what each declares) and the MIS schemes.
    Shifts(cli::ListArgs),
    /// Render one method on one scene: linear EXR + tonemapped PNG + timing.
    Render(cli::render::RenderArgs),
    /// Compare methods against a cached reference: table.md, table.csv, results.json, error maps.
    Compare(cli::compare::CompareArgs),
    /// Test one method for bias: per-region Welch tests and the equivalence verdict with δ.
    Bias(cli::bias::BiasArgs),
    /// Progressive path-traced reference with checkpoint/resume and shards.
    Reference(cli::reference::ReferenceArgs),
    /// Merge the shards of a reference, a bias test or a comparison (bit-identical to one run).
    Merge(cli::merge::MergeArgs),
    /// Named reproductions of paper 001's figures.
    Experiment(cli::experiment::ExperimentArgs),
    /// On the Vulkan device: device and limits, GPU parity, time of every pass at each size,
    /// equal-time comparison; one markdown file for docs/performance.md.
    GpuReport(cli::gpu_report::GpuReportArgs),
    /// An interactive window on the Vulkan backend: fly or orbit the camera, switch methods,
    /// see the error against a progressive reference; --script drives it, --record writes it.
    View(cli::view::ViewArgs),
    /// The toy GRIS chains: bias of every shift × MIS scheme against closed-form integrals.
    Toy,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    if let Some(dir) = &cli.assets {
        sss::scene::assets::set_dir(dir);
    }
    install_interrupt_handler();
    let result: Result<(), CliError> = match &cli.command {
        Command::Scenes(args) => {
            cli::scenes(args);
            Ok(())
        }
        Command::Methods(args) => {
            cli::methods(args);
            Ok(())
        }
        Command::Shifts(args) => {
            cli::shifts(args);
            Ok(())
        }
        Command::Render(args) => cli::render::command(args),
        Command::Compare(args) => cli::compare::command(args),
        Command::Bias(args) => cli::bias::command(args),
        Command::Reference(args) => cli::reference::command(args),
        Command::Merge(args) => cli::merge::command(args),
        Command::Experiment(args) => cli::experiment::command(args),
        Command::GpuReport(args) => cli::gpu_report::command(args),
        Command::View(args) => cli::view::command(args),
        Command::Toy => toy::run().map_err(CliError::from),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("reshift: {e}");
            ExitCode::FAILURE
        }
    }
}
