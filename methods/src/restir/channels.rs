//! `restir:<preset>/channels=rgb`: per-channel reservoirs. One resampled sample `Y` paints
//! `f(Y)·W`, whose colour is `f(Y)/p̂(Y)` up to a scalar; with a scalar `p̂` that per-sample colour
//! is chromatic noise in lit pixels. Here the preset runs three times, with `p̂ = f_r`, `f_g`
//! and `f_b` ([`Target::Red`], `Green`, `Blue`), and output channel `c` is channel `c` of run
//! `c`: each run is GRIS with a target positive wherever its channel of `f` is, so each output
//! channel is unbiased [001 Eq. 5], and within a channel `f_c(Y)·W` has no colour left to vary.
//!
//! The three runs share the seed, so they draw the same candidates, probe rays, light samples
//! and neighbours; only the resampling decisions (which depend on `p̂`) differ. The cost is
//! about three runs of the preset: the timing covers all three and the non-finite counts are
//! their sum. With `/shade=all` each run shades its own channel by its Rao-Blackwellised value.

use engine::image::Image;
use engine::{Backend, Keep, PassTiming, PipelineError, Preset, Target};
use sss::scene::Scene;

use super::streamed;
use crate::estimator::{Estimator, LastFrame, Method, Trajectory};

/// The per-channel targets, in output channel order.
const CHANNELS: [Target; 3] = [Target::Red, Target::Green, Target::Blue];

/// The preset `0` (its target the luminance, which each run replaces) run once per channel.
#[derive(Clone, Debug, PartialEq)]
pub struct Channels(pub Preset);

/// The image whose channel `c` is channel `c` of `images[c]` (all of one size).
fn merge(images: [&Image; 3]) -> Image {
    let [red, green, blue] = images;
    let pixels = (red.pixels.iter().zip(&green.pixels).zip(&blue.pixels))
        .map(|((r, g), b)| glam::Vec3::new(r.x, g.y, b.z))
        .collect();
    Image {
        width: red.width,
        height: red.height,
        pixels,
    }
}

/// The three runs' passes, each labelled by its run's channel (`red: spatial4:hybrid`).
fn channel_passes(runs: &mut [Trajectory]) -> Vec<PassTiming> {
    let mut passes = Vec::new();
    for (run, target) in runs.iter_mut().zip(CHANNELS) {
        passes.extend(
            std::mem::take(&mut run.passes)
                .into_iter()
                .map(|pass| PassTiming {
                    label: format!("{}: {}", target.name(), pass.label),
                    ..pass
                }),
        );
    }
    passes
}

impl Estimator for Channels {
    fn name(&self) -> String {
        format!("restir:{}", self.0.name)
    }

    /// One BSSRDF candidate per pixel and frame, shared by the three runs.
    fn spp(&self) -> u32 {
        1
    }

    fn with_spp(&self, _spp: u32) -> Option<Method> {
        None
    }

    /// Streams pose the scene at each frame and evaluate temporal reuse's history in the
    /// previous frame's pose (`engine::reuse::Previous`).
    fn renders_motion(&self) -> bool {
        true
    }

    /// The three runs' last frames, merged; each run keeps only its last image.
    fn render(
        &self,
        backend: &Backend,
        scene: &Scene,
        frames: u32,
        seed: u64,
    ) -> Result<LastFrame, PipelineError> {
        self.merged(backend, scene, frames, seed, Keep::Last)?
            .last_frame()
    }

    /// The three runs of replica `seed`, merged channel by channel, frame by frame; the
    /// non-finite count is theirs summed.
    fn render_trajectory(
        &self,
        backend: &Backend,
        scene: &Scene,
        frames: u32,
        seed: u64,
    ) -> Result<Trajectory, PipelineError> {
        self.merged(backend, scene, frames, seed, Keep::Every)
    }
}

impl Channels {
    /// The three channel runs of replica `seed` one after another (each a stream of `frames`
    /// frames keeping the images `keep` says), their kept frames merged.
    fn merged(
        &self,
        backend: &Backend,
        scene: &Scene,
        frames: u32,
        seed: u64,
        keep: Keep,
    ) -> Result<Trajectory, PipelineError> {
        let mut runs = Vec::with_capacity(CHANNELS.len());
        for target in CHANNELS {
            let preset = Preset {
                target,
                ..self.0.clone()
            };
            runs.push(streamed(&preset, backend, scene, frames, seed, keep)?);
        }
        let frames_out = (0..runs[0].frames.len())
            .map(|f| merge([&runs[0].frames[f], &runs[1].frames[f], &runs[2].frames[f]]))
            .collect();
        Ok(Trajectory {
            frames: frames_out,
            frames_rendered: frames,
            nonfinite: runs.iter().map(|r| r.nonfinite).sum(),
            counts: None,
            passes: channel_passes(&mut runs),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bumpy() -> Scene {
        let mut scene = Scene::builtin("bumpy").expect("built-in scene");
        scene.camera = scene.camera.with_resolution(24, 18);
        scene
    }

    /// Every frame of replica `seed` of `spec` on the CPU.
    fn frames(spec: &str, scene: &Scene, seed: u64) -> Vec<Image> {
        let method = Method::parse(spec).unwrap();
        let (run, _) = method
            .render_trajectory_on(&Backend::Cpu, scene, 3, seed)
            .unwrap();
        assert_eq!((run.frames.len(), run.nonfinite), (3, 0), "{spec}");
        run.frames
    }

    /// Output channel `c` of `restir:hybrid/channels=rgb` (and with `/shade=all`) is channel `c`
    /// of `restir:hybrid/target=<c>` with the same seed, bit for bit, on every frame; the last
    /// frame is `render`'s; and the merged image is not the luminance target's (the channel
    /// runs resample differently).
    #[test]
    fn each_channel_is_its_channel_target_run() {
        let scene = bumpy();
        for shade in ["", "/shade=all"] {
            let spec = format!("restir:hybrid/channels=rgb{shade}");
            let merged = frames(&spec, &scene, 7);
            for (c, name) in ["red", "green", "blue"].into_iter().enumerate() {
                let single = frames(&format!("restir:hybrid/target={name}{shade}"), &scene, 7);
                let bits = |img: &Image| -> Vec<u32> {
                    img.pixels.iter().map(|p| p[c].to_bits()).collect()
                };
                for (m, s) in merged.iter().zip(&single) {
                    assert_eq!(bits(m), bits(s), "channel {name}{shade}");
                }
            }
            let last = Method::parse(&spec).unwrap().render(&scene, 3, 7).unwrap();
            assert_eq!(last.image.pixels, merged[2].pixels, "{spec}");
            let luminance = frames(&format!("restir:hybrid{shade}"), &scene, 7);
            assert_ne!(merged[2].pixels, luminance[2].pixels, "{spec}");
        }
    }

    /// The same replica on 1 and 2 threads is bit-identical.
    #[test]
    fn channels_are_deterministic_across_thread_counts() {
        let scene = bumpy();
        let on = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| frames("restir:hybrid/channels=rgb", &scene, 3))
        };
        let bits = |frames: Vec<Image>| -> Vec<u32> {
            frames
                .iter()
                .flat_map(|f| f.pixels.iter().flat_map(|p| p.to_array().map(f32::to_bits)))
                .collect()
        };
        assert_eq!(bits(on(1)), bits(on(2)));
    }
}
