//! Integrators (DESIGN §4): the path-tracing baseline ([`pt`]) and the progressive reference
//! ([`reference`]) built on it, with exact order-independent accumulation ([`exact`]); seed
//! 000's hybrid of path-traced zero and single scattering with `R − R1` diffusion
//! ([`single_scatter`]); the image-space method of seed 002 ([`image_space`]) and the
//! variance-guided adaptive sampler of seed 004 ([`adaptive`]).

pub mod adaptive;
pub mod boundary_reuse;
pub mod exact;
pub mod image_space;
pub mod pt;
pub mod reference;
pub mod single_scatter;

pub use exact::ExactSum;
pub use pt::{HitPolicy, PtSettings, SampleMeans, Shading};
pub use reference::{Reference, ReferenceConfig, Shard};
