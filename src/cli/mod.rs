//! The `reshift` subcommands (DESIGN §7). Each module owns its clap arguments and one command.

pub mod bias;
pub mod common;
pub mod compare;
pub mod experiment;
pub mod gpu_report;
pub mod merge;
pub mod reference;
pub mod render;
pub mod view;

use clap::Args;
use methods::{REGISTRY, restir as restir_method};
use restir::mis::MisKind;
use serde_json::{Value, json};
use shifts::ShiftKind;
use shifts::preset::{Pairs, Preset};
use sss::scene::Scene;

/// `--json` for the listing commands.
#[derive(Args, Clone, Debug)]
pub struct ListArgs {
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

/// `reshift scenes`: built-in scenes with a one-line description; those that read the asset
/// directory (`--assets`, `RESHIFT_ASSETS`) say so.
pub fn scenes(args: &ListArgs) {
    let all = Scene::BUILTIN
        .iter()
        .map(|s| (s, false))
        .chain(Scene::WITH_ASSETS.iter().map(|s| (s, true)));
    if args.json {
        let list: Vec<_> = all
            .map(|((name, about), assets)| {
                json!({ "name": name, "description": about, "assets": assets })
            })
            .collect();
        print_json(Value::Array(list));
    } else {
        let width = all.clone().map(|((n, _), _)| n.len()).max().unwrap_or(0);
        for ((name, about), assets) in all {
            let needs = if assets { " [assets]" } else { "" };
            println!("{name:width$}  {about}{needs}");
        }
    }
}

/// Prints `list` as pretty JSON.
fn print_json(list: Value) {
    println!(
        "{}",
        serde_json::to_string_pretty(&list).expect("JSON values")
    );
}

/// `reshift methods`: the method registry; under the ReSTIR family, the registered presets
/// (`shifts::preset::PRESETS`) with their passes.
pub fn methods(args: &ListArgs) {
    let presets = Preset::all();
    if args.json {
        let list: Vec<_> = REGISTRY
            .iter()
            .map(|e| {
                let mut entry =
                    json!({ "family": e.family, "usage": e.usage, "description": e.about });
                if e.family == restir_method::ENTRY.family {
                    entry["presets"] = presets
                        .iter()
                        .map(|p| json!({ "name": p.name, "passes": p.describe() }))
                        .collect();
                }
                entry
            })
            .collect();
        print_json(Value::Array(list));
    } else {
        for e in REGISTRY {
            println!("{}\n    {}", e.usage, e.about);
            if e.family == restir_method::ENTRY.family {
                let width = presets.iter().map(|p| p.name.len()).max().unwrap_or(0);
                println!("    presets:");
                for p in &presets {
                    println!("      {:width$}  {}", p.name, p.describe());
                }
            }
        }
    }
}

/// `reshift shifts`: the shift registry (`shifts/src/registry.rs`) with what each shift
/// declares, the MIS schemes a pass can name, and how a spatial pass pairs its neighbours.
pub fn shifts(args: &ListArgs) {
    let deferred = |k: &ShiftKind| k.resolves_deferred_index();
    if args.json {
        let shifts: Vec<_> = ShiftKind::ALL
            .iter()
            .map(|k| {
                json!({
                    "name": k.name(),
                    "code": k.code(),
                    "stored_numbers": k.numbers().to_string(),
                    "resolves_deferred_index": deferred(k),
                    "description": k.about(),
                })
            })
            .collect();
        let mis: Vec<_> = MisKind::ALL
            .iter()
            .map(|m| json!({ "name": m.scheme().name(), "unbiased_when_supports_differ": m.scheme().bias().is_unbiased_when_supports_differ() }))
            .collect();
        let pairs: Vec<_> = Pairs::ALL
            .iter()
            .map(|p| json!({ "name": p.name(), "description": p.about() }))
            .collect();
        print_json(json!({ "shifts": shifts, "mis": mis, "neighbour_pairs": pairs }));
    } else {
        for k in ShiftKind::ALL {
            println!("{}\n    {}", k.name(), k.about());
            println!("    stored random numbers: {}", k.numbers());
            if deferred(&k) {
                println!("    resolves the selected sample's intersection index after the pass");
            }
        }
        println!("MIS schemes:");
        for m in MisKind::ALL {
            let bias = if m.scheme().bias().is_unbiased_when_supports_differ() {
                "unbiased"
            } else {
                "biased unless every shift is a bijection between the supports"
            };
            println!("  {}  {bias}", m.scheme().name());
        }
    }
}
