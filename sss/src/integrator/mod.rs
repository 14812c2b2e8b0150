//! Integrators (DESIGN §4): the path-tracing baseline ([`pt`]) and the progressive reference
//! ([`reference`]) built on it, with exact order-independent accumulation ([`exact`]).

pub mod exact;
pub mod pt;
pub mod reference;

pub use exact::ExactSum;
pub use pt::{HitPolicy, Image, PtSettings, Shading};
pub use reference::{Reference, ReferenceConfig, Shard};
