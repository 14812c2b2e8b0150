//! The `reshift` subcommands (DESIGN §7). Each module owns its clap arguments and one command.

pub mod bias;
mod bias_output;
pub mod common;
pub mod compare;
pub mod experiment;
pub mod gpu_report;
pub mod reference;
pub mod render;

use clap::Args;
use methods::REGISTRY;
use serde_json::json;
use sss::scene::Scene;

/// `--json` for the listing commands.
#[derive(Args, Clone, Debug)]
pub struct ListArgs {
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

/// `reshift scenes`: built-in scenes with a one-line description.
pub fn scenes(args: &ListArgs) {
    if args.json {
        let list: Vec<_> = Scene::BUILTIN
            .iter()
            .map(|(name, about)| json!({ "name": name, "description": about }))
            .collect();
        println!(
            "{}",
            serde_json::to_string_pretty(&list).expect("JSON values")
        );
    } else {
        let width = Scene::BUILTIN
            .iter()
            .map(|(n, _)| n.len())
            .max()
            .unwrap_or(0);
        for (name, about) in Scene::BUILTIN {
            println!("{name:width$}  {about}");
        }
    }
}

/// `reshift methods`: the method registry.
pub fn methods(args: &ListArgs) {
    if args.json {
        let list: Vec<_> = REGISTRY
            .iter()
            .map(|e| json!({ "family": e.family, "usage": e.usage, "description": e.about }))
            .collect();
        println!(
            "{}",
            serde_json::to_string_pretty(&list).expect("JSON values")
        );
    } else {
        for e in REGISTRY {
            println!("{}\n    {}", e.usage, e.about);
        }
    }
}
