//! `adaptive[:option=value[/option=value…]]`: paper 004 (Xie et al. 2020) — path tracing with
//! Xie's radius sampling `g(ξ)` weighted by its own density (unbiased against the Burley
//! reference) and the single-pass variance-guided sample count per pixel and frame
//! ([`cpu`], [004 Eq. 6–17]). Every frame of the trajectory is rendered (the
//! per-pixel history is carried by reprojection) and the last one is kept, with its sample-count
//! map ([`SampleCounts`]). On Vulkan its twin `method_adaptive.glsl` ([`vulkan`]).
//!
//! The folder is the whole method: this file (its registry entry, option parsing and
//! [`Estimator`]), the CPU estimator [`cpu`] and its GLSL twin `adaptive.glsl` (the controller),
//! the kernel `method_adaptive.glsl` with its host code [`vulkan`], what the two languages share
//! ([`contract`]) and the parity tests of the kernel against the CPU (`parity.rs`).
//!
//! Options, each at most once, the paper's defaults otherwise [004 Fig. 1]: `kappa` (κ ∈ [0, 1],
//! 0.2), `target_variance` (σ0² > 0, 0.001), `b_min` and `b_max` (1 ≤ b_min ≤ b_max ≤ `MAX_SPP`,
//! 8 and 64). The canonical name lists the options that differ from the defaults, in that order. With
//! `b_min = b_max = n` every pixel takes `n` samples: the fixed-count baseline of the same
//! estimator (`pt` with `g(ξ)` radii at `n` spp, bit for bit).

pub mod contract;
pub mod cpu;
#[cfg(test)]
mod parity;
pub mod vulkan;

use engine::{Backend, PipelineError};
use sss::limits::MAX_SPP;
use sss::scene::Scene;

use self::cpu::AdaptiveParams;
use crate::estimator::{Entry, Estimator, LastFrame, Method, SampleCounts};
use crate::pt::to_image;

pub const ENTRY: Entry = Entry {
    family: "adaptive",
    usage: "adaptive[:kappa=K/target_variance=S/b_min=N/b_max=M]",
    about: "variance-guided adaptive sample counts with g(ξ) radii [004] (defaults κ 0.2, σ0² 0.001, \
            [8, 64]); reports its mean spp and writes its sample-count map",
    build: |arg| Ok(Method::new(Adaptive(params(arg)?))),
};

/// The option names, in canonical order.
const OPTIONS: [&str; 4] = ["kappa", "target_variance", "b_min", "b_max"];

/// The controller parameters of `adaptive[:<arg>]` (module doc), validated; the error is one
/// line naming the option.
pub fn params(arg: Option<&str>) -> Result<AdaptiveParams, String> {
    let mut params = AdaptiveParams::default();
    let Some(arg) = arg else {
        return Ok(params);
    };
    let mut seen = [false; OPTIONS.len()];
    for option in arg.split('/') {
        let (key, value) = option
            .split_once('=')
            .ok_or_else(|| format!("option {option:?} is not key=value"))?;
        let index = OPTIONS
            .iter()
            .position(|&o| o == key)
            .ok_or_else(|| format!("unknown option {key:?}; known: {}", OPTIONS.join(", ")))?;
        if std::mem::replace(&mut seen[index], true) {
            return Err(format!("option {key} is given twice"));
        }
        let number = || format!("{key} = {value:?} is not a number");
        let count = || format!("{key} = {value:?} is not a whole number");
        match index {
            0 => params.kappa = value.parse().map_err(|_| number())?,
            1 => params.target_variance = value.parse().map_err(|_| number())?,
            2 => params.b_min = value.parse().map_err(|_| count())?,
            _ => params.b_max = value.parse().map_err(|_| count())?,
        }
    }
    params
        .validate()
        .map_err(|e| format!("{} = {}: {}", e.field, e.value, e.reason))?;
    if params.b_max > MAX_SPP {
        // As for `pt:N`: the most samples per pixel and frame of one method (on Vulkan, dispatches).
        return Err(format!("b_max = {} exceeds {MAX_SPP}", params.b_max));
    }
    Ok(params)
}

