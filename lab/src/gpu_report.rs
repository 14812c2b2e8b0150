//! `reshift gpu-report`: one markdown file about a Vulkan device, for `docs/performance.md`.
//!
//! 1. The device: name, kind, Vulkan version, driver and the limits that bound the backend.
//! 2. Whole-run parity of every preset: `R = relMSE(GPU a, CPU a) / relMSE(CPU b, CPU a)` over
//!    two seeds; the GPU must reproduce the CPU run of its own seed far closer than another seed
//!    does, `R < 0.1` (the bound of `lab/tests/vulkan_methods.rs`: the backends differ only by
//!    float rounding and the transcendentals' last bits, which occasionally flip a resampling
//!    decision), and render no NaN.
//! 3. Time per frame of every pass of every preset (GPU timestamp queries) and of every
//!    memoryless method (wall clock around a frame: G-buffer, kernel, read-back; those kernels
//!    are not timed on the device) at each size: median and range over the frames after the
//!    first (frame 0 has no temporal history).
//! 4. `compare` on the device at equal time: every preset against `pt` scaled to the median
//!    frame time of the slowest preset at that size (`lab::compare`'s `--equal-time`).

use engine::denoise::Denoiser;
use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

use engine::vulkan::testing::rel_mse;
use engine::vulkan::{DeviceDetails, VulkanError};
use engine::{Backend, PipelineError, Preset, Run, RunConfig};
use methods::adaptive::cpu::AdaptiveParams;
use sss::integrator::pt::HitPolicy;
use sss::integrator::single_scatter::ChannelSelection;
use sss::scene::Scene;

use crate::compare::{self, Comparison, DEFAULT_BASELINE};
use crate::error::Error;
use crate::progress::Progress;
use crate::reference_cache::ReferenceSource;
use crate::report;
use crate::scenes::{LoadedScene, load_scene};
use methods::Method;

/// The parity bound on `R` (see the module comment).
pub const PARITY_BOUND: f64 = 0.1;

/// The equal-time comparison of the report.
#[derive(Clone, Debug)]
pub struct CompareSettings {
    pub size: (u32, u32),
    pub replicas: u32,
    pub frames: u32,
    /// Samples per pixel of the last frame's path-traced reference, and of one batch of it.
    pub reference_spp: u32,
    pub reference_batch_spp: u32,
    /// Folder of cached references.
    pub cache: PathBuf,
    /// Where `compare` writes its tables and images.
    pub out: PathBuf,
}

/// What the report measures.
#[derive(Clone, Debug)]
pub struct Settings {
    /// The scene: a built-in name or a `.toml` path (its camera's resolution is replaced by
    /// each size).
    pub scene: String,
    /// Resolutions of the timing table.
    pub sizes: Vec<(u32, u32)>,
    /// Frames per timed run (≥ 2: frame 0 is left out of the statistics).
    pub frames: u32,
    /// Resolution and frames of the parity runs.
    pub parity_size: (u32, u32),
    pub parity_frames: u32,
    /// `None`: no comparison.
    pub compare: Option<CompareSettings>,
}

/// A finished report.
pub struct Report {
    pub markdown: String,
    /// The presets whose parity failed (the report says so too).
    pub parity_failures: Vec<String>,
}

/// Median and range of a set of seconds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spread {
    pub median: f64,
    pub min: f64,
    pub max: f64,
}

impl Spread {
    /// `None` for no values.
    pub fn of(values: &[f64]) -> Option<Spread> {
        let mut v = values.to_vec();
        v.sort_by(f64::total_cmp);
        let n = v.len();
        let median = match n {
            0 => return None,
            _ if n % 2 == 1 => v[n / 2],
            _ => 0.5 * (v[n / 2 - 1] + v[n / 2]),
        };
        Some(Spread {
            median,
            min: v[0],
            max: v[n - 1],
        })
    }
}

/// The scene of `settings` at `width`×`height`, and its key.
fn at(settings: &Settings, (width, height): (u32, u32)) -> Result<(Scene, String), Error> {
    let LoadedScene { mut scene, key } = load_scene(&settings.scene)?;
    scene.camera = scene.camera.with_resolution(width, height);
    Ok((scene, key))
}

/// A device method's frame, its image dropped.
fn frame<T>(result: Result<T, impl Into<PipelineError>>) -> Result<(), Error> {
    result.map(drop).map_err(|e| Error::Pipeline(e.into()))
}

fn config(seed: u64, frames: u32) -> RunConfig {
    RunConfig {
        seed,
        frames,
        collect_diagnostics: false,
    }
}

