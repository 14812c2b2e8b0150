//! `reshift render`: one method, one scene → the final frame as linear EXR and tonemapped PNG,
//! and its timing; for a method that chooses its sample counts per pixel (`adaptive`), its mean
//! samples per pixel and the count map as a false-colour PNG with a labelled colour bar (0 … the
//! most a pixel may take); for a method built from the engine's passes (`restir:…`), the time of
//! each pass per rendered frame (process CPU time and wall time on the CPU backend, GPU
//! timestamps on Vulkan), which says where a configuration's cost goes. With `--timing`, paper
//! 001's timing protocol instead (`lab::timing`): warm-up frames, timed frames along the
//! trajectory, repeats, and per pass the median and spread. The first Ctrl-C ends a streamed
//! method's run (`restir:<preset>`) after the frame in progress: the output is that frame's,
//! the summary says how many frames were rendered and that the run was interrupted, and the
//! exit status is 1 (as for `bias` and `compare`); other methods finish their render.

use std::path::PathBuf;

use clap::Args;
use engine::clock::Clock;
use engine::{Backend, PassTiming};
use lab::draw::false_colour_map;
use lab::output::{file_stem, output_dir};
use lab::timing::{self as protocol, Protocol};
use methods::Method;
use serde_json::json;
use sss::limits::{self, MAX_FRAMES};

use super::common::{
    BackendArgs, CliError, CliResult, command_line, interrupted, json_number, load_scene_at,
    scene_and_frames,
};

#[derive(Args, Clone, Debug)]
pub struct RenderArgs {
    /// Built-in scene name or path to a scene .toml.
    #[arg(long)]
    pub scene: String,
    /// The method, e.g. pt:16 or restir:hybrid (see `reshift methods`).
    #[arg(long)]
    pub method: String,
    /// Frames of the camera trajectory; the last one is written [default: 16, or the poses of
    /// --trajectory].
    #[arg(long)]
    pub frames: Option<u32>,
    /// Render along this camera path (a trajectory file, e.g. recorded by `reshift view
    /// --record`) instead of the scene camera's.
    #[arg(long, value_name = "FILE")]
    pub trajectory: Option<PathBuf>,
    /// Image size WxH [default: the scene's].
    #[arg(long)]
    pub resolution: Option<String>,
    /// Replica seed.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Output folder [default: out/render].
    #[arg(long, default_value = "out/render")]
    pub out: PathBuf,
    /// Print a JSON summary.
    #[arg(long)]
    pub json: bool,
    /// Run paper 001's timing protocol instead of writing an image: a `restir:<preset>`
    /// stream warms up at the trajectory's first pose, then its passes are timed over frames
    /// along the trajectory, the whole repeated; prints each pass's median and spread.
    #[arg(long)]
    pub timing: bool,
    /// Warm-up frames of --timing.
    #[arg(long, requires = "timing", default_value_t = Protocol::default().warmup)]
    pub warmup: u32,
    /// Timed frames of --timing, along the trajectory.
    #[arg(long, requires = "timing", default_value_t = Protocol::default().timed)]
    pub timed: u32,
    /// Repeats of --timing, each a fresh stream.
    #[arg(long, requires = "timing", default_value_t = Protocol::default().repeats)]
    pub repeats: u32,
    #[command(flatten)]
    pub backend: BackendArgs,
}

/// Most repeats of `--timing`.
const MAX_REPEATS: u64 = 1024;

pub fn command(args: &RenderArgs) -> CliResult<()> {
    if args.timing {
        return timing(args);
    }
    let method = Method::parse(&args.method)?;
    let (loaded, frames) = scene_and_frames(
        load_scene_at(&args.scene, args.resolution.as_deref())?,
        args.trajectory.as_deref(),
        args.frames,
    )?;
    let scene = loaded.scene;
    let out = output_dir(&args.out)?;
    let backend = args.backend.open()?;
    let rendered = method.render_until(&backend, &scene, frames, args.seed, &interrupted)?;
    // The frame written: the last of the trajectory, or the last rendered before a Ctrl-C.
    let frame = match rendered.stopped {
        true => rendered.frames_rendered - 1,
        false => frames - 1,
    };
    let stem = format!("{}-{}", file_stem(&loaded.key), file_stem(&method.name()));
    let (exr, png) = (
        out.join(format!("{stem}.exr")),
        out.join(format!("{stem}.png")),
    );
    rendered.image.write_exr(&exr)?;
    rendered.image.write_png(&png)?;
    let samples = match &rendered.counts {
        Some(c) => {
            let path = out.join(format!("{stem}-samples.png"));
            let values: Vec<f64> = c.counts.iter().map(|&n| n as f64).collect();
            let title = format!("{}: samples per pixel", method.name());
            false_colour_map(&path, &values, (c.width, c.height), c.max as f64, &title)?;
            Some(path)
        }
        None => None,
    };
    let per_frame = f64::from(rendered.frames_rendered.max(1));
    if args.json {
        let value = json!({
            "schema": "reshift-render/2",
            "scene": scene.name,
            "method": method.name(),
            "backend": backend.to_string(),
            "width": rendered.image.width,
            "height": rendered.image.height,
            "frames": frames,
            "frames_rendered": rendered.frames_rendered,
            "interrupted": rendered.stopped,
            "frame": frame,
            "seed": args.seed,
            "clock": Clock::of(&backend).name(),
            "seconds_per_frame": json_number(rendered.seconds_per_frame),
            "wall_seconds_per_frame": json_number(rendered.wall_seconds_per_frame),
            "nonfinite": rendered.nonfinite,
            "mean_spp": json_number(rendered.spp),
            "exr": exr.display().to_string(),
            "png": png.display().to_string(),
            "samples_png": samples.as_ref().map(|p| p.display().to_string()),
            "passes": rendered.passes.iter().map(|pass| json!({
                "label": pass.label,
                "seconds_per_frame": json_number(pass.seconds / per_frame),
                "cpu_seconds_per_frame": pass.cpu_seconds.map(|s| json_number(s / per_frame)),
            })).collect::<Vec<_>>(),
        });
        print_json(&value);
    } else {
        println!(
            "{} on {} ({}×{}, frame {} of {}{}, {}): {:.1} ms/frame of {} ({:.1} ms wall) over {} rendered frame(s), {:.2} samples per pixel, {} non-finite\n{}\n{}{}",
            method,
            scene.name,
            rendered.image.width,
            rendered.image.height,
            frame,
            frames,
            if rendered.stopped {
                ", interrupted"
            } else {
                ""
            },
            backend,
            1e3 * rendered.seconds_per_frame,
            Clock::of(&backend).name(),
            1e3 * rendered.wall_seconds_per_frame,
            rendered.frames_rendered,
            rendered.spp,
            rendered.nonfinite,
            exr.display(),
            png.display(),
            samples.map_or(String::new(), |p| format!("\n{}", p.display()))
        );
        if !rendered.passes.is_empty() {
            print!("{}", pass_table(&rendered.passes, per_frame));
        }
    }
    if rendered.stopped {
        return Err(CliError(format!(
            "interrupted after {} of {frames} frames; the images are frame {frame}'s",
            rendered.frames_rendered
        )));
    }
    Ok(())
}