/// The adaptive sampler with controller parameters `0` (radius sampling `g(ξ)`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Adaptive(pub AdaptiveParams);

impl Estimator for Adaptive {
    fn name(&self) -> String {
        let (p, d) = (&self.0, AdaptiveParams::default());
        let options: Vec<String> = [
            (p.kappa != d.kappa).then(|| format!("kappa={}", p.kappa)),
            (p.target_variance != d.target_variance)
                .then(|| format!("target_variance={}", p.target_variance)),
            (p.b_min != d.b_min).then(|| format!("b_min={}", p.b_min)),
            (p.b_max != d.b_max).then(|| format!("b_max={}", p.b_max)),
        ]
        .into_iter()
        .flatten()
        .collect();
        if options.is_empty() {
            "adaptive".into()
        } else {
            format!("adaptive:{}", options.join("/"))
        }
    }

    /// `b_max`, the most samples a pixel may take in a frame; the mean a frame took is
    /// measured ([`Rendered::spp`](crate::Rendered::spp)).
    fn spp(&self) -> u32 {
        self.0.b_max
    }

    /// The controller chooses the counts: `spp` does not scale it.
    fn with_spp(&self, _spp: u32) -> Option<Method> {
        None
    }

    fn render(
        &self,
        backend: &Backend,
        scene: &Scene,
        frames: u32,
        seed: u64,
    ) -> Result<LastFrame, PipelineError> {
        Ok(self.render_counted(backend, scene, frames, seed)?.0)
    }

