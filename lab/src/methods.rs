//! The method registry of the CLI (DESIGN §7): `pt[:spp]`, `restir:<preset>` and
//! `random-walk[:spp]`. A method
//! renders the final frame of a scene's camera trajectory for one replica seed; adding a method
//! or a family of methods is one entry of [`REGISTRY`].

use std::fmt;
use std::time::Instant;

use sss::integrator::pt::{self, PtSettings};
use sss::scene::{GBuffer, Scene};

use engine::image::Image;
use engine::random_walk_method;
use engine::{Backend, PipelineError, RunConfig};
use shifts::ShiftKind;
use shifts::preset::{PRESET_NAMES, PassSpec, Preset};

/// The final frame of one replica of a method, and what it cost.
#[derive(Clone, Debug)]
pub struct Rendered {
    /// Linear RGB of frame `frames − 1`.
    pub image: Image,
    /// Wall-clock seconds per rendered frame (G-buffer included).
    pub seconds_per_frame: f64,
    /// Frames the method rendered to produce `image` (1 for memoryless estimators).
    pub frames_rendered: u32,
    /// Shaded values that were NaN or infinite (written as 0 or left out of the mean).
    pub nonfinite: u64,
}

/// A rendering method: a function of `(scene, frames, seed)`.
#[derive(Clone, Debug, PartialEq)]
pub enum Method {
    /// The path-traced baseline at `spp` samples per pixel. It has no memory across frames, so
    /// only the final frame is rendered.
    Pt { spp: u32 },
    /// The ReSTIR SSS pipeline with a preset; every frame of the trajectory is rendered
    /// (temporal reuse), the last one is kept.
    Restir(Preset),
    /// The volumetric random walk on translucent pixels, the path tracer on the others
    /// ([`random_walk_method`]); memoryless like `pt`.
    RandomWalk { spp: u32 },
}

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

/// One family of methods: `family[:argument]`.
pub struct Entry {
    pub family: &'static str,
    /// How to write it, e.g. `pt[:spp]`.
    pub usage: &'static str,
    pub about: &'static str,
    /// Builds the method from the text after `family:` (`None` without a colon).
    pub build: fn(Option<&str>) -> Result<Method, String>,
}

/// Every method family the CLI knows.
pub const REGISTRY: &[Entry] = &[
    Entry {
        family: "pt",
        usage: "pt[:spp]",
        about: "path-traced baseline, BSSRDF importance sampling, all probe hits (default 1 spp)",
        build: |arg| Ok(Method::Pt { spp: spp(arg)? }),
    },
    Entry {
        family: "restir",
        usage: "restir:<reconnection|delayed|hybrid|sequential|sequential-exact>[/temporal=<shift>]",
        about: "ReSTIR SSS with spatiotemporal reuse and the preset's shift mapping [001 §5.1]; \
                `/temporal=<shift>` swaps the temporal pass's shift (001 Fig. 10)",
        build: restir,
    },
    Entry {
        family: "random-walk",
        usage: "random-walk[:spp]",
        about: "volumetric random walk on translucent pixels (another transport model than the BSSRDF)",
        build: |arg| Ok(Method::RandomWalk { spp: spp(arg)? }),
    },
];

/// `restir:<preset>[/temporal=<shift>]`: a registered preset, optionally with the shift of its
/// temporal pass replaced by the [`ShiftKind`] named `<shift>`.
fn restir(arg: Option<&str>) -> Result<Method, String> {
    let arg = arg.ok_or("needs a preset, e.g. restir:hybrid")?;
    let (name, temporal) = match arg.split_once("/temporal=") {
        Some((name, shift)) => (name, Some(shift)),
        None => (arg, None),
    };
    let mut preset = Preset::named(name).ok_or_else(|| {
        format!(
            "unknown preset {name:?}; known: {}",
            PRESET_NAMES.join(", ")
        )
    })?;
    if let Some(wanted) = temporal {
        let kind = ShiftKind::ALL
            .into_iter()
            .find(|k| k.name() == wanted)
            .ok_or_else(|| {
                let known: Vec<&str> = ShiftKind::ALL.iter().map(|k| k.name()).collect();
                format!("unknown shift {wanted:?}; known: {}", known.join(", "))
            })?;
        for pass in &mut preset.passes {
            if let PassSpec::Temporal { shift, .. } = pass {
                *shift = kind;
            }
        }
        preset.name = arg.to_string();
    }
    Ok(Method::Restir(preset))
}

