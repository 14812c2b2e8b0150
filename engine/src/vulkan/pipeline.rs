//! The ReSTIR frame pipeline on the GPU (DESIGN §6): the twin of `cpu::run`.
//!
//! A [`Renderer`] holds the [`Context`], the compiled kernels and the uploaded [`GpuScene`]
//! across runs (creating a pipeline on lavapipe compiles LLVM code: it is done once per shader).
//! A run allocates its buffers once and records each distinct frame — G-buffer, the preset's
//! passes, shade, then read-back copies — into a command buffer once; frames are re-submitted.
//! Frames differ only in which buffers play "current" and "previous" (the G-buffer alternates,
//! the final reservoir buffer rotates among three), so a run records at most six command
//! buffers. `FrameParams` is copied from a staging buffer at the start of every frame, and a
//! timestamp pair around each pass gives [`Run::timings`] in GPU seconds.

use std::collections::HashMap;
use std::collections::hash_map::Entry;

use ash::vk;
use bytemuck::{Pod, Zeroable};
use restir::resample::ResampleError;
use restir::reservoir::InvalidCandidate;
use sss::scene::Scene;

use super::compute::bind_buffers;
use super::device::Context;
use super::error::{VulkanError, api};
use super::memory::{Allocation, Buffer, Placement, barrier};
use super::random_walk::{RANDOM_WALK, render_random_walk, scene_media};
use super::scene::{FrameParams, GBUFFER, GpuPixel, GpuScene};
use super::shaders::Shader;
use super::timing::Timestamps;
use super::{FrameInput, Kernel, PT, SHADE, groups_for, render_pt};
use crate::candidates::ProbeCounts;
use crate::diagnostics::{Counters, HybridChoice};
use crate::image::Image;
use crate::layout::PixelReservoir;
use crate::preset::{PassSpec, Preset, ShiftKind};
use crate::reuse::ShiftCounts;
use crate::{PassTiming, PipelineError, Run, RunConfig};

/// `pass_candidates.glsl`: scene (0–8), G-buffer, reservoirs out, diag out.
pub const CANDIDATES: Shader = Shader::new("pass_candidates", 12, 32);
/// `pass_temporal.glsl`: scene, G-buffer, reservoirs in, previous G-buffer, previous
/// reservoirs, reservoirs out, diag out.
pub const TEMPORAL: Shader = Shader::new("pass_temporal", 15, 32);
/// `pass_spatial.glsl`: scene, G-buffer, reservoirs in, reservoirs out, diag out.
pub const SPATIAL: Shader = Shader::new("pass_spatial", 13, 32);

/// Push constants of every pass shader (contract: 32 bytes, std430 scalars).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct PassParams {
    /// The pass's index in the preset (the stream key's `pass`); the pass count for shade.
    pub pass: u32,
    /// Index in [`ShiftKind::ALL`].
    pub shift: u32,
    /// [`crate::MisKind`] in declaration order.
    pub mis: u32,
    pub neighbours: u32,
    /// ≤ 0: no cap (a spatial pass's `None`).
    pub confidence_cap: f32,
    pub bssrdf_samples: u32,
    pub shared_light: u32,
    pub collect_diagnostics: u32,
}

impl PassParams {
    /// The push constants of pass `pass` of a preset (`spec = None`: G-buffer or shade).
    pub fn new(pass: u32, spec: Option<&PassSpec>, collect_diagnostics: bool) -> PassParams {
        let base = PassParams {
            pass,
            collect_diagnostics: collect_diagnostics as u32,
            ..PassParams::default()
        };
        let shift_index =
            |s: ShiftKind| ShiftKind::ALL.iter().position(|&k| k == s).unwrap_or(0) as u32;
        match spec {
            None => base,
            Some(&PassSpec::Candidates {
                bssrdf_samples,
                shared_light,
            }) => PassParams {
                bssrdf_samples,
                shared_light: shared_light as u32,
                ..base
            },
            Some(&PassSpec::Temporal {
                shift,
                mis,
                confidence_cap,
            }) => PassParams {
                shift: shift_index(shift),
                mis: mis as u32,
                confidence_cap,
                ..base
            },
            Some(&PassSpec::Spatial {
                shift,
                mis,
                neighbours,
                confidence_cap,
            }) => PassParams {
                shift: shift_index(shift),
                mis: mis as u32,
                neighbours,
                confidence_cap: confidence_cap.unwrap_or(0.0),
                ..base
            },
        }
    }
}

