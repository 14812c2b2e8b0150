//! Integrators (DESIGN §4): the path-tracing baseline ([`pt`]) and the progressive reference
//! ([`reference`]) built on it, with exact order-independent accumulation ([`exact`]); seed
//! 000's hybrid of path-traced zero and single scattering with `R − R1` diffusion
//! ([`single_scatter`]). The image-space method of paper 002 and the adaptive sampler of paper 004
//! are estimators of the `methods` crate (`methods/src/image_space/`, `methods/src/adaptive/`).

pub mod exact;
pub mod pt;
pub mod reference;
pub mod single_scatter;

pub use exact::ExactSum;
pub use pt::{HitPolicy, PtSettings, SampleMeans, Shading};
pub use reference::{Reference, ReferenceConfig, Shard};