/// `spp` of `family[:spp]`: 1 without an argument, else a positive integer.
fn spp(arg: Option<&str>) -> Result<u32, String> {
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

    /// The canonical name (`pt:4`, `restir:hybrid`).
    pub fn name(&self) -> String {
        match self {
            Method::Pt { spp } => format!("pt:{spp}"),
            Method::Restir(preset) => format!("restir:{}", preset.name),
            Method::RandomWalk { spp } => format!("random-walk:{spp}"),
        }
    }

    /// Samples per pixel per frame: the path tracers' `spp`, 1 candidate for ReSTIR.
    pub fn spp(&self) -> u32 {
        match self {
            Method::Pt { spp } | Method::RandomWalk { spp } => *spp,
            Method::Restir(_) => 1,
        }
    }

    /// The same method with `spp` samples per pixel, for the path tracers; ReSTIR presets have a
    /// fixed per-frame cost and are returned unchanged.
    pub fn with_spp(&self, spp: u32) -> Method {
        match self {
            Method::Pt { .. } => Method::Pt { spp },
            Method::RandomWalk { .. } => Method::RandomWalk { spp },
            Method::Restir(_) => self.clone(),
        }
    }

    /// Renders replica `seed` on the CPU and returns frame `frames − 1` (the resolution is the
    /// camera's).
    pub fn render(&self, scene: &Scene, frames: u32, seed: u64) -> Result<Rendered, PipelineError> {
        self.render_on(&Backend::Cpu, scene, frames, seed)
    }

    /// [`Method::render`] on `backend`. On Vulkan, `seconds_per_frame` is wall-clock time
    /// including read-back, like the CPU's.
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
        let last = frames - 1;
        let start = Instant::now();
        // The renderer's lock is taken only by the memoryless methods: `Backend::run` takes it
        // itself.
        let (image, frames_rendered, nonfinite) = match self {
            Method::Restir(preset) => {
                let config = RunConfig {
                    seed,
                    frames,
                    collect_diagnostics: false,
                };
                let mut result = backend.run(scene, preset, &config)?;
                let image = result
                    .frames
                    .pop()
                    .ok_or_else(|| PipelineError::Config("the run returned no frame".into()))?;
                (image, frames, result.nan_count)
            }
            Method::Pt { spp } => match backend.renderer() {
                Some(mut renderer) => {
                    let (image, nonfinite) = renderer.pt(scene, last, seed, *spp)?;
                    (image, 1, nonfinite)
                }
                None => {
                    let gbuffer = GBuffer::render(scene, last);
                    let image = pt::render(scene, &gbuffer, &PtSettings::default(), seed, 0, *spp);
                    let pixels = image.pixels.iter().map(|p| p.as_vec3()).collect();
                    let converted = Image {
                        width: image.width,
                        height: image.height,
                        pixels,
                    };
                    (converted, 1, image.nonfinite)
                }
            },
            Method::RandomWalk { spp } => match backend.renderer() {
                Some(mut renderer) => {
                    let (image, nonfinite) = renderer.random_walk(scene, last, seed, *spp)?;
                    (image, 1, nonfinite)
                }
                None => {
                    let gbuffer = GBuffer::render(scene, last);
                    let (image, nonfinite) =
                        random_walk_method::render(scene, &gbuffer, seed, *spp)?;
                    (image, 1, nonfinite)
                }
            },
        };
        Ok(Rendered {
            image,
            seconds_per_frame: start.elapsed().as_secs_f64() / frames_rendered as f64,
            frames_rendered,
            nonfinite,
        })
    }
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.pad(&self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn registry_parses_every_family_and_rejects_the_rest() {
        assert_eq!(Method::parse("pt").unwrap(), Method::Pt { spp: 1 });
        assert_eq!(Method::parse("pt:8").unwrap(), Method::Pt { spp: 8 });
        assert_eq!(
            Method::parse("random-walk:2").unwrap(),
            Method::RandomWalk { spp: 2 }
        );
        for name in PRESET_NAMES {
            let method = Method::parse(&format!("restir:{name}")).unwrap();
            assert_eq!(method.name(), format!("restir:{name}"));
            assert_eq!(Method::parse(&method.name()).unwrap(), method);
        }
        let swapped = Method::parse("restir:sequential/temporal=delayed").unwrap();
        assert_eq!(swapped.name(), "restir:sequential/temporal=delayed");
        let Method::Restir(preset) = &swapped else {
            panic!("{swapped:?}")
        };
        let temporal: Vec<_> = preset
            .passes
            .iter()
            .filter_map(|p| match p {
                PassSpec::Temporal { shift, .. } => Some(*shift),
                _ => None,
            })
            .collect();
        assert_eq!(temporal, [ShiftKind::DelayedReconnection]);
        for bad in [
            "restir:sequential/temporal=nope",
            "restir:nope/temporal=delayed",
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