/// The diag `w` of a pixel whose loops the device cut short (`restir/glsl/loop_budget.glsl`).
pub const LOOP_BUDGET_CUT: u32 = 0xFF;
/// The diag `w` of a pixel with a BSSRDF probe of more than [`KEPT_HITS`] hits
/// (`pass_candidates.glsl`).
pub const HIT_OVERFLOW: u32 = 0xFE;
/// Hits per probe that the pass shaders keep (their `BVH_MAX_HITS`).
pub const KEPT_HITS: u32 = 16;

/// Decodes a pass's per-pixel error code (diag `w`; 0 = none, [`LOOP_BUDGET_CUT`] and
/// [`HIT_OVERFLOW`] are handled before). Low byte: 1–4 an
/// [`InvalidCandidate`] (`Weight`, `Target`, `Confidence`, `Ucw`), 5 `TooManyDomains`, 6
/// `BadPdf`, 7 `BadJacobian`; bits 8–15: the domain index `source` of a resampling error. The
/// offending value is not carried (it reads as NaN); a code outside this table is reported as
/// a `Weight(NaN)` of the pass.
pub fn decode_error(code: u32) -> ResampleError {
    let source = ((code >> 8) & 0xff) as usize;
    let nan = f32::NAN;
    let candidate = |kind| match kind {
        2 => InvalidCandidate::Target(nan),
        3 => InvalidCandidate::Confidence(nan),
        4 => InvalidCandidate::Ucw(nan),
        _ => InvalidCandidate::Weight(nan),
    };
    match code & 0xff {
        5 => ResampleError::TooManyDomains(source),
        6 => ResampleError::BadPdf(nan),
        7 => ResampleError::BadJacobian {
            source,
            jacobian: nan,
        },
        kind => ResampleError::Candidate {
            source,
            error: candidate(kind),
        },
    }
}

/// A Vulkan device with its kernels and the last uploaded scene, reused across runs.
pub struct Renderer {
    context: Context,
    kernels: HashMap<&'static str, Kernel>,
    /// The uploaded scene and the fingerprint of the [`Scene`] it came from.
    scene: Option<(u64, GpuScene)>,
}

impl Renderer {
    /// A renderer on `context`; kernels are built on first use.
    pub fn new(context: Context) -> Renderer {
        Renderer {
            context,
            kernels: HashMap::new(),
            scene: None,
        }
    }

    /// The device the renderer runs on.
    pub fn context(&self) -> &Context {
        &self.context
    }

    /// Builds (once) the kernels of `shaders`.
    pub fn prepare(&mut self, shaders: &[Shader]) -> Result<(), VulkanError> {
        for &shader in shaders {
            if let Entry::Vacant(slot) = self.kernels.entry(shader.name) {
                slot.insert(Kernel::for_shader(&self.context, shader)?);
            }
        }
        Ok(())
    }

    /// Uploads `scene` unless the cached upload came from an identical scene (cameras aside:
    /// the camera travels in [`FrameParams`]).
    pub fn upload(&mut self, scene: &Scene) -> Result<(), VulkanError> {
        let key = fingerprint(scene);
        if self.scene.as_ref().is_none_or(|(k, _)| *k != key) {
            self.scene = None;
            self.scene = Some((key, GpuScene::upload(&self.context, scene)?));
        }
        Ok(())
    }

    /// The uploaded scene (after [`Renderer::upload`]).
    pub fn gpu_scene(&self) -> Result<&GpuScene, VulkanError> {
        self.scene
            .as_ref()
            .map(|(_, s)| s)
            .ok_or_else(|| VulkanError::Binding("no scene was uploaded".into()))
    }

