//! `shifts`: shift mappings on SSS paths `[x0, x1, x2, x3]` (DESIGN §5, §9; [001 §3.2, §4]).
//!
//! Every shift implements [`restir::shift::Shift`] over [`SssDomain`] (one pixel at a frame) and
//! [`SssSample`] (the reservoir sample of [001 Alg. 3]):
//!
//! | shift | map | `J` |
//! |---|---|---|
//! | [`Identity`] | `x` | 1 |
//! | [`Reconnection`] | `[y0, y1, x2, x3]` | 1 |
//! | [`DelayedReconnection`] | replay at y1 → y2, keep x3 | [001 Eq. 11] |
//! | [`Hybrid`] | reconnection or delayed by the criterion of [001 §4.1] | as chosen |
//! | [`InvertingReconnection`] | reconnection + probabilistic inversion [001 Alg. 4] | 1 |
//! | [`DistantReconnection`] | reconnection where x2 is far from both x1 (worked example) | 1 |
//!
//! [`broken`] holds the deliberately wrong shifts the conformance tests must catch. Every shift
//! is registered by one line of `registry.rs`, which gives it its [`ShiftKind`]: a name, a GPU
//! code and the CPU shift that presets ([`preset`]) and the backends use; the shift's type
//! declares what it does with a sample's stored random numbers ([`numbers`]), from which
//! [`preset::Preset::validate`] derives which passes may replay them.

pub mod broken;
/// What the GLSL twins (`shifts/glsl/`) share with this crate: the stored sample and reservoir,
/// the index policy, the shifts' stream purposes (`twin::contract!`; rendered to
/// `contract/shifts.glsl` by `engine/build.rs`). The shift kinds come from `registry.rs`.
pub mod contract;
mod delayed;
mod distant;
mod domain;
mod hybrid;
mod inversion;
mod kind;
pub mod numbers;
pub mod preset;
mod reconnection;
mod sample;
mod target;

pub use contract::{IndexPolicy, PixelReservoir, SssSample};
pub use delayed::DelayedReconnection;
pub use distant::DistantReconnection;
pub use domain::{LightPath, Located, SssDomain};
pub use hybrid::Hybrid;
pub use inversion::{InvertingReconnection, resolve_deferred_index};
pub use kind::ShiftKind;
pub use reconnection::{Identity, Reconnection};
pub use sss::contract::bssrdf::INDEX_UNKNOWN;
pub use target::Target;