/// Runs every part of the report on `backend` (a Vulkan backend; the CPU backend has no device
/// to report) and returns the markdown.
pub fn run(
    backend: &Backend,
    settings: &Settings,
    progress: &mut dyn Progress,
) -> Result<Report, Error> {
    if settings.frames < 2 {
        return Err(Error::Invalid(format!(
            "frames = {}: need at least 2 (frame 0 is left out of the statistics)",
            settings.frames
        )));
    }
    let (device, details) = {
        let renderer = backend.renderer().ok_or_else(|| {
            Error::Invalid("gpu-report needs the Vulkan backend (--backend vulkan)".into())
        })?;
        let context = renderer.context();
        (context.device().clone(), context.details().clone())
    };
    let mut md = String::new();
    let _ = writeln!(md, "# GPU report: {}\n", device.name);
    device_section(
        &mut md,
        &device.name,
        &format!("{:?}", device.kind),
        &details,
    );
    progress.begin("parity", Preset::all().len() as u64, 0);
    let parity_failures = parity_section(&mut md, backend, settings, progress)?;
    let presets = Preset::all();
    let mut sizes = settings.sizes.clone();
    if let Some(c) = &settings.compare
        && !sizes.contains(&c.size)
    {
        sizes.push(c.size);
    }
    progress.begin("timing", sizes.len() as u64, 0);
    let mut slowest: Vec<((u32, u32), f64)> = Vec::new();
    let _ = writeln!(
        md,
        "## Time per frame\n\nScene `{}`, {} frames per run; median and range over frames 1..{} \
         (frame 0 has no temporal history). Preset passes: GPU timestamps around each dispatch. \
         Memoryless methods: wall clock around a whole frame (G-buffer, kernel, read-back).\n\n\
         | resolution | method | pass | median ms | min–max ms |\n|---|---|---|---:|---:|",
        settings.scene,
        settings.frames,
        settings.frames - 1
    );
    for &size in &sizes {
        let (scene, _) = at(settings, size)?;
        let slowest_here = time_presets(&mut md, backend, &scene, size, &presets, settings.frames)?;
        if let Some(s) = slowest_here {
            slowest.push((size, s));
        }
        time_methods(&mut md, backend, &scene, size, settings.frames)?;
        progress.step();
    }
    if let Some(c) = &settings.compare {
        compare_section(&mut md, backend, settings, c, &slowest, progress)?;
    }
    Ok(Report {
        markdown: md,
        parity_failures,
    })
}

fn device_section(md: &mut String, name: &str, kind: &str, d: &DeviceDetails) {
    let mib = |b: u64| b as f64 / (1024.0 * 1024.0);
    let _ = writeln!(
        md,
        "## Device\n\n| property | value |\n|---|---|\n\
         | device | {name} ({kind}, vendor 0x{:04x}, device 0x{:04x}) |\n\
         | Vulkan | {} |\n| driver | {} (version 0x{:x}) |\n\
         | device-local memory | {:.0} MiB |\n| maxStorageBufferRange | {:.0} MiB |\n\
         | maxComputeWorkGroupInvocations | {} |\n| maxComputeSharedMemorySize | {} B |\n\
         | maxPushConstantsSize | {} B |\n| timestamps | {} valid bits, {} ns per tick |\n",
        d.vendor_id,
        d.device_id,
        d.api_version,
        d.driver.as_deref().unwrap_or("unknown"),
        d.driver_version,
        mib(d.device_local_bytes),
        mib(d.max_storage_buffer_range as u64),
        d.max_compute_work_group_invocations,
        d.max_compute_shared_memory_size,
        d.max_push_constants_size,
        d.timestamp_valid_bits,
        d.timestamp_period
    );
}