    /// The context, a built kernel and the uploaded scene, borrowed together.
    pub fn parts(
        &mut self,
        shader: Shader,
    ) -> Result<(&mut Context, &Kernel, &GpuScene), VulkanError> {
        self.prepare(&[shader])?;
        let scene = self
            .scene
            .as_ref()
            .map(|(_, s)| s)
            .ok_or_else(|| VulkanError::Binding("no scene was uploaded".into()))?;
        Ok((&mut self.context, &self.kernels[shader.name], scene))
    }

    /// The G-buffer of `frame` of `scene`'s trajectory on the device (uploading the scene if
    /// needed), with the frame's parameter buffer: the input of the memoryless methods.
    pub fn gbuffer(
        &mut self,
        scene: &Scene,
        frame: u32,
        seed: u64,
    ) -> Result<(Buffer, Buffer), VulkanError> {
        self.upload(scene)?;
        let n = pixel_count(scene);
        let params = FrameParams::new(scene, frame, frame.checked_sub(1), seed);
        let params = Buffer::from_slice(&self.context, &[params])?;
        let gpixels = Buffer::zeroed(&self.context, n * size_of::<GpuPixel>())?;
        let (context, kernel, gpu) = self.parts(GBUFFER)?;
        let mut buffers: Vec<&Buffer> = gpu.buffers().to_vec();
        buffers.extend([&params, &gpixels]);
        let push = PassParams::new(0, None, false);
        context.dispatch(
            kernel,
            &buffers,
            bytemuck::bytes_of(&push),
            [groups_for(n as u32, GBUFFER.local_size), 1, 1],
        )?;
        Ok((gpixels, params))
    }

    /// The `pt:spp` method at `frame`: the image and the samples left out of the means.
    pub fn pt(
        &mut self,
        scene: &Scene,
        frame: u32,
        seed: u64,
        spp: u32,
    ) -> Result<(Image, u64), VulkanError> {
        let (gbuffer, params) = self.gbuffer(scene, frame, seed)?;
        let (context, kernel, gpu) = self.parts(PT)?;
        let input = FrameInput {
            scene: gpu,
            params: &params,
            gbuffer: &gbuffer,
            width: scene.camera.width(),
            height: scene.camera.height(),
        };
        let out = render_pt(context, kernel, &input, spp)?;
        Ok((out.image, out.left_out))
    }

    /// The `random-walk:spp` method at `frame`: the image and the samples left out.
    pub fn random_walk(
        &mut self,
        scene: &Scene,
        frame: u32,
        seed: u64,
        spp: u32,
    ) -> Result<(Image, u64), PipelineError> {
        let media = scene_media(scene)?;
        let (gbuffer, params) = self.gbuffer(scene, frame, seed)?;
        let (context, kernel, gpu) = self.parts(RANDOM_WALK)?;
        let input = FrameInput {
            scene: gpu,
            params: &params,
            gbuffer: &gbuffer,
            width: scene.camera.width(),
            height: scene.camera.height(),
        };
        let out = render_random_walk(context, kernel, &input, &media, spp)?;
        if out.cut > 0 {
            return Err(PipelineError::Vulkan(VulkanError::LoopsCut {
                shader: RANDOM_WALK.name,
                count: out.cut,
            }));
        }
        Ok((out.image.image, out.image.left_out))
    }

    /// Renders `config.frames` frames of `scene` with `preset` (validated by the caller) on
    /// the device: the GPU twin of [`crate::run`]. `Run::timings` are GPU seconds from the
    /// timestamps; they are empty on a queue that writes no timestamps.
    pub fn run(
        &mut self,
        scene: &Scene,
        preset: &Preset,
        config: &RunConfig,
    ) -> Result<Run, PipelineError> {
        let mut shaders = vec![GBUFFER, SHADE];
        shaders.extend(preset.passes.iter().map(shader_of));
        self.prepare(&shaders)?;
        self.upload(scene)?;
        let gpu = self.gpu_scene()?;
        FrameRun::new(&self.context, gpu, &self.kernels, scene, preset, config)?.run(scene)
    }
}

/// The shader of a pass.
fn shader_of(pass: &PassSpec) -> Shader {
    match pass {
        PassSpec::Candidates { .. } => CANDIDATES,
        PassSpec::Temporal { .. } => TEMPORAL,
        PassSpec::Spatial { .. } => SPATIAL,
    }
}

