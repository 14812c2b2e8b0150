//! `single-scatter[:spp][/channels=<scattering|uniform>]`: seed 000's hybrid estimator
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
//! On Vulkan its twin is the kernel `engine/glsl/method_single_scatter.glsl`
//! ([`engine::vulkan::Renderer::single_scatter`]): the same sample and light-selection streams,
//! one dispatch per sample.

use std::cell::RefCell;

use engine::random_walk_method::SceneLighting;
use engine::{Backend, PipelineError};
use restir::rng::StreamKey;
use sss::integrator::single_scatter::{self, ChannelSelection, SingleScatterSettings};
use sss::scene::{GBuffer, Scene};

use super::estimator::{Entry, Estimator, Frame, Method, parse_spp};
use super::pt::to_image;

/// `purpose` of the exits' light-selection streams (the kernel's `PURPOSE_SINGLE_SCATTER_LIGHT`).
pub use engine::purpose::SINGLE_SCATTER_LIGHT as PURPOSE_SINGLE_SCATTER_LIGHT;

pub const ENTRY: Entry = Entry {
    family: "single-scatter",
    usage: "single-scatter[:spp][/channels=<scattering|uniform>]",
    about: "path-traced zero and single scattering, diffusion with R − R1 for the rest [000]; \
            `/channels=uniform` draws distance channels uniformly (default σt·α CDF)",
    build: |arg| Ok(Method::new(parse(arg)?)),
};

/// `spp` samples per pixel of the hybrid estimator with distance channels drawn by `channels`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SingleScatter {
    pub spp: u32,
    pub channels: ChannelSelection,
}

/// The method of `single-scatter:<arg>` (`None`: 1 spp, the σt·α channel CDF).
fn parse(arg: Option<&str>) -> Result<SingleScatter, String> {
    let (spp, option) = match arg.map(|a| a.split_once('/').unwrap_or((a, ""))) {
        None => (None, ""),
        Some((spp, option)) => (Some(spp), option),
    };
    let channels = match option {
        "" | "channels=scattering" => ChannelSelection::Scattering,
        "channels=uniform" => ChannelSelection::Uniform,
        other => {
            return Err(format!(
                "unknown option {other:?}; known: channels=scattering, channels=uniform"
            ));
        }
    };
    Ok(SingleScatter {
        spp: parse_spp(spp)?,
        channels,
    })
}

impl Estimator for SingleScatter {
    fn name(&self) -> String {
        match self.channels {
            ChannelSelection::Scattering => format!("single-scatter:{}", self.spp),
            ChannelSelection::Uniform => format!("single-scatter:{}/channels=uniform", self.spp),
        }
    }

    fn spp(&self) -> u32 {
        self.spp
    }

    fn with_spp(&self, spp: u32) -> Option<Method> {
        Some(Method::new(SingleScatter { spp, ..*self }))
    }

    fn render(
        &self,
        backend: &Backend,
        scene: &Scene,
        frames: u32,
        seed: u64,
    ) -> Result<Frame, PipelineError> {
        let frame = frames - 1;
        if let Some(mut renderer) = backend.renderer() {
            let (image, nonfinite) =
                renderer.single_scatter(scene, frame, seed, self.spp, self.channels)?;
            return Ok(Frame {
                image,
                frames_rendered: 1,
                nonfinite,
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
        Ok(Frame {
            image: to_image(&image),
            frames_rendered: 1,
            nonfinite: image.nonfinite,
        })
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
        ] {
            assert_eq!(Method::parse(bad).expect_err(bad).spec, bad);
        }
    }
}