    fn render_counted(
        &self,
        backend: &Backend,
        scene: &Scene,
        frames: u32,
        seed: u64,
    ) -> Result<(LastFrame, Option<SampleCounts>), PipelineError> {
        let mut nonfinite = 0;
        let (image, counts) = match backend.renderer() {
            Some(mut renderer) => {
                let last = vulkan::run(&mut renderer, scene, &self.0, seed, frames, |f| {
                    nonfinite += f.image.left_out
                })?
                .ok_or_else(|| PipelineError::Config("adaptive rendered no frame".into()))?;
                (last.image.image, last.counts)
            }
            None => {
                let last = cpu::run(scene, &self.0, seed, frames, |f| {
                    nonfinite += f.image.nonfinite
                })
                .ok_or_else(|| PipelineError::Config("adaptive rendered no frame".into()))?;
                (to_image(&last.image), last.counts)
            }
        };
        let counts = SampleCounts {
            width: image.width,
            height: image.height,
            counts,
            max: self.0.b_max,
        };
        let frame = LastFrame {
            image,
            frames_rendered: frames,
            nonfinite,
            passes: Vec::new(),
        };
        Ok((frame, Some(counts)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use engine::vulkan::testing::backend_or_skip;
    use sss::bssrdf::RadiusSampling;
    use sss::integrator::pt::{self, PtSettings};
    use sss::scene::GBuffer;

    fn scene(name: &str) -> Scene {
        let mut scene = Scene::builtin(name).expect("built-in scene");
        scene.camera = scene.camera.with_resolution(16, 12);
        scene
    }

    #[test]
    fn options_parse_to_a_canonical_name_and_bad_ones_are_named() {
        let default = Method::parse("adaptive").unwrap();
        assert_eq!((default.name(), default.spp()), ("adaptive".into(), 64));
        assert_eq!(
            default.with_spp(4),
            default,
            "the controller sets the counts"
        );
        let method = Method::parse("adaptive:b_max=32/kappa=0.5").unwrap();
        assert_eq!(method.name(), "adaptive:kappa=0.5/b_max=32");
        assert_eq!(Method::parse(&method.name()).unwrap(), method);
        assert_eq!(method.spp(), 32);
        for (bad, names) in [
            ("adaptive:kappa", "kappa"),
            ("adaptive:gamma=1", "gamma"),
            ("adaptive:kappa=0.1/kappa=0.2", "twice"),
            ("adaptive:kappa=2", "kappa"),
            ("adaptive:b_min=9/b_max=4", "b_min"),
            ("adaptive:b_min=x", "b_min"),
            ("adaptive:target_variance=0", "target_variance"),
            ("adaptive:b_max=2000000", "b_max"),
        ] {
            let e = Method::parse(bad).expect_err(bad).to_string();
            assert!(e.contains(names) && !e.contains('\n'), "{bad}: {e}");
        }
    }

    /// With `b_min = b_max = 2` every pixel takes 2 samples: the frame is the path tracer with
    /// `g(ξ)` radii at 2 spp, bit for bit; negative controls: the default radii of `pt` give other
    /// bits, and the default controller takes more than `b_min` samples somewhere.
    #[test]
    fn fixed_budget_is_the_path_tracer_with_xie_radii() {
        let scene = scene("bumpy");
        let fixed = Method::parse("adaptive:b_min=2/b_max=2")
            .unwrap()
            .render(&scene, 3, 4)
            .unwrap();
        let gbuffer = GBuffer::render(&scene, 2);
        let xie = PtSettings {
            radius: RadiusSampling::Xie,
            ..PtSettings::default()
        };
        let f32s = |i: pt::SampleMeans| i.pixels.iter().map(|p| p.as_vec3()).collect::<Vec<_>>();
        let want = f32s(pt::render(&scene, &gbuffer, &xie, 4, 0, 2));
        assert_eq!(fixed.image.pixels, want);
        let burley = f32s(pt::render(
            &scene,
            &gbuffer,
            &PtSettings::default(),
            4,
            0,
            2,
        ));
        assert_ne!(fixed.image.pixels, burley);
        let counts = fixed.counts.as_ref().unwrap();
        assert!(counts.counts.iter().all(|&n| n == 0 || n == 2));
        assert_eq!((fixed.spp, fixed.frames_rendered), (2.0, 3));

        let adaptive = Method::parse("adaptive")
            .unwrap()
            .render(&scene, 3, 4)
            .unwrap();
        let counts = adaptive.counts.as_ref().unwrap();
        assert_eq!(counts.max, 64);
        assert!(
            counts
                .counts
                .iter()
                .all(|&n| n == 0 || (8..=64).contains(&n))
        );
        assert!(counts.counts.iter().any(|&n| n > 8), "{counts:?}");
        assert_eq!(adaptive.spp, counts.mean());
        assert!(adaptive.spp > 8.0 && adaptive.spp <= 64.0);
        assert_eq!(adaptive.nonfinite, 0);
    }

    /// On Vulkan the method renders `bumpy` through its kernel: no non-finite pixel, counts in
    /// `[b_min, b_max]` (0 without a hit) and above `b_min` somewhere (per-pixel parity with the
    /// CPU is `parity.rs`).
    #[test]
    fn renders_on_vulkan() {
        let Some(backend) = backend_or_skip("adaptive::renders_on_vulkan") else {
            return;
        };
        let method = Method::parse("adaptive:b_min=2/b_max=8").unwrap();
        let gpu = method.render_on(&backend, &scene("bumpy"), 3, 4).unwrap();
        assert_eq!((gpu.nonfinite, gpu.frames_rendered), (0, 3));
        assert!(gpu.image.pixels.iter().all(|p| p.is_finite()));
        let counts = gpu.counts.as_ref().unwrap();
        assert!(
            counts
                .counts
                .iter()
                .all(|&n| n == 0 || (2..=8).contains(&n))
        );
        assert!(counts.counts.iter().any(|&n| n > 2), "{counts:?}");
    }
}