fn pixel_count(scene: &Scene) -> usize {
    scene.camera.width() as usize * scene.camera.height() as usize
}

/// FNV-1a over what [`GpuScene`] is built from: materials, objects, lights, every triangle's
/// vertices, shading normals and object. Two scenes with the same fingerprint upload the same
/// buffers.
fn fingerprint(scene: &Scene) -> u64 {
    let mut hash = 0xcbf2_9ce4_8422_2325u64;
    let mut eat = |bytes: &[u8]| {
        for &b in bytes {
            hash = (hash ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3);
        }
    };
    eat(format!("{:?}{:?}{:?}", scene.materials, scene.objects, scene.lights).as_bytes());
    let geometry = &scene.geometry;
    for prim in 0..geometry.triangle_count() {
        for v in geometry.vertices(prim) {
            eat(bytemuck::bytes_of(&v.to_array()));
        }
        for bary in [[0.0f32, 0.0], [1.0, 0.0], [0.0, 1.0]] {
            let n = geometry.shading_normal(prim, glam::Vec2::from_array(bary));
            eat(bytemuck::bytes_of(&n.to_array()));
        }
        eat(&geometry.object_of(prim).to_le_bytes());
    }
    hash
}

/// Bytes per pixel of a diag buffer (`uvec4`) and of the shaded image (`vec4`).
const TEXEL: usize = 16;

/// One run's buffers, recorded frames and read-back staging.
struct FrameRun<'a> {
    context: &'a Context,
    scene: &'a GpuScene,
    kernels: &'a HashMap<&'static str, Kernel>,
    preset: &'a Preset,
    config: &'a RunConfig,
    width: u32,
    height: u32,
    params: Buffer,
    params_staging: Allocation,
    gpixels: [Buffer; 2],
    reservoirs: [Buffer; 3],
    /// One per preset pass.
    diags: Vec<Buffer>,
    image: Buffer,
    /// Image, then each pass's diag, then the final reservoirs.
    readback: Allocation,
    descriptor_pool: vk::DescriptorPool,
    /// Recorded frames by (current G-buffer, previous final reservoir buffer).
    recorded: HashMap<(usize, usize), Recorded>,
}

/// A recorded frame.
struct Recorded {
    cb: vk::CommandBuffer,
    timestamps: Option<Timestamps>,
    /// The reservoir buffer holding the frame's final reservoirs.
    final_reservoirs: usize,
}

