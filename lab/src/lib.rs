//! `lab`: the reshift lab (DESIGN §7). It names methods ([`methods`]), measures them against
//! references per region ([`regions`], [`metrics`], [`compare`]), runs the replica bias protocol
//! ([`bias`]) and writes tables ([`tables`]). It renders through the `engine` crate and knows
//! nothing of how a backend runs a pass.

pub mod bias;
pub mod compare;
pub mod methods;
pub mod metrics;
pub mod regions;
pub mod tables;
