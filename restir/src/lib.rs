//! `restir`: the domain-agnostic GRIS / ReSTIR core (DESIGN §3).
//!
//! [`shift`] defines what a user plugs in (domains, shifts, candidate samplers), [`reservoir`]
//! the streaming and stored reservoirs, [`mis`] the resampling MIS schemes, [`resample`] the
//! driver, [`toy`] analytic test domains and a ReSTIR-shaped chain, and [`check`] the
//! conformance kit that tells a user whether their shift is correct.

pub mod check;
/// What the GLSL twins (`restir/glsl/`) share with this crate: [`contract::MAX_DOMAINS`], the MIS
/// kinds, the shift failures and the resampling error codes (`twin::contract!`; rendered to
/// `contract/restir.glsl` by `engine/build.rs`).
pub mod contract;
pub mod mis;
pub mod resample;
pub mod reservoir;
pub mod rng;
pub mod shift;
pub mod stats;
pub mod toy;
