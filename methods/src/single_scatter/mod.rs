//! `single-scatter[:spp][/channels=<scattering|uniform>]`: paper 000's hybrid estimator
//! (`sss::integrator::single_scatter`): at a translucent primary hit, zero and single scattering
//! are path traced through the material's `boundary`, and only the rest goes through diffusion,
//! with the signed multiple-scattering-only profile `R − R1` [000 "Combined Approach"]. Lambert
//! pixels get the path tracer's direct lighting. Memoryless like `pt`: only the final frame is
//! rendered.
//!
//! `/channels=` picks the channel of each distance sample: `scattering` (default, the talk's
//! CDF `P_c ∝ σt,c α_c` [000 "RGB variation in σt"]) or `uniform` (`P_c = 1/3`); both are
//! unbiased. Exits are lit by the scene's lights with shadow rays
//! ([`SceneLighting`], the random walk's), whose light selection draws from a stream of its own
//! per pixel ([`PURPOSE_SINGLE_SCATTER_LIGHT`]).
//!
//! On Vulkan its twin is the kernel `method_single_scatter.glsl` beside this file, with its host
//! code [`vulkan`] and what the two share ([`contract`]): the same sample and light-selection
//! streams, one dispatch per sample; `parity.rs` holds its parity tests against the CPU.
//!
//! `/restir` replaces the boundary (zero-scattering) term by ReSTIR over the entry direction and
//! the exit's light vertex [000 "ReSTIR Sample"] ([`boundary_reuse`]: `spp`
//! candidates per frame, temporal reuse with confidence cap `/cap=<κ>`, default 3, and 3 × 3
//! spatial reuse): every frame of the trajectory is rendered and the last one kept. Diffuse
//! boundaries only (other materials are refused); CPU only (refused on Vulkan in one line).

pub mod boundary_reuse;
pub mod contract;
#[cfg(test)]
mod parity;
pub mod vulkan;

use std::cell::RefCell;

use engine::scene_lighting::SceneLighting;
use engine::{Backend, PipelineError};
use restir::rng::StreamKey;
use sss::integrator::single_scatter::{self, ChannelSelection, SingleScatterSettings};
use sss::scene::{GBuffer, Scene};

use self::boundary_reuse::{DEFAULT_CAP, ReuseSettings, SameVertices};
use crate::estimator::{
    Entry, Estimator, LastFrame, Method, Trajectory, memoryless_trajectory, parse_spp,
};
use crate::pt::to_image;

/// `purpose` of the exits' light-selection streams (the kernel's `PURPOSE_SINGLE_SCATTER_LIGHT`).
pub use engine::purpose::SINGLE_SCATTER_LIGHT as PURPOSE_SINGLE_SCATTER_LIGHT;

pub const ENTRY: Entry = Entry {
    family: "single-scatter",
    usage: "single-scatter[:spp][/channels=<scattering|uniform>][/restir[/cap=<κ>]]",
    about: "path-traced zero and single scattering, diffusion with R − R1 for the rest [000]; \
            `/channels=uniform` draws distance channels uniformly (default σt·α CDF); \
            `/restir` resamples the boundary term with temporal (cap κ, default 3) and 3×3 \
            spatial reuse over frames (diffuse boundaries; CPU only)",
    build: |arg| Ok(Method::new(parse(arg)?)),
};

/// `spp` samples per pixel of the hybrid estimator with distance channels drawn by `channels`;
/// with `restir`, the boundary term's temporal confidence cap.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SingleScatter {
    pub spp: u32,
    pub channels: ChannelSelection,
    pub restir: Option<f32>,
}

/// The method of `single-scatter:<arg>` (`None`: 1 spp, the σt·α channel CDF, no reuse).
fn parse(arg: Option<&str>) -> Result<SingleScatter, String> {
    let mut parts = arg.map(|a| a.split('/'));
    let spp = parts.as_mut().and_then(|p| p.next());
    let mut method = SingleScatter {
        spp: parse_spp(spp)?,
        channels: ChannelSelection::Scattering,
        restir: None,
    };
    for option in parts.into_iter().flatten() {
        match (option, option.split_once('=')) {
            ("channels=scattering", _) => method.channels = ChannelSelection::Scattering,
            ("channels=uniform", _) => method.channels = ChannelSelection::Uniform,
            ("restir", _) => method.restir = Some(method.restir.unwrap_or(DEFAULT_CAP)),
            (_, Some(("cap", value))) if method.restir.is_some() => {
                let cap = value
                    .parse::<f32>()
                    .ok()
                    .filter(|c| c.is_finite() && *c > 0.0);
                method.restir =
                    Some(cap.ok_or_else(|| format!("cap {value:?} is not a number > 0"))?);
            }
            (other, _) => {
                return Err(format!(
                    "unknown option {other:?}; known: channels=scattering, channels=uniform, \
                     restir, restir/cap=<κ>"
                ));
            }
        }
    }
    Ok(method)
}

impl Estimator for SingleScatter {
    fn name(&self) -> String {
        let channels = match self.channels {
            ChannelSelection::Scattering => "",
            ChannelSelection::Uniform => "/channels=uniform",
        };
        let restir = match self.restir {
            None => String::new(),
            Some(DEFAULT_CAP) => "/restir".into(),
            Some(cap) => format!("/restir/cap={cap}"),
        };
        format!("single-scatter:{}{channels}{restir}", self.spp)
    }

    fn spp(&self) -> u32 {
        self.spp
    }

    fn with_spp(&self, spp: u32) -> Option<Method> {
        Some(Method::new(SingleScatter { spp, ..*self }))
    }

