//! `lab`: the reshift lab (DESIGN §7), the library behind the `reshift` CLI. It runs the methods
//! of the `methods` crate, obtains references ([`reference_cache`]), measures methods against them per
//! region ([`regions`], [`metrics`], [`flip`], [`low_frequency`], [`perceptual`],
//! [`method_result`]), runs
//! comparisons ([`compare`]) and the replica bias protocol ([`bias`]), and writes tables,
//! `results.json` and images ([`report`], drawn with [`draw`]) into its output folders
//! ([`output`]). It renders through the `engine` crate and
//! knows nothing of how a backend runs a pass; long jobs report to a caller's
//! [`progress::Progress`].

pub mod bias;
pub mod chained;
pub mod compare;
pub mod draw;
pub mod error;
pub mod flicker;
pub mod flip;
pub mod gpu_report;
pub mod limits;
pub mod low_frequency;
pub mod method_result;
pub mod metrics;
pub mod output;
pub mod perceptual;
pub mod progress;
pub mod reference_cache;
pub mod regions;
pub mod report;
pub mod scenes;
pub mod shard;
pub mod telemetry;
pub mod timing;
pub mod uncertainty;

pub use error::Error;