/// The parity table; returns the presets that failed.
fn parity_section(
    md: &mut String,
    backend: &Backend,
    settings: &Settings,
    progress: &mut dyn Progress,
) -> Result<Vec<String>, Error> {
    let (scene, key) = at(settings, settings.parity_size)?;
    let (w, h) = settings.parity_size;
    let frames = settings.parity_frames;
    let _ = writeln!(
        md,
        "## Parity with the CPU backend\n\n`{}` at {w}×{h}, {frames} frames, seeds a = 1, b = 2: \
         R = relMSE(GPU a, CPU a) / relMSE(CPU b, CPU a) must be < {PARITY_BOUND} and the GPU \
         images free of NaN.\n\n| preset | relMSE(GPU a, CPU a) | relMSE(CPU b, CPU a) | R | NaN | verdict |\n\
         |---|---:|---:|---:|---:|---|",
        key
    );
    let mut failures = Vec::new();
    for preset in Preset::all() {
        progress.item(&preset.name);
        let gpu = backend.run(&scene, &preset, &config(1, frames))?;
        let cpu_a = Backend::Cpu.run(&scene, &preset, &config(1, frames))?;
        let cpu_b = Backend::Cpu.run(&scene, &preset, &config(2, frames))?;
        let (distance, noise) = (rel_mse(&gpu, &cpu_a), rel_mse(&cpu_b, &cpu_a));
        let ratio = distance / noise;
        let pass = ratio < PARITY_BOUND && gpu.nan_count == 0;
        if !pass {
            failures.push(preset.name.clone());
        }
        let _ = writeln!(
            md,
            "| {} | {distance:.3e} | {noise:.3e} | {ratio:.3e} | {} | {} |",
            preset.name,
            gpu.nan_count,
            if pass { "pass" } else { "**FAIL**" }
        );
        progress.step();
    }
    md.push('\n');
    Ok(failures)
}

/// `Ok(None)` where the device cannot hold the run's buffers (lavapipe at 1920×1080).
fn device_run(
    backend: &Backend,
    scene: &Scene,
    preset: &Preset,
    frames: u32,
) -> Result<Option<Run>, Error> {
    match backend.run(scene, preset, &config(0, frames)) {
        Ok(run) => Ok(Some(run)),
        Err(PipelineError::Vulkan(VulkanError::BufferTooLarge { .. })) => Ok(None),
        Err(e) => Err(e.into()),
    }
}

fn row(md: &mut String, (w, h): (u32, u32), method: &str, pass: &str, spread: Option<Spread>) {
    match spread {
        Some(s) => {
            let _ = writeln!(
                md,
                "| {w}×{h} | {method} | {pass} | {:.3} | {:.3}–{:.3} |",
                1e3 * s.median,
                1e3 * s.min,
                1e3 * s.max
            );
        }
        None => {
            let _ = writeln!(md, "| {w}×{h} | {method} | {pass} | n/a | n/a |");
        }
    }
}

/// Times every pass of every preset at `size`; returns the slowest preset's median frame time.
fn time_presets(
    md: &mut String,
    backend: &Backend,
    scene: &Scene,
    size: (u32, u32),
    presets: &[Preset],
    frames: u32,
) -> Result<Option<f64>, Error> {
    let mut slowest: Option<f64> = None;
    for preset in presets {
        let method = format!("restir:{}", preset.name);
        let Some(run) = device_run(backend, scene, preset, frames)? else {
            row(
                md,
                size,
                &method,
                "skipped: buffers exceed maxStorageBufferRange",
                None,
            );
            continue;
        };
        if run.timings.is_empty() {
            row(md, size, &method, "no timestamps on this queue", None);
            continue;
        }
        for t in &run.timings {
            row(md, size, &method, &t.label, Spread::of(&t.per_frame[1..]));
        }
        let totals: Vec<f64> = (1..frames as usize)
            .map(|f| run.timings.iter().map(|t| t.per_frame[f]).sum())
            .collect();
        let total = Spread::of(&totals);
        row(md, size, &method, "**frame**", total);
        if let Some(t) = total {
            slowest = Some(slowest.map_or(t.median, |s: f64| s.max(t.median)));
        }
    }
    Ok(slowest)
}