impl<'a> FrameRun<'a> {
    fn new(
        context: &'a Context,
        scene_gpu: &'a GpuScene,
        kernels: &'a HashMap<&'static str, Kernel>,
        scene: &Scene,
        preset: &'a Preset,
        config: &'a RunConfig,
    ) -> Result<FrameRun<'a>, VulkanError> {
        let (width, height) = (scene.camera.width(), scene.camera.height());
        let n = width as usize * height as usize;
        let zeroed = |bytes| Buffer::zeroed(context, bytes);
        let reservoir_bytes = n * PixelReservoir::BYTES;
        let passes = preset.passes.len();
        let per_frame = 6 * (passes + 2) as u32;
        let sizes = [vk::DescriptorPoolSize::default()
            .ty(vk::DescriptorType::STORAGE_BUFFER)
            .descriptor_count(per_frame * 16)];
        // SAFETY: valid create info on a live device; destroyed in `Drop`.
        let descriptor_pool = unsafe {
            context.shared.device.create_descriptor_pool(
                &vk::DescriptorPoolCreateInfo::default()
                    .max_sets(per_frame)
                    .pool_sizes(&sizes),
                None,
            )
        }
        .map_err(api("vkCreateDescriptorPool"))?;
        let mut run = FrameRun {
            context,
            scene: scene_gpu,
            kernels,
            preset,
            config,
            width,
            height,
            params: zeroed(size_of::<FrameParams>())?,
            params_staging: Allocation::new(
                &context.shared,
                size_of::<FrameParams>() as u64,
                vk::BufferUsageFlags::TRANSFER_SRC,
                Placement::Host,
            )?,
            gpixels: [
                zeroed(n * size_of::<GpuPixel>())?,
                zeroed(n * size_of::<GpuPixel>())?,
            ],
            reservoirs: [
                zeroed(reservoir_bytes)?,
                zeroed(reservoir_bytes)?,
                zeroed(reservoir_bytes)?,
            ],
            diags: Vec::new(),
            image: zeroed(n * TEXEL)?,
            readback: Allocation::new(
                &context.shared,
                ((passes + 1) * n * TEXEL + reservoir_bytes) as u64,
                vk::BufferUsageFlags::TRANSFER_DST,
                Placement::Host,
            )?,
            descriptor_pool,
            recorded: HashMap::new(),
        };
        run.diags = (0..passes)
            .map(|_| zeroed(n * TEXEL))
            .collect::<Result<_, _>>()?;
        Ok(run)
    }

    fn pixels(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// Runs every frame and assembles the [`Run`].
    fn run(&mut self, scene: &Scene) -> Result<Run, PipelineError> {
        let n = self.pixels();
        let config = *self.config;
        let passes = self.preset.passes.len();
        let reuse_labels = self
            .preset
            .passes
            .iter()
            .filter(|p| p.shift().is_some())
            .map(PassSpec::label);
        let mut counters = config
            .collect_diagnostics
            .then(|| Counters::new(self.width, self.height, reuse_labels.collect()));
        let mut seconds = vec![0.0f64; passes + 2];
        let mut timed = true;
        let mut frames = Vec::with_capacity(config.frames as usize);
        let mut nan_count = 0;
        let mut previous_final = 2;
        for frame in 0..config.frames {
            let params = FrameParams::new(scene, frame, frame.checked_sub(1), config.seed);
            self.params_staging
                .mapped_mut()
                .ok_or(VulkanError::NoMemoryType)?[..size_of::<FrameParams>()]
                .copy_from_slice(bytemuck::bytes_of(&params));
            let key = ((frame % 2) as usize, previous_final);
            if !self.recorded.contains_key(&key) {
                let recorded = self.record(key)?;
                self.recorded.insert(key, recorded);
            }
            let recorded = &self.recorded[&key];
            {
                let submit = self.context.shared.lock();
                // SAFETY: the command buffer was recorded by `record`; the lock is held.
                unsafe {
                    super::device::submit_and_wait(
                        &self.context.shared.device,
                        submit.queue,
                        recorded.cb,
                    )
                }?;
            }
            match &recorded.timestamps {
                Some(t) => {
                    for (s, t) in seconds.iter_mut().zip(t.seconds()?) {
                        *s += t;
                    }
                }
                None => timed = false,
            }
            previous_final = recorded.final_reservoirs;
            let bytes = self.readback.mapped().ok_or(VulkanError::NoMemoryType)?;
            let texels: &[[f32; 4]] = bytemuck::cast_slice(&bytes[..n * TEXEL]);
            nan_count += texels.iter().filter(|t| t[3] != 0.0).count() as u64;
            frames.push(Image {
                width: self.width,
                height: self.height,
                pixels: texels
                    .iter()
                    .map(|t| glam::Vec3::new(t[0], t[1], t[2]))
                    .collect(),
            });
            let mut reuse_pass = 0;
            for (index, pass) in self.preset.passes.iter().enumerate() {
                let start = (index + 1) * n * TEXEL;
                let diag: &[[u32; 4]] = bytemuck::cast_slice(&bytes[start..start + n * TEXEL]);
                let pixels_with = |code| diag.iter().filter(|d| d[3] == code).count() as u64;
                let shader = shader_of(pass).name;
                match (pixels_with(LOOP_BUDGET_CUT), pixels_with(HIT_OVERFLOW)) {
                    (0, 0) => {}
                    (0, count) => {
                        return Err(PipelineError::Vulkan(VulkanError::TooManyHits {
                            shader,
                            kept: KEPT_HITS,
                            count,
                        }));
                    }
                    (count, _) => {
                        return Err(PipelineError::Vulkan(VulkanError::LoopsCut {
                            shader,
                            count,
                        }));
                    }
                }
                if let Some(pixel) = diag.iter().position(|d| d[3] != 0) {
                    let error = decode_error(diag[pixel][3]);
                    let pixel = pixel as u32;
                    return Err(match (pass, error) {
                        (PassSpec::Candidates { .. }, ResampleError::Candidate { error, .. }) => {
                            PipelineError::Candidate {
                                frame,
                                pixel,
                                error,
                            }
                        }
                        (_, error) => PipelineError::Resample {
                            frame,
                            pass: index,
                            pixel,
                            error,
                        },
                    });
                }
                let Some(counters) = &mut counters else {
                    continue;
                };
                if pass.shift().is_some() {
                    let shifts: Vec<ShiftCounts> = diag
                        .iter()
                        .map(|d| ShiftCounts {
                            shifted: d[0],
                            failed: d[1],
                            improved: d[2],
                        })
                        .collect();
                    counters.add_shifts(reuse_pass, &shifts);
                    reuse_pass += 1;
                } else {
                    let probes: Vec<_> = diag
                        .iter()
                        .map(|d| {
                            let choice = match d[2] {
                                1 => HybridChoice::Reconnection,
                                2 => HybridChoice::Delayed,
                                _ => HybridChoice::None,
                            };
                            (
                                ProbeCounts {
                                    probes: d[0],
                                    hits: d[1],
                                },
                                choice,
                            )
                        })
                        .collect();
                    counters.add_candidates(&probes);
                }
            }
        }
        let bytes = self.readback.mapped().ok_or(VulkanError::NoMemoryType)?;
        let start = (passes + 1) * n * TEXEL;
        let reservoirs: &[PixelReservoir] =
            bytemuck::cast_slice(&bytes[start..start + n * PixelReservoir::BYTES]);
        let timings = if timed {
            std::iter::once("gbuffer".to_string())
                .chain(self.preset.passes.iter().map(PassSpec::label))
                .chain(std::iter::once("shade".to_string()))
                .zip(seconds)
                .map(|(label, seconds)| PassTiming { label, seconds })
                .collect()
        } else {
            Vec::new()
        };
        Ok(Run {
            frames,
            timings,
            diagnostics: counters.map(|c| c.finish()),
            nan_count,
            reservoirs: reservoirs.to_vec(),
        })
    }

    /// Records the frame whose current G-buffer is `gpixels[current]` and whose previous final
    /// reservoirs are `reservoirs[previous]`.
    fn record(&self, (current, previous): (usize, usize)) -> Result<Recorded, VulkanError> {
        let device = &self.context.shared.device;
        let n = self.pixels();
        let passes = self.preset.passes.len();
        let timestamps = Timestamps::new(self.context, passes as u32 + 2)?;
        let cb = {
            let submit = self.context.shared.lock();
            // SAFETY: allocation from the pool while its lock is held.
            unsafe {
                device.allocate_command_buffers(
                    &vk::CommandBufferAllocateInfo::default()
                        .command_pool(submit.command_pool)
                        .level(vk::CommandBufferLevel::PRIMARY)
                        .command_buffer_count(1),
                )
            }
            .map_err(api("vkAllocateCommandBuffers"))?[0]
        };
        // The command buffer is freed with the pool's other buffers in `Drop` from here on.
        let mut recorded = Recorded {
            cb,
            timestamps,
            final_reservoirs: previous,
        };
        let work: Vec<usize> = (0..3).filter(|&i| i != previous).collect();
        let gcur = &self.gpixels[current];
        let gprev = &self.gpixels[1 - current];
        let groups = groups_for(n as u32, 64);
        // SAFETY: `cb` is recorded here from live objects of this run, which outlive it.
        unsafe {
            device
                .begin_command_buffer(cb, &vk::CommandBufferBeginInfo::default())
                .map_err(api("vkBeginCommandBuffer"))?;
            if let Some(t) = &recorded.timestamps {
                t.reset(cb);
            }
            // The previous submission's transfers are done (its fence was waited on); this
            // orders them before this frame's writes all the same.
            barrier(
                device,
                cb,
                (
                    vk::PipelineStageFlags::ALL_COMMANDS,
                    vk::AccessFlags::MEMORY_WRITE,
                ),
                (
                    vk::PipelineStageFlags::ALL_COMMANDS,
                    vk::AccessFlags::MEMORY_READ | vk::AccessFlags::MEMORY_WRITE,
                ),
            );
            let region = [vk::BufferCopy::default().size(size_of::<FrameParams>() as u64)];
            device.cmd_copy_buffer(
                cb,
                self.params_staging.buffer,
                self.params.allocation.buffer,
                &region,
            );
            barrier(
                device,
                cb,
                (
                    vk::PipelineStageFlags::TRANSFER,
                    vk::AccessFlags::TRANSFER_WRITE,
                ),
                (
                    vk::PipelineStageFlags::COMPUTE_SHADER,
                    vk::AccessFlags::SHADER_READ,
                ),
            );
            let push = PassParams::new(0, None, false);
            self.dispatch(
                cb,
                &recorded,
                0,
                GBUFFER,
                &self.bindings(&[gcur]),
                &push,
                groups,
            )?;
            let mut input = previous;
            for (index, pass) in self.preset.passes.iter().enumerate() {
                let output = work[index % 2];
                let diag = &self.diags[index];
                let rin = &self.reservoirs[input];
                let rout = &self.reservoirs[output];
                let rprev = &self.reservoirs[previous];
                let buffers = match pass {
                    PassSpec::Candidates { .. } => self.bindings(&[gcur, rout, diag]),
                    PassSpec::Temporal { .. } => {
                        self.bindings(&[gcur, rin, gprev, rprev, rout, diag])
                    }
                    PassSpec::Spatial { .. } => self.bindings(&[gcur, rin, rout, diag]),
                };
                let push =
                    PassParams::new(index as u32, Some(pass), self.config.collect_diagnostics);
                self.dispatch(
                    cb,
                    &recorded,
                    index as u32 + 1,
                    shader_of(pass),
                    &buffers,
                    &push,
                    groups,
                )?;
                input = output;
            }
            recorded.final_reservoirs = input;
            let push = PassParams::new(passes as u32, None, false);
            let buffers = self.bindings(&[gcur, &self.reservoirs[input], &self.image]);
            self.dispatch(
                cb,
                &recorded,
                passes as u32 + 1,
                SHADE,
                &buffers,
                &push,
                groups,
            )?;
            barrier(
                device,
                cb,
                (
                    vk::PipelineStageFlags::COMPUTE_SHADER,
                    vk::AccessFlags::SHADER_WRITE,
                ),
                (
                    vk::PipelineStageFlags::TRANSFER,
                    vk::AccessFlags::TRANSFER_READ,
                ),
            );
            let texels = (n * TEXEL) as u64;
            let copy = |src: &Buffer, offset: u64, size: u64| {
                let region = [vk::BufferCopy::default().dst_offset(offset).size(size)];
                device.cmd_copy_buffer(cb, src.allocation.buffer, self.readback.buffer, &region);
            };
            copy(&self.image, 0, texels);
            for (index, diag) in self.diags.iter().enumerate() {
                copy(diag, (index as u64 + 1) * texels, texels);
            }
            copy(
                &self.reservoirs[input],
                (passes as u64 + 1) * texels,
                (n * PixelReservoir::BYTES) as u64,
            );
            barrier(
                device,
                cb,
                (
                    vk::PipelineStageFlags::TRANSFER,
                    vk::AccessFlags::TRANSFER_WRITE,
                ),
                (vk::PipelineStageFlags::HOST, vk::AccessFlags::HOST_READ),
            );
            device
                .end_command_buffer(cb)
                .map_err(api("vkEndCommandBuffer"))?;
        }
        Ok(recorded)
    }

    /// The scene's buffers (0–8: its eight, then `FrameParams`), then `rest`.
    fn bindings<'b>(&'b self, rest: &[&'b Buffer]) -> Vec<&'b Buffer> {
        let mut all: Vec<&Buffer> = self.scene.buffers().to_vec();
        all.push(&self.params);
        all.extend_from_slice(rest);
        all
    }

    /// Records one timed pass: bind, push, dispatch, then a barrier for the next pass.
    #[allow(clippy::too_many_arguments)]
    fn dispatch(
        &self,
        cb: vk::CommandBuffer,
        recorded: &Recorded,
        section: u32,
        shader: Shader,
        buffers: &[&Buffer],
        push: &PassParams,
        groups: u32,
    ) -> Result<(), VulkanError> {
        let kernel = self
            .kernels
            .get(shader.name)
            .ok_or_else(|| VulkanError::UnknownShader(shader.name.to_string()))?;
        if buffers.len() != kernel.buffers as usize
            || kernel.push_bytes as usize != size_of::<PassParams>()
        {
            return Err(VulkanError::Binding(format!(
                "{} takes {} buffers and {} push bytes, got {} and {}",
                shader.name,
                kernel.buffers,
                kernel.push_bytes,
                buffers.len(),
                size_of::<PassParams>()
            )));
        }
        let device = &self.context.shared.device;
        // SAFETY: the set is allocated from this run's pool with the kernel's layout and
        // written with live buffers; `cb` is recording.
        unsafe {
            let set = bind_buffers(device, self.descriptor_pool, kernel, buffers)?;
            if let Some(t) = &recorded.timestamps {
                t.begin(cb, section);
            }
            device.cmd_bind_pipeline(cb, vk::PipelineBindPoint::COMPUTE, kernel.pipeline);
            device.cmd_bind_descriptor_sets(
                cb,
                vk::PipelineBindPoint::COMPUTE,
                kernel.layout,
                0,
                &[set],
                &[],
            );
            device.cmd_push_constants(
                cb,
                kernel.layout,
                vk::ShaderStageFlags::COMPUTE,
                0,
                bytemuck::bytes_of(push),
            );
            device.cmd_dispatch(cb, groups, 1, 1);
            if let Some(t) = &recorded.timestamps {
                t.end(cb, section);
            }
            barrier(
                device,
                cb,
                (
                    vk::PipelineStageFlags::COMPUTE_SHADER,
                    vk::AccessFlags::SHADER_WRITE,
                ),
                (
                    vk::PipelineStageFlags::COMPUTE_SHADER,
                    vk::AccessFlags::SHADER_READ | vk::AccessFlags::SHADER_WRITE,
                ),
            );
        }
        Ok(())
    }
}

impl Drop for FrameRun<'_> {
    fn drop(&mut self) {
        let device = &self.context.shared.device;
        let submit = self.context.shared.lock();
        let cbs: Vec<_> = self.recorded.values().map(|r| r.cb).collect();
        // SAFETY: every submission was waited on; the pool lock is held while freeing.
        unsafe {
            if !cbs.is_empty() {
                device.free_command_buffers(submit.command_pool, &cbs);
            }
            device.destroy_descriptor_pool(self.descriptor_pool, None);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::preset::MisKind;
    use std::mem::offset_of;

    #[test]
    fn pass_params_match_the_contract() {
        assert_eq!(size_of::<PassParams>(), 32);
        assert_eq!(offset_of!(PassParams, confidence_cap), 16);
        assert_eq!(offset_of!(PassParams, collect_diagnostics), 28);
        let spatial = PassSpec::Spatial {
            shift: ShiftKind::ALL[3],
            mis: MisKind::DefensivePairwise,
            neighbours: 4,
            confidence_cap: None,
        };
        let p = PassParams::new(2, Some(&spatial), true);
        assert_eq!((p.pass, p.shift, p.mis, p.neighbours), (2, 3, 2, 4));
        assert_eq!((p.confidence_cap, p.collect_diagnostics), (0.0, 1));
        let candidates = PassSpec::Candidates {
            bssrdf_samples: 3,
            shared_light: true,
        };
        let p = PassParams::new(0, Some(&candidates), false);
        assert_eq!((p.bssrdf_samples, p.shared_light, p.shift), (3, 1, 0));
    }

    #[test]
    fn error_codes_decode_to_the_cpu_errors() {
        assert!(matches!(
            decode_error(0x0204),
            ResampleError::Candidate {
                source: 2,
                error: InvalidCandidate::Ucw(_)
            }
        ));
        assert!(matches!(
            decode_error(0x0107),
            ResampleError::BadJacobian { source: 1, .. }
        ));
        assert!(matches!(decode_error(6), ResampleError::BadPdf(_)));
        assert!(matches!(
            decode_error(2),
            ResampleError::Candidate {
                source: 0,
                error: InvalidCandidate::Target(_)
            }
        ));
    }
}
