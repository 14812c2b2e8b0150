//! `restir`: the domain-agnostic GRIS / ReSTIR core (DESIGN §3).

pub mod rng;
pub mod stats;
