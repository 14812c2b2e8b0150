//! A preset's stream (DESIGN §6): created once for `(scene, preset, seed, backend)`, then asked
//! for one frame after another. It owns what the frames share — the previous frame's G-buffer
//! and reservoirs, the plan's rotation of its buffers, the diagnostics — on the backend that
//! runs it (on Vulkan the buffers stay on the device between frames), and keeps no frame: a
//! caller that keeps only what it needs renders any number of frames in flat memory.
//! [`Backend::run`] is a loop over a stream.

pub(crate) mod frame;

use std::borrow::Cow;

use crate::cpu::CpuStream;
use crate::vulkan::{Renderer, VulkanStream};
use crate::{Backend, PassTiming, PipelineError, Preset, Run, RunConfig};
use sss::scene::{Pose, Scene};

pub use frame::{Finished, Frame};

/// Which frames' images [`Stream::run`] keeps.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Keep {
    Every,
    Last,
}

/// The frames of `preset` on `scene` with one seed, one after another on one backend. A Vulkan
/// stream holds its backend's renderer (locked) until it is dropped.
pub struct Stream<'a> {
    inner: Inner<'a>,
    labels: Vec<String>,
}

enum Inner<'a> {
    Cpu(Box<CpuStream<'a>>),
    Vulkan(Box<VulkanStream<'a>>),
}

impl<'a> Stream<'a> {
    /// The stream of `preset` on `scene` with `config.seed` on `backend`. `config.frames` is
    /// not a limit: the stream renders as many frames as it is asked for (past the end of the
    /// camera's trajectory the camera stays at its last pose); with diagnostics, the reuse
    /// telemetry is recorded at frame `config.frames − 1`.
    pub fn new(
        backend: &'a Backend,
        scene: &'a Scene,
        preset: &Preset,
        config: &RunConfig,
    ) -> Result<Stream<'a>, PipelineError> {
        preset.validate()?;
        match backend.renderer() {
            None => Ok(Stream::of(Inner::Cpu(Box::new(CpuStream::new(
                Cow::Borrowed(scene),
                preset,
                config,
            ))))),
            Some(renderer) => Ok(Stream::of(Inner::Vulkan(Box::new(VulkanStream::new(
                renderer, scene, preset, config,
            )?)))),
        }
    }

    /// [`Stream::new`] with a scene of its own and, on Vulkan, the backend's renderer shared:
    /// locked only while a frame renders, so other users of the backend (a viewer's reference,
    /// its presentation) run between frames. The stream a viewer keeps while the user flies
    /// the camera ([`Stream::frame_at`]).
    pub fn live(
        backend: &Backend,
        scene: Scene,
        preset: &Preset,
        config: &RunConfig,
    ) -> Result<Stream<'static>, PipelineError> {
        preset.validate()?;
        let inner = match backend {
            Backend::Cpu => Inner::Cpu(Box::new(CpuStream::new(Cow::Owned(scene), preset, config))),
            Backend::Vulkan(renderer) => Inner::Vulkan(Box::new(VulkanStream::shared(
                renderer.clone(),
                scene,
                preset,
                config,
            )?)),
        };
        Ok(Stream::of(inner))
    }

    /// [`Stream::new`] on `renderer`, borrowed for the stream's life.
    pub fn on_renderer(
        renderer: &'a mut Renderer,
        scene: &'a Scene,
        preset: &Preset,
        config: &RunConfig,
    ) -> Result<Stream<'a>, PipelineError> {
        preset.validate()?;
        let stream = VulkanStream::new(renderer, scene, preset, config)?;
        Ok(Stream::of(Inner::Vulkan(Box::new(stream))))
    }

    fn of(inner: Inner<'a>) -> Stream<'a> {
        let labels = match &inner {
            Inner::Cpu(s) => s.labels(),
            Inner::Vulkan(s) => s.labels(),
        };
        Stream { inner, labels }
    }

    /// The labels of the plan's steps (`gbuffer`, `candidates`, `temporal:…`, `spatial<n>:…`,
    /// `shade`), the order of [`Frame::steps`].
    pub fn labels(&self) -> &[String] {
        &self.labels
    }

    /// Renders the next frame.
    pub fn frame(&mut self) -> Result<Frame, PipelineError> {
        match &mut self.inner {
            Inner::Cpu(s) => s.frame(),
            Inner::Vulkan(s) => s.frame(),
        }
    }

    /// Renders the next frame with the camera moved to `pose` (its previous frame keeps the
    /// pose it had: [`sss::scene::Camera::moved_to`]), the call of a viewer that flies the
    /// camera. The frames of poses given one by one are those of a trajectory of the same poses
    /// rendered by [`Stream::frame`], bit for bit.
    pub fn frame_at(&mut self, pose: Pose) -> Result<Frame, PipelineError> {
        match &mut self.inner {
            Inner::Cpu(s) => s.move_camera(pose),
            Inner::Vulkan(s) => s.move_camera(pose),
        }
        self.frame()
    }

    /// Ends the stream: the last frame's reservoirs and the diagnostics.
    pub fn finish(self) -> Result<Finished, PipelineError> {
        match self.inner {
            Inner::Cpu(s) => Ok((*s).finish()),
            Inner::Vulkan(s) => s.finish(),
        }
    }

    /// The next `frames` frames as a [`Run`], keeping the images `keep` says (a run that keeps
    /// only the last holds one image whatever `frames` is), with the per-step timings summed
    /// into [`PassTiming`]s (none where a frame came without them). [`Backend::run`] keeps
    /// every one.
    pub fn run(self, frames: u32, keep: Keep) -> Result<Run, PipelineError> {
        self.run_until(frames, keep, &|| false)
    }

    /// [`Stream::run`] that asks `stop` before each frame after the first and, once it says
    /// yes, ends with the frames rendered so far ([`Run::frames_rendered`]; [`Keep::Last`]
    /// keeps the last of them): a caller's interrupt leaves a valid, shorter run. A `stop` that
    /// never says yes gives [`Stream::run`]'s run.
    pub fn run_until(
        mut self,
        frames: u32,
        keep: Keep,
        stop: &dyn Fn() -> bool,
    ) -> Result<Run, PipelineError> {
        let mut images = Vec::with_capacity(match keep {
            Keep::Every => frames as usize,
            Keep::Last => 1,
        });
        let mut steps = vec![Vec::with_capacity(frames as usize); self.labels.len()];
        let mut timed = true;
        let mut nan_count = 0;
        let mut rendered = 0;
        while rendered < frames && (rendered == 0 || !stop()) {
            let frame = self.frame()?;
            nan_count += frame.nan_count;
            timed &= frame.steps.len() == steps.len();
            for (seconds, timing) in steps.iter_mut().zip(frame.steps) {
                seconds.push(timing);
            }
            if keep == Keep::Last {
                images.clear();
            }
            images.push(frame.image);
            rendered += 1;
        }
        let timings = match timed {
            true => (self.labels.iter().zip(steps))
                .map(|(label, seconds)| PassTiming::timed(label.clone(), &seconds))
                .collect(),
            false => Vec::new(),
        };
        let Finished {
            diagnostics,
            reservoirs,
        } = self.finish()?;
        Ok(Run {
            frames: images,
            frames_rendered: rendered,
            timings,
            diagnostics,
            nan_count,
            reservoirs,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vulkan::testing::backend_or_skip;

    /// `bumpy` at 24 × 18 and the hybrid preset, whose frames depend on the previous frame's
    /// reservoirs (temporal reuse) and G-buffer.
    fn setting() -> (Scene, Preset) {
        let mut scene = Scene::builtin("bumpy").unwrap();
        scene.camera = scene.camera.with_resolution(24, 18);
        (scene, Preset::named("hybrid").unwrap())
    }

    fn config(seed: u64, frames: u32) -> RunConfig {
        RunConfig {
            seed,
            frames,
            collect_diagnostics: false,
        }
    }

    /// Two CPU streams asked for frames in turn keep their own state: each one's frames are
    /// bit for bit the frames of a run of its seed, and a frame's index and step timings are
    /// its own.
    #[test]
    fn interleaved_streams_keep_their_own_state() {
        const FRAMES: u32 = 4;
        let (scene, preset) = setting();
        let (one, two) = (config(1, FRAMES), config(2, FRAMES));
        let mut streams = [
            Stream::new(&Backend::Cpu, &scene, &preset, &one).unwrap(),
            Stream::new(&Backend::Cpu, &scene, &preset, &two).unwrap(),
        ];
        let runs = [
            Backend::Cpu.run(&scene, &preset, &one).unwrap(),
            Backend::Cpu.run(&scene, &preset, &two).unwrap(),
        ];
        assert_ne!(runs[0].frames[1].bits(), runs[1].frames[1].bits());
        for f in 0..FRAMES {
            for (stream, run) in streams.iter_mut().zip(&runs) {
                let frame = stream.frame().unwrap();
                assert_eq!(frame.index, f);
                assert_eq!(frame.steps.len(), stream.labels().len());
                assert_eq!(
                    frame.image.bits(),
                    run.frames[f as usize].bits(),
                    "frame {f}"
                );
            }
        }
        for (stream, run) in streams.into_iter().zip(&runs) {
            assert_eq!(stream.finish().unwrap().reservoirs, run.reservoirs);
        }
    }

    /// `RunConfig::frames` does not bound a stream: asked for more frames, it renders them
    /// (the camera at its last pose) as a longer run does.
    #[test]
    fn a_stream_renders_past_its_configured_frames() {
        let (scene, preset) = setting();
        let run = Backend::Cpu.run(&scene, &preset, &config(3, 20)).unwrap();
        let short = config(3, 2);
        let mut stream = Stream::new(&Backend::Cpu, &scene, &preset, &short).unwrap();
        for (f, want) in run.frames.iter().enumerate() {
            assert_eq!(
                stream.frame().unwrap().image.bits(),
                want.bits(),
                "frame {f}"
            );
        }
    }

    /// A run that keeps the last frame holds that one image, the last of a run that keeps
    /// every frame, with the same timings' labels and non-finite count.
    #[test]
    fn keeping_the_last_frame_holds_one_image() {
        let (scene, preset) = setting();
        let config = config(4, 5);
        let every = Stream::new(&Backend::Cpu, &scene, &preset, &config)
            .and_then(|s| s.run(5, Keep::Every))
            .unwrap();
        let last = Stream::new(&Backend::Cpu, &scene, &preset, &config)
            .and_then(|s| s.run(5, Keep::Last))
            .unwrap();
        assert_eq!((every.frames.len(), last.frames.len()), (5, 1));
        assert_eq!(last.frames[0].bits(), every.frames[4].bits());
        let labels = |run: &Run| {
            run.timings
                .iter()
                .map(|t| t.label.clone())
                .collect::<Vec<_>>()
        };
        assert_eq!(labels(&last), labels(&every));
        assert_eq!(last.nan_count, every.nan_count);
        assert_eq!(last.reservoirs, every.reservoirs);
    }

    /// A run stopped once `stop` says yes ends with the frames rendered so far: asked to stop
    /// after 3 of 8 frames, it has rendered 3, keeps the third bit for bit as a whole run's
    /// frame 2, and ends with a 3-frame run's reservoirs. Control: a `stop` that never says
    /// yes renders all 8, and one that says yes at once still renders the first frame.
    #[test]
    fn a_stopped_run_keeps_the_frames_rendered_so_far() {
        let (scene, preset) = setting();
        let whole = Backend::Cpu.run(&scene, &preset, &config(8, 8)).unwrap();
        let three = Backend::Cpu.run(&scene, &preset, &config(8, 3)).unwrap();
        let stopped_after = |n: u32| {
            let asked = std::cell::Cell::new(0);
            let stop = || {
                asked.set(asked.get() + 1);
                asked.get() > n
            };
            Stream::new(&Backend::Cpu, &scene, &preset, &config(8, 8))
                .and_then(|s| s.run_until(8, Keep::Last, &stop))
                .unwrap()
        };
        // `stop` is first asked before the second frame.
        let stopped = stopped_after(2);
        assert_eq!((stopped.frames_rendered, stopped.frames.len()), (3, 1));
        assert_eq!(stopped.frames[0].bits(), whole.frames[2].bits());
        assert_eq!(stopped.reservoirs, three.reservoirs);
        assert_eq!(stopped.nan_count, three.nan_count);
        let never = Stream::new(&Backend::Cpu, &scene, &preset, &config(8, 8))
            .and_then(|s| s.run_until(8, Keep::Last, &|| false))
            .unwrap();
        assert_eq!(never.frames_rendered, 8);
        assert_eq!(never.frames[0].bits(), whole.frames[7].bits());
        assert_eq!(stopped_after(0).frames_rendered, 1);
    }

    /// The poses of a trajectory, four frames of the bumpy camera's path apart.
    fn poses(scene: &Scene, count: u32) -> Vec<Pose> {
        (0..count).map(|f| scene.camera.pose(4 * f % 16)).collect()
    }

    /// `scene` on the trajectory of `poses`.
    fn on_trajectory(scene: &Scene, poses: &[Pose]) -> Scene {
        let mut replay = scene.clone();
        replay.camera = scene.camera.with_trajectory(&sss::scene::Trajectory {
            vfov: None,
            poses: poses.to_vec(),
        });
        replay
    }

    /// A live stream flown pose by pose renders, bit for bit, the frames of a run on the
    /// trajectory of the same poses (the replay of a viewer's recording), and its temporal
    /// history is carried while the camera moves: the frames' mean confidence grows past the
    /// first frame's. Control: a stream started again at every pose stays at the first frame's
    /// confidence.
    #[test]
    fn a_live_stream_flown_pose_by_pose_is_the_run_of_its_trajectory() {
        let (scene, preset) = setting();
        let poses = poses(&scene, 4);
        let replay = on_trajectory(&scene, &poses);
        let run = Backend::Cpu
            .run(&replay, &preset, &config(6, poses.len() as u32))
            .unwrap();
        let mut live = Stream::live(&Backend::Cpu, scene.clone(), &preset, &config(6, 1)).unwrap();
        let mut confidence = Vec::new();
        for (f, pose) in poses.iter().enumerate() {
            let frame = live.frame_at(*pose).unwrap();
            assert_eq!(frame.image.bits(), run.frames[f].bits(), "frame {f}");
            confidence.push(frame.confidence);
        }
        let restarted = Stream::live(&Backend::Cpu, replay, &preset, &config(6, 1))
            .and_then(|mut s| s.frame_at(poses[3]))
            .unwrap();
        eprintln!(
            "confidence: {confidence:?}; restarted at the last pose {}",
            restarted.confidence
        );
        assert!(confidence[3] > 1.5 * confidence[0], "{confidence:?}");
        assert!(restarted.confidence < 1.1 * confidence[0], "control");
    }

    /// On a Vulkan device a live stream flown pose by pose gives the frames of a run on their
    /// trajectory, bit for bit, while other work uses the renderer between its frames; after
    /// the renderer uploads another scene its next frame is a one-line error.
    #[test]
    fn a_live_vulkan_stream_shares_its_renderer_between_frames() {
        let test = "a_live_vulkan_stream_shares_its_renderer_between_frames";
        let Some(backend) = backend_or_skip(test) else {
            return;
        };
        let (scene, preset) = setting();
        let poses = poses(&scene, 3);
        let replay = on_trajectory(&scene, &poses);
        let run = backend.run(&replay, &preset, &config(7, 3)).unwrap();
        let mut live = Stream::live(&backend, scene.clone(), &preset, &config(7, 1)).unwrap();
        for (f, pose) in poses.iter().enumerate() {
            assert_eq!(
                live.frame_at(*pose).unwrap().image.bits(),
                run.frames[f].bits()
            );
            // Between frames the backend renders another preset on the same scene.
            backend
                .run(
                    &scene,
                    &Preset::named("reconnection").unwrap(),
                    &config(1, 1),
                )
                .unwrap();
        }
        let mut other = Scene::builtin("slab").unwrap();
        other.camera = other.camera.with_resolution(24, 18);
        backend.run(&other, &preset, &config(1, 1)).unwrap();
        let error = live.frame_at(poses[0]).unwrap_err().to_string();
        assert!(error.contains("another scene"), "{error}");
    }

    /// On a Vulkan device a stream driven frame by frame gives the frames of `Backend::run`
    /// with the same seed, bit for bit, and holds the device's buffers between frames (a
    /// stream dropped early leaves the renderer usable).
    #[test]
    fn a_vulkan_stream_gives_the_frames_of_a_run() {
        let Some(backend) = backend_or_skip("a_vulkan_stream_gives_the_frames_of_a_run") else {
            return;
        };
        let (scene, preset) = setting();
        let config = config(5, 3);
        let run = backend.run(&scene, &preset, &config).unwrap();
        {
            let mut early = Stream::new(&backend, &scene, &preset, &config).unwrap();
            early.frame().unwrap();
        }
        let mut stream = Stream::new(&backend, &scene, &preset, &config).unwrap();
        for (f, want) in run.frames.iter().enumerate() {
            let frame = stream.frame().unwrap();
            assert_eq!(frame.index, f as u32);
            assert_eq!(frame.image.bits(), want.bits(), "frame {f}");
        }
        assert_eq!(stream.finish().unwrap().reservoirs, run.reservoirs);
    }
}
