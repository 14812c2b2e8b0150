//! `reshift merge`: the shards of one run, in any order, merged into what one run would have
//! given, bit for bit: reference checkpoints (`reshift reference --shard`) into one checkpoint,
//! bias shard files (`reshift bias --shard`) into the printed outcome, compare shards
//! (`reshift compare --shard`) into the report of one run (docs/cluster.md). The kind
//! is read from the files: JSON shard files name their schema, anything else is a checkpoint.

use std::path::{Path, PathBuf};

use clap::Args;
use lab::bias::shard::SHARD_SCHEMA as BIAS_SHARD;
use lab::compare::shard::SHARD_SCHEMA as COMPARE_SHARD;

use super::common::{CliError, CliResult};

#[derive(Args, Clone, Debug)]
pub struct MergeArgs {
    /// The shards of one run, in any order: files, or folders whose shard-*-of-*.json files are
    /// taken (from `reshift bias --shard` or `reshift compare --shard`), or reference checkpoints
    /// (`reshift reference --shard`).
    #[arg(required = true)]
    pub shards: Vec<PathBuf>,
    /// Reference checkpoints: the merged checkpoint (the mean is also written to <out>.exr);
    /// compare shards: the report's folder [default: the first shard's folder].
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Print JSON: the bias outcome (as `reshift bias --json`), the comparison's results.json or
    /// the reference's summary.
    #[arg(long)]
    pub json: bool,
}

/// Merges the shards of `args` by their kind.
pub fn command(args: &MergeArgs) -> CliResult<()> {
    let files = shard_files(&args.shards)?;
    if !files.iter().any(|f| is_json(f)) {
        let out = args.out.as_deref().ok_or_else(|| {
            CliError("merge: reference checkpoints need --out (the merged checkpoint)".into())
        })?;
        return super::reference::merge(&files, out, args.json);
    }
    let mut parts = Vec::new();
    for path in files {
        let (schema, value) = lab::shard::read(&path)?;
        parts.push((path, schema, value));
    }
    let (first, schema) = (parts[0].0.clone(), parts[0].1.clone());
    if let Some((path, other, _)) = parts.iter().find(|(_, s, _)| *s != schema) {
        return Err(CliError(format!(
            "{}: field 'schema' is {other:?}, {} has {schema:?}",
            path.display(),
            first.display()
        )));
    }
    let values = parts.into_iter().map(|(p, _, v)| (p, v)).collect();
    match schema.as_str() {
        BIAS_SHARD => {
            if let Some(out) = &args.out {
                return Err(CliError(format!(
                    "--out {}: bias shards merge into the printed outcome, no file",
                    out.display()
                )));
            }
            super::bias::merge(values, args.json)
        }
        COMPARE_SHARD => super::compare::merge(values, args.out.clone(), args.json),
        other => Err(CliError(format!(
            "{}: schema {other:?} is not a shard file's ({BIAS_SHARD}, {COMPARE_SHARD})",
            first.display()
        ))),
    }
}

/// The files of `paths`: a file as given, a folder's `shard-*-of-*.json` files in name order.
fn shard_files(paths: &[PathBuf]) -> CliResult<Vec<PathBuf>> {
    let mut files = Vec::new();
    for path in paths {
        if !path.is_dir() {
            files.push(path.clone());
            continue;
        }
        let entries =
            std::fs::read_dir(path).map_err(|e| CliError(format!("{}: {e}", path.display())))?;
        let mut found: Vec<PathBuf> = entries
            .filter_map(|e| Some(e.ok()?.path()))
            .filter(|p| {
                p.file_name()
                    .and_then(|n| n.to_str())
                    .is_some_and(|n| n.starts_with("shard-") && n.ends_with(".json"))
            })
            .collect();
        if found.is_empty() {
            return Err(CliError(format!(
                "{}: no shard-*-of-*.json file in this folder",
                path.display()
            )));
        }
        found.sort();
        files.extend(found);
    }
    Ok(files)
}

/// Whether `path` starts (after white space) with `{`: a JSON shard file rather than a
/// checkpoint. An unreadable file is left to the reader to name.
fn is_json(path: &Path) -> bool {
    use std::io::Read;
    let mut head = [0u8; 64];
    let n = std::fs::File::open(path)
        .and_then(|mut f| f.read(&mut head))
        .unwrap_or(0);
    head[..n]
        .iter()
        .find(|b| !b.is_ascii_whitespace())
        .is_some_and(|&b| b == b'{')
}