/// Wall time per frame of the memoryless methods at one sample per pixel.
fn time_methods(
    md: &mut String,
    backend: &Backend,
    scene: &Scene,
    size: (u32, u32),
    frames: u32,
) -> Result<(), Error> {
    let mut renderer = backend
        .renderer()
        .ok_or_else(|| Error::Invalid("no Vulkan renderer".into()))?;
    type Frame<'a> = Box<dyn FnMut(&mut engine::vulkan::Renderer, u32) -> Result<(), Error> + 'a>;
    let methods: [(&str, Frame); 4] = [
        (
            "pt:1",
            Box::new(|r, f| {
                frame(methods::pt::vulkan::render(
                    r,
                    scene,
                    f,
                    0,
                    1,
                    HitPolicy::All,
                ))
            }),
        ),
        (
            "random-walk:1",
            Box::new(|r, f| frame(methods::random_walk::vulkan::render(r, scene, f, 0, 1))),
        ),
        (
            "single-scatter:1",
            Box::new(|r, f| {
                let channels = ChannelSelection::Scattering;
                frame(methods::single_scatter::vulkan::render(
                    r, scene, f, 0, 1, channels,
                ))
            }),
        ),
        (
            "image-space:1",
            Box::new(|r, f| frame(methods::image_space::vulkan::render(r, scene, f, 0, 1))),
        ),
    ];
    for (name, mut frame) in methods {
        let mut seconds = Vec::new();
        let mut skipped = false;
        for f in 0..frames {
            let start = Instant::now();
            match frame(&mut renderer, f) {
                Ok(()) => seconds.push(start.elapsed().as_secs_f64()),
                Err(Error::Pipeline(PipelineError::Vulkan(VulkanError::BufferTooLarge {
                    ..
                }))) => {
                    skipped = true;
                    break;
                }
                Err(e) => return Err(e),
            }
        }
        let pass = if skipped {
            "skipped: buffers exceed maxStorageBufferRange"
        } else {
            "frame (wall)"
        };
        row(
            md,
            size,
            name,
            pass,
            Spread::of(seconds.get(1..).unwrap_or(&[])),
        );
    }
    let mut seconds = Vec::new();
    let mut start = Instant::now();
    let adaptive = methods::adaptive::vulkan::run(
        &mut renderer,
        scene,
        &AdaptiveParams::default(),
        0,
        frames,
        |_| {
            seconds.push(start.elapsed().as_secs_f64());
            start = Instant::now();
        },
    );
    match adaptive {
        Ok(_) => row(
            md,
            size,
            "adaptive",
            "frame (wall)",
            Spread::of(&seconds[1..]),
        ),
        Err(VulkanError::BufferTooLarge { .. }) => row(
            md,
            size,
            "adaptive",
            "skipped: buffers exceed maxStorageBufferRange",
            None,
        ),
        Err(e) => return Err(PipelineError::Vulkan(e).into()),
    }
    Ok(())
}

fn compare_section(
    md: &mut String,
    backend: &Backend,
    settings: &Settings,
    c: &CompareSettings,
    slowest: &[((u32, u32), f64)],
    progress: &mut dyn Progress,
) -> Result<(), Error> {
    let (w, h) = c.size;
    let Some(&(_, seconds)) = slowest.iter().find(|(s, _)| *s == c.size) else {
        let _ = writeln!(
            md,
            "## Equal-time comparison\n\nNot run: no preset could be timed at {w}×{h} on this \
             device (buffers too large or no timestamps).\n"
        );
        return Ok(());
    };
    let mut methods = vec![(
        DEFAULT_BASELINE.to_string(),
        Method::parse(DEFAULT_BASELINE)?,
    )];
    for preset in Preset::all() {
        let spec = format!("restir:{}", preset.name);
        methods.push((spec.clone(), Method::parse(&spec)?));
    }
    let (scene, scene_key) = at(settings, c.size)?;
    let plan = Comparison {
        scene,
        scene_key,
        methods,
        baseline: DEFAULT_BASELINE.into(),
        replicas: c.replicas,
        first_seed: 0,
        frames: c.frames,
        equal_time: Some(seconds),
        reference: ReferenceSource::Cache {
            dir: c.cache.clone(),
            spp: c.reference_spp,
            batch_spp: c.reference_batch_spp,
        },
        frame_reference_spp: None,
        out: c.out.clone(),
        backend: backend.clone(),
        // Every denoiser installed: SVGF runs on the device, OIDN on the host's CPU.
        video: false,
        denoise: Denoiser::ALL
            .into_iter()
            .filter(|d| d.available().is_ok())
            .collect(),
    };
    let outcome = compare::run(&plan, progress)?;
    let written = report::write(&plan, &outcome)?;
    let _ = writeln!(
        md,
        "## Equal-time comparison\n\n`compare` on the device at {w}×{h}: {} replicas, {} frames, \
         `pt` scaled to {:.3} ms per frame (the slowest preset's median frame time above), \
         reference {} spp; tables and images in `{}`.\n\n{}",
        c.replicas,
        c.frames,
        1e3 * seconds,
        c.reference_spp,
        outcome.out.display(),
        written.markdown
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spread_is_median_and_range() {
        assert_eq!(Spread::of(&[]), None);
        let s = Spread::of(&[3.0, 1.0, 2.0]).unwrap();
        assert_eq!((s.median, s.min, s.max), (2.0, 1.0, 3.0));
        let s = Spread::of(&[4.0, 1.0, 2.0, 3.0]).unwrap();
        assert_eq!((s.median, s.min, s.max), (2.5, 1.0, 4.0));
    }
}
