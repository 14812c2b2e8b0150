//! Rendering methods by name (DESIGN §7): `pt[:spp]`, `restir:<preset>`, `random-walk[:spp]`.
//!
//! A method renders the final frame of a scene's camera trajectory for one replica seed on a
//! [`Backend`]. Each family is one file implementing [`Estimator`] with its [`Entry`] (family,
//! usage, about, build); [`REGISTRY`] lists the entries, one line each. Adding a method is that
//! file plus its `mod` line and its registry line (docs/adding-a-method.md).

pub mod pt;
pub mod random_walk;
pub mod restir;

use std::fmt;
use std::sync::Arc;
use std::time::Instant;

use engine::image::Image;
use engine::{Backend, PipelineError};
use sss::scene::Scene;

/// Every method family the CLI knows, in the order `reshift methods` lists them.
pub const REGISTRY: &[Entry] = &[pt::ENTRY, restir::ENTRY, random_walk::ENTRY];

/// One family of methods: `family[:argument]`.
pub struct Entry {
    pub family: &'static str,
    /// How to write it, e.g. `pt[:spp]`.
    pub usage: &'static str,
    pub about: &'static str,
    /// Builds the method from the text after `family:` (`None` without a colon).
    pub build: fn(Option<&str>) -> Result<Method, String>,
}

/// What a method implements: one estimator of the final frame of a camera trajectory.
pub trait Estimator: fmt::Debug + Send + Sync + 'static {
    /// The canonical name, which [`Method::parse`] reads back (`pt:4`, `restir:hybrid`).
    fn name(&self) -> String;

    /// Samples per pixel per frame.
    fn spp(&self) -> u32;

    /// The same estimator at `spp` samples per pixel, or `None` when its per-frame cost is
    /// fixed (ReSTIR presets).
    fn with_spp(&self, spp: u32) -> Option<Method>;

    /// Renders replica `seed` of `frames ≥ 1` frames of `scene`'s trajectory on `backend` and
    /// returns frame `frames − 1` (the resolution is the camera's). A memoryless estimator
    /// renders only that frame.
    fn render(
        &self,
        backend: &Backend,
        scene: &Scene,
        frames: u32,
        seed: u64,
    ) -> Result<Frame, PipelineError>;
}

/// The output of [`Estimator::render`].
#[derive(Clone, Debug)]
pub struct Frame {
    /// Linear RGB of frame `frames − 1`.
    pub image: Image,
    /// Frames rendered to produce `image` (1 for memoryless estimators).
    pub frames_rendered: u32,
    /// Shaded values that were NaN or infinite (written as 0 or left out of the mean).
    pub nonfinite: u64,
}

/// The final frame of one replica of a method, and what it cost.
#[derive(Clone, Debug)]
pub struct Rendered {
    /// Linear RGB of frame `frames − 1`.
    pub image: Image,
    /// Wall-clock seconds per rendered frame (G-buffer included; on Vulkan with read-back).
    pub seconds_per_frame: f64,
    /// Frames the method rendered to produce `image` (1 for memoryless estimators).
    pub frames_rendered: u32,
    /// Shaded values that were NaN or infinite (written as 0 or left out of the mean).
    pub nonfinite: u64,
}

/// A rendering method: a shared [`Estimator`]. Two methods are equal when their canonical
/// names are.
#[derive(Clone)]
pub struct Method(Arc<dyn Estimator>);

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
    /// The method of `estimator`.
    pub fn new(estimator: impl Estimator) -> Method {
        Method(Arc::new(estimator))
    }

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

    /// The canonical name (`pt:4`, `restir:hybrid`).
    pub fn name(&self) -> String {
        self.0.name()
    }

    /// Samples per pixel per frame: the path tracers' `spp`, 1 candidate for ReSTIR.
    pub fn spp(&self) -> u32 {
        self.0.spp()
    }

    /// The same method with `spp` samples per pixel; a method with a fixed per-frame cost is
    /// returned unchanged.
    pub fn with_spp(&self, spp: u32) -> Method {
        self.0.with_spp(spp).unwrap_or_else(|| self.clone())
    }

    /// Renders replica `seed` on the CPU and returns frame `frames − 1` (the resolution is the
    /// camera's).
    pub fn render(&self, scene: &Scene, frames: u32, seed: u64) -> Result<Rendered, PipelineError> {
        self.render_on(&Backend::Cpu, scene, frames, seed)
    }

    /// [`Method::render`] on `backend`, timed: `seconds_per_frame` is wall-clock time per
    /// rendered frame, including read-back on Vulkan.
    pub fn render_on(
        &self,
        backend: &Backend,
        scene: &Scene,
        frames: u32,
        seed: u64,
    ) -> Result<Rendered, PipelineError> {
        if frames == 0 {
            return Err(PipelineError::Config("frames = 0; need at least 1".into()));
        }
        let start = Instant::now();
        let frame = self.0.render(backend, scene, frames, seed)?;
        Ok(Rendered {
            seconds_per_frame: start.elapsed().as_secs_f64() / frame.frames_rendered as f64,
            image: frame.image,
            frames_rendered: frame.frames_rendered,
            nonfinite: frame.nonfinite,
        })
    }
}

impl PartialEq for Method {
    fn eq(&self, other: &Method) -> bool {
        self.name() == other.name()
    }
}

impl fmt::Debug for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.0.fmt(f)
    }
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.pad(&self.name())
    }
}

/// `spp` of `family[:spp]`: 1 without an argument, else a positive integer.
pub fn parse_spp(arg: Option<&str>) -> Result<u32, String> {
    match arg {
        None => Ok(1),
        Some(text) => match text.parse::<u32>() {
            Ok(n) if n > 0 => Ok(n),
            _ => Err(format!(
                "samples per pixel {text:?} is not a positive integer"
            )),
        },
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

    /// Replica seeds are independent draws, and a replica is a function of its seed: the same
    /// seed gives the same bits, another seed a different image (the negative control).
    #[test]
    fn pt_replicas_are_deterministic_per_seed() {
        let scene = Scene::builtin("bumpy").expect("built-in");
        let scene = Scene {
            camera: scene.camera.with_resolution(12, 9),
            ..scene
        };
        let method = Method::parse("pt:2").unwrap();
        let a = method.render(&scene, 16, 3).unwrap();
        let b = method.render(&scene, 16, 3).unwrap();
        let c = method.render(&scene, 16, 4).unwrap();
        assert_eq!(a.image, b.image);
        assert_ne!(a.image, c.image);
        assert_eq!((a.image.width, a.image.height), (12, 9));
        assert!(method.render(&scene, 0, 3).is_err());
    }
}