/// Per pass, ms per rendered frame on both clocks: the process's CPU time (CPU backend) and the
/// wall time (GPU timestamps on Vulkan), as a markdown table.
fn pass_table(passes: &[PassTiming], frames: f64) -> String {
    let ms = |s: f64| format!("{:.2}", 1e3 * s / frames);
    let mut table =
        String::from("| pass | CPU ms/frame | wall or GPU ms/frame |\n|---|---:|---:|\n");
    for pass in passes {
        let cpu = pass.cpu_seconds.map_or("—".to_string(), ms);
        table += &format!("| {} | {cpu} | {} |\n", pass.label, ms(pass.seconds));
    }
    table
}

/// `render --timing`: the protocol's table (or JSON) for a `restir:<preset>` method.
fn timing(args: &RenderArgs) -> CliResult<()> {
    let preset = args
        .method
        .strip_prefix("restir:")
        .ok_or_else(|| {
            CliError(format!(
                "--timing: --method {}: the protocol times the engine's passes, which a \
                 restir:<preset> method runs",
                args.method
            ))
        })
        .and_then(|arg| {
            methods::restir::preset(Some(arg))
                .map_err(|e| CliError(format!("--timing: --method {}: {e}", args.method)))
        })?;
    let protocol = Protocol {
        warmup: args.warmup,
        timed: args.timed,
        repeats: args.repeats,
    };
    let file = command_line();
    limits::count(
        file,
        "--warmup",
        protocol.warmup as u64,
        0,
        MAX_FRAMES as u64,
    )?;
    limits::count(file, "--timed", protocol.timed as u64, 1, MAX_FRAMES as u64)?;
    limits::count(file, "--repeats", protocol.repeats as u64, 1, MAX_REPEATS)?;
    let loaded = load_scene_at(&args.scene, args.resolution.as_deref())?;
    let (width, height) = (loaded.scene.camera.width(), loaded.scene.camera.height());
    let name = loaded.scene.name.clone();
    let backend = args.backend.open()?;
    let timing = protocol::measure(&backend, loaded.scene, &preset, args.seed, &protocol)?;
    if args.json {
        let ms = |s: f64| json_number(1e3 * s);
        let value = json!({
            "schema": "reshift-timing/1",
            "scene": name,
            "method": args.method,
            "backend": backend.to_string(),
            "width": width,
            "height": height,
            "seed": args.seed,
            "warmup": protocol.warmup,
            "timed": protocol.timed,
            "repeats": protocol.repeats,
            "clock": timing.clock.name(),
            "rows": timing.rows.iter().map(|r| json!({
                "label": r.label,
                "median_ms": ms(r.median),
                "quartiles_ms": [ms(r.quartiles.0), ms(r.quartiles.1)],
                "range_ms": [ms(r.range.0), ms(r.range.1)],
                "frames": r.samples,
            })).collect::<Vec<_>>(),
        });
        print_json(&value);
    } else {
        println!(
            "{} on {name} ({width}×{height}, {backend}): {} warm-up frames at the first pose, {} timed frames along the trajectory, {} repeats; passes on {}, frame on {}\n{}",
            args.method,
            protocol.warmup,
            protocol.timed,
            protocol.repeats,
            match &backend {
                Backend::Cpu => timing.clock.name(),
                Backend::Vulkan(_) => "the device's timestamps",
            },
            timing.clock.name(),
            timing.table()
        );
    }
    Ok(())
}

/// `value`, pretty-printed.
fn print_json(value: &serde_json::Value) {
    println!(
        "{}",
        serde_json::to_string_pretty(value).expect("JSON values")
    );
}