    /// With `/restir` one run of the trajectory (the reservoirs carry over); plain: the default.
    fn render_trajectory(
        &self,
        backend: &Backend,
        scene: &Scene,
        frames: u32,
        seed: u64,
    ) -> Result<Trajectory, PipelineError> {
        let Some(cap) = self.restir else {
            return memoryless_trajectory(self, backend, scene, frames, seed);
        };
        self.refuse_restir_on(backend)?;
        let images = self.render_restir(scene, cap, frames, 0, seed)?;
        Ok(Trajectory {
            nonfinite: images.iter().map(|i| i.nonfinite).sum(),
            frames: images.iter().map(to_image).collect(),
            frames_rendered: frames,
            counts: None,
            passes: Vec::new(),
        })
    }

    fn render(
        &self,
        backend: &Backend,
        scene: &Scene,
        frames: u32,
        seed: u64,
    ) -> Result<LastFrame, PipelineError> {
        self.refuse_restir_on(backend)?;
        if let Some(cap) = self.restir {
            let last = self.render_restir(scene, cap, frames, frames - 1, seed)?;
            let image = last.last().ok_or_else(|| {
                PipelineError::Config(format!("{}: frames = {frames} gave no frame", self.name()))
            })?;
            return Ok(LastFrame {
                image: to_image(image),
                frames_rendered: frames,
                nonfinite: image.nonfinite,
                passes: Vec::new(),
            });
        }
        let frame = frames - 1;
        if let Some(mut renderer) = backend.renderer() {
            let (image, nonfinite) =
                vulkan::render(&mut renderer, scene, frame, seed, self.spp, self.channels)?;
            return Ok(LastFrame {
                image,
                frames_rendered: 1,
                nonfinite,
                passes: Vec::new(),
            });
        }
        let gbuffer = GBuffer::render(scene, frame);
        let settings = SingleScatterSettings {
            channel: self.channels,
            ..SingleScatterSettings::default()
        };
        let (image, _truncated) =
            single_scatter::render(scene, &gbuffer, &settings, seed, 0, self.spp, |pixel| {
                exit_lighting(scene, pixel, frame, seed)
            })
            .map_err(|e| PipelineError::Config(format!("{}: {e}", self.name())))?;
        Ok(LastFrame {
            image: to_image(&image),
            frames_rendered: 1,
            nonfinite: image.nonfinite,
            passes: Vec::new(),
        })
    }
}

impl SingleScatter {
    /// `/restir` has no Vulkan implementation: one line naming the method.
    fn refuse_restir_on(&self, backend: &Backend) -> Result<(), PipelineError> {
        match (backend, self.restir) {
            (Backend::Vulkan(_), Some(_)) => Err(PipelineError::Config(format!(
                "{}: /restir (ReSTIR on the boundary term) is CPU only; use --backend cpu",
                self.name()
            ))),
            _ => Ok(()),
        }
    }

    /// `/restir`: frames `0..frames` with the boundary term reused
    /// (`boundary_reuse::render`), the images of frames `first_shaded..frames`.
    fn render_restir(
        &self,
        scene: &Scene,
        cap: f32,
        frames: u32,
        first_shaded: u32,
        seed: u64,
    ) -> Result<Vec<sss::integrator::SampleMeans>, PipelineError> {
        let settings = SingleScatterSettings {
            channel: self.channels,
            ..SingleScatterSettings::default()
        };
        let reuse = ReuseSettings {
            candidates: self.spp,
            cap,
        };
        let rendered = boundary_reuse::render(
            scene,
            &settings,
            &reuse,
            seed,
            frames,
            first_shaded,
            self.spp,
            |pixel, frame| exit_lighting(scene, pixel, frame, seed),
            &SameVertices,
        )
        .map_err(|e| PipelineError::Config(format!("{}: {e}", self.name())))?;
        Ok(rendered.into_iter().map(|r| r.image).collect())
    }
}

/// The scene's lights at the exits of pixel `pixel`, with its light-selection stream.
pub fn exit_lighting(scene: &Scene, pixel: u32, frame: u32, seed: u64) -> SceneLighting<'_> {
    let key = StreamKey {
        pixel,
        frame,
        pass: 0,
        purpose: PURPOSE_SINGLE_SCATTER_LIGHT,
    };
    SceneLighting {
        scene,
        selection: RefCell::new(key.stream(seed)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_parse_back_and_bad_options_are_refused() {
        for (spec, name) in [
            ("single-scatter", "single-scatter:1"),
            ("single-scatter:4", "single-scatter:4"),
            ("single-scatter:4/channels=scattering", "single-scatter:4"),
            (
                "single-scatter:2/channels=uniform",
                "single-scatter:2/channels=uniform",
            ),
            ("single-scatter:1/restir", "single-scatter:1/restir"),
            ("single-scatter:1/restir/cap=3", "single-scatter:1/restir"),
            (
                "single-scatter:2/restir/cap=20",
                "single-scatter:2/restir/cap=20",
            ),
            (
                "single-scatter:1/restir/channels=uniform",
                "single-scatter:1/channels=uniform/restir",
            ),
        ] {
            let method = Method::parse(spec).unwrap();
            assert_eq!(method.name(), name);
            assert_eq!(Method::parse(&method.name()).unwrap(), method);
        }
        let uniform = Method::parse("single-scatter:2/channels=uniform").unwrap();
        assert_eq!(
            uniform.with_spp(8).name(),
            "single-scatter:8/channels=uniform"
        );
        for bad in [
            "single-scatter:0",
            "single-scatter:x",
            "single-scatter:4/channels=hero",
            "single-scatter:4/spp=2",
            "single-scatter:/channels=uniform",
            "single-scatter:1/cap=3",
            "single-scatter:1/restir/cap=0",
            "single-scatter:1/restir/cap=x",
            "single-scatter/restir",
        ] {
            assert_eq!(Method::parse(bad).expect_err(bad).spec, bad);
        }
    }
}
