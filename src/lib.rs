//! reshift: ReSTIR with pluggable shift mappings, built around subsurface scattering.
//!
//! This facade re-exports the workspace crates; see `docs/architecture.md` for the layout.

pub use engine;
pub use lab;
pub use restir;
pub use shifts;
pub use sss;
