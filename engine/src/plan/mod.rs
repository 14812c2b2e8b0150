//! The pass kernels' interface (`kernels.rs`, shared with `build.rs`, which writes the kernels'
//! GLSL buffer declarations from it).

mod kernels;

pub use kernels::{Access, KernelBuffer, PassKernel, Role, SCENE_BINDINGS};
