//! `methods`: the rendering methods by name (DESIGN §7): `pt[:spp]`, `restir:<preset>`,
//! `random-walk[:spp]`, `pt-one-hit[:spp]`, `single-scatter[:spp]`, `image-space[:spp]`,
//! `adaptive[:options]`.
//!
//! A method renders the final frame of a scene's camera trajectory (or every frame of it) for
//! one replica seed on a backend. Each family implements [`Estimator`] with its [`Entry`]
//! (family, usage, about, build); [`REGISTRY`] lists the entries. A method with a kernel of its
//! own is one folder (`pt/`, `image_space/`, `adaptive/`, ...): its entry and estimator
//! (`mod.rs`), its CPU estimator (`cpu.rs`) and GLSL twin, its kernel (`method_*.glsl`, compiled
//! by `build.rs`) with its Vulkan host code (`vulkan.rs`, on the engine's
//! [`Renderer`](engine::vulkan::Renderer)), its contract (`contract.rs`) and its tests.
//!
//! Adding one is that folder and its `pub mod` line in the method registry below: that line is
//! the registration. `build.rs` reads the block (through `methods-registry`, methods/registry)
//! and generates [`REGISTRY`] from it, `<name>::ENTRY` per line in the block's order, which is
//! alphabetical (`cargo fmt` sorts consecutive `mod` lines; only listings follow the order:
//! `reshift methods`, the rows of the ground-truth experiment); a folder with a `contract.rs` has its contract rendered to GLSL
//! (docs/adding-a-method.md). The `mod` lines stay written out: `cargo fmt` and readers follow
//! them.

mod estimator;
pub mod per_sample;

// Method registry: one `pub mod <name>;` line per method family, whose module defines
// `pub const ENTRY: Entry` (only such lines, comments and blank lines go here).
pub mod adaptive;
pub mod image_space;
pub mod pt;
pub mod pt_one_hit;
pub mod random_walk;
pub mod restir;
pub mod single_scatter;
// End of the method registry.

use std::fmt;

/// The SPIR-V that `build.rs` compiled from a kernel `src/<folder>/<name>.glsl`, `None` in a
/// build without `glslc` (for [`Shader::compiled`](engine::vulkan::Shader::compiled)).
#[cfg(reshift_glslc)]
macro_rules! spirv {
    ($name:literal) => {
        Some(include_bytes!(concat!(env!("OUT_DIR"), "/", $name, ".spv")) as &[u8])
    };
}

/// The SPIR-V that `build.rs` compiled from a kernel `src/<folder>/<name>.glsl`, `None` in a
/// build without `glslc` (for [`Shader::compiled`](engine::vulkan::Shader::compiled)).
#[cfg(not(reshift_glslc))]
macro_rules! spirv {
    ($name:literal) => {
        None
    };
}
pub(crate) use spirv;

pub use estimator::{
    Entry, Estimator, LastFrame, Method, Rendered, SampleCounts, Trajectory, memoryless_trajectory,
    parse_spp,
};

include!(concat!(env!("OUT_DIR"), "/registry.rs"));

/// A method specification that could not be parsed.
#[derive(Clone, Debug, PartialEq)]
pub struct MethodError {
    pub spec: String,
    pub reason: String,
}

impl fmt::Display for MethodError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "method {:?}: {}", self.spec, self.reason)
    }
}

impl std::error::Error for MethodError {}

impl Method {
    /// Parses `family[:argument]` against [`REGISTRY`].
    pub fn parse(spec: &str) -> Result<Method, MethodError> {
        let (family, arg) = match spec.split_once(':') {
            Some((f, a)) => (f, Some(a)),
            None => (spec, None),
        };
        let error = |reason: String| MethodError {
            spec: spec.to_string(),
            reason,
        };
        let entry = REGISTRY
            .iter()
            .find(|e| e.family == family)
            .ok_or_else(|| {
                let known: Vec<&str> = REGISTRY.iter().map(|e| e.usage).collect();
                error(format!("unknown method; known: {}", known.join(", ")))
            })?;
        (entry.build)(arg).map_err(error)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn registry_parses_every_family_and_rejects_the_rest() {
        for (spec, name, spp) in [
            ("pt", "pt:1", 1),
            ("pt:8", "pt:8", 8),
            ("random-walk:2", "random-walk:2", 2),
            ("restir:hybrid", "restir:hybrid", 1),
        ] {
            let method = Method::parse(spec).unwrap();
            assert_eq!((method.name(), method.spp()), (name.to_string(), spp));
            assert_eq!(Method::parse(&method.name()).unwrap(), method);
        }
        for entry in REGISTRY {
            assert!(entry.usage.starts_with(entry.family), "{}", entry.usage);
        }
        for bad in [
            "",
            "ptx",
            "pt:0",
            "pt:-1",
            "pt:x",
            "restir",
            "restir:nope",
            "bdpt:4",
        ] {
            let e = Method::parse(bad).expect_err(bad);
            assert_eq!(e.spec, bad);
        }
    }

    #[test]
    fn with_spp_scales_the_path_tracers_only() {
        let pt = Method::parse("pt").unwrap();
        assert_eq!(pt.with_spp(5), Method::parse("pt:5").unwrap());
        let walk = Method::parse("random-walk").unwrap();
        assert_eq!(walk.with_spp(3).name(), "random-walk:3");
        let hybrid = Method::parse("restir:hybrid").unwrap();
        assert_eq!(hybrid.with_spp(5), hybrid);
    }
}
