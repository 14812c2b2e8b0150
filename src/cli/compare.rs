//! `reshift compare`: K replicas of several methods on one scene against a cached reference;
//! writes `table.md`, `table.csv`, `results.json` (docs/results-schema.md) and images.

use std::path::{Path, PathBuf};

use clap::Args;
use engine::{Backend, Image};
use lab::compare::{
    MethodResult, REFERENCE_SEED, ReferenceKey, cache_path, check_reference, equal_time_method,
    quantile, reference_pixels, write_false_colour,
};
use lab::methods::pt::Pt;
use lab::methods::{Method, Rendered};
use lab::metrics::{BIAS_CONFIDENCE, REL_EPSILON, efficiency, error_maps};
use lab::regions::{Region, Regions};
use lab::tables;
use serde_json::{Value, json};
use sss::integrator::Reference;
use sss::scene::{GBuffer, Scene};

use super::common::{
    BackendArgs, CliError, CliResult, LoadedScene, file_stem, interrupted, json_number, json_opt,
    load_scene, output_dir, parse_resolution, progress, with_resolution, write_file,
};

/// The default method list: the path tracer and the four main presets [001 §5.1].
pub const DEFAULT_METHODS: &str =
    "pt,restir:reconnection,restir:delayed,restir:hybrid,restir:sequential";

#[derive(Args, Clone, Debug)]
pub struct CompareArgs {
    /// Built-in scene name or path to a scene .toml.
    #[arg(long, default_value = "bumpy")]
    pub scene: String,
    /// Comma-separated methods (see `reshift methods`).
    #[arg(long, value_delimiter = ',', default_value = DEFAULT_METHODS)]
    pub methods: Vec<String>,
    /// Independent replicas per method (seeds 0..K).
    #[arg(long, default_value_t = 8)]
    pub replicas: u32,
    /// Frames of the camera trajectory; errors are measured on the last one.
    #[arg(long, default_value_t = 16)]
    pub frames: u32,
    /// Every method at its own samples per pixel (the default).
    #[arg(long, conflicts_with = "equal_time")]
    pub equal_spp: bool,
    /// Scale a bare `pt` to this many seconds per frame (`pt:N` and ReSTIR presets keep their cost).
    #[arg(long, value_name = "SECONDS")]
    pub equal_time: Option<f64>,
    /// Image size WxH.
    #[arg(long, default_value = "128x96")]
    pub resolution: String,
    /// Output folder [default: out/compare-<scene>].
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Folder of cached references.
    #[arg(long, default_value = "out/cache")]
    pub cache: PathBuf,
    /// Use this reference checkpoint (from `reshift reference`) instead of the cache.
    #[arg(long)]
    pub reference: Option<PathBuf>,
    /// Samples per pixel of the reference (a multiple of --reference-batch-spp).
    #[arg(long, default_value_t = 8192)]
    pub reference_spp: u32,
    /// Samples per pixel of one reference batch.
    #[arg(long, default_value_t = 128)]
    pub reference_batch_spp: u32,
    /// Print results.json to stdout instead of the table.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub backend: BackendArgs,
}

/// What a finished (or interrupted) comparison produced.
pub struct Outcome {
    pub results: Vec<MethodResult>,
    pub json: Value,
    pub markdown: String,
    pub out: PathBuf,
}

/// Runs `compare` and prints the table (or the JSON).
pub fn command(args: &CompareArgs) -> CliResult<()> {
    let outcome = run(args)?;
    if args.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&outcome.json).expect("JSON values")
        );
    } else {
        println!("{}", outcome.markdown);
        println!(
            "Images, table.md, table.csv and results.json are in {}",
            outcome.out.display()
        );
    }
    if outcome.json["interrupted"] == json!(true) {
        return Err(CliError("interrupted: partial results written".into()));
    }
    Ok(())
}

/// The comparison without printing.
pub fn run(args: &CompareArgs) -> CliResult<Outcome> {
    let methods: Vec<(String, Method)> = args
        .methods
        .iter()
        .map(|spec| Ok((spec.clone(), Method::parse(spec)?)))
        .collect::<CliResult<_>>()?;
    if methods.is_empty() {
        return Err(CliError("--methods: no method given".into()));
    }
    if args.replicas == 0 || args.frames == 0 {
        return Err(CliError("--replicas and --frames must be ≥ 1".into()));
    }
    if let Some(t) = args.equal_time
        && !(t.is_finite() && t > 0.0)
    {
        return Err(CliError(format!(
            "--equal-time {t}: must be a positive number of seconds"
        )));
    }
    let resolution = parse_resolution(&args.resolution)?;
    let backend = args.backend.open()?;
    let LoadedScene { scene, key } = load_scene(&args.scene)?;
    let scene = with_resolution(scene, Some(resolution));
    let out = output_dir(
        &args
            .out
            .clone()
            .unwrap_or_else(|| PathBuf::from(format!("out/compare-{}", file_stem(&key)))),
    )?;
    let frame = args.frames - 1;
    let (reference, reference_path, cached) = reference(args, &scene, &key, resolution, frame)?;
    let gbuffer = GBuffer::render(&scene, frame);
    let regions = Regions::classify(&scene, &gbuffer, REFERENCE_SEED);

    let budget = args.equal_time;
    let seconds_per_spp = match budget {
        Some(_) if methods.iter().any(|(spec, _)| spec == "pt") => {
            calibrate_pt(&backend, &scene, args.frames)?
        }
        _ => 0.0,
    };
    let total = methods.len() as u64 * args.replicas as u64;
    let bar = progress(total, "replicas");
    let mut runs: Vec<(String, Method, Vec<Rendered>)> = Vec::new();
    'methods: for (spec, method) in &methods {
        // `pt:N` pins its spp; a bare `pt` is scaled to the budget.
        let method = match budget {
            Some(b) if spec == "pt" => equal_time_method(method, b, seconds_per_spp),
            _ => method.clone(),
        };
        bar.set_message(method.name());
        let mut replicas = Vec::new();
        for seed in 0..args.replicas as u64 {
            if interrupted() {
                runs.push((spec.clone(), method, replicas));
                break 'methods;
            }
            replicas.push(method.render_on(&backend, &scene, args.frames, seed)?);
            bar.inc(1);
        }
        runs.push((spec.clone(), method, replicas));
    }
    bar.finish_and_clear();
    let stopped = interrupted();

    let mut results = Vec::new();
    for (spec, method, replicas) in &runs {
        if replicas.is_empty() {
            continue;
        }
        let result =
            MethodResult::from_replicas(spec, method.spp(), replicas, &reference, &regions)
                .ok_or_else(|| {
                    CliError(format!("{spec}: image size differs from the reference"))
                })?;
        results.push(result);
    }
    let images = write_images(&out, &runs, &reference)?;
    let markdown = tables::markdown(&results);
    write_file(&out.join("table.md"), &markdown)?;
    write_file(&out.join("table.csv"), &tables::csv(&results))?;
    let json = results_json(&Context {
        args,
        backend: &backend,
        scene: &scene,
        regions: &regions,
        reference: &reference,
        reference_path: &reference_path,
        cached,
        interrupted: stopped,
        images: &images,
        results: &results,
    });
    write_file(
        &out.join("results.json"),
        &serde_json::to_string_pretty(&json).expect("JSON values"),
    )?;
    Ok(Outcome {
        results,
        json,
        markdown,
        out,
    })
}

/// The reference of this comparison: `--reference FILE` (checked), else the cache entry
/// (resumed if incomplete), else computed now and cached. Returns it, its path and whether it
/// was reused.
fn reference(
    args: &CompareArgs,
    scene: &Scene,
    key: &str,
    (width, height): (u32, u32),
    frame: u32,
) -> CliResult<(Reference, PathBuf, bool)> {
    if let Some(path) = &args.reference {
        let reference = Reference::load(path)?;
        check_reference(&reference, path, width, height, frame)?;
        if reference.config.scene != scene.name {
            return Err(CliError(format!(
                "{}: a reference of scene {:?}, not {:?}",
                path.display(),
                reference.config.scene,
                scene.name
            )));
        }
        return Ok((reference, path.clone(), true));
    }
    let batch = args.reference_batch_spp;
    if batch == 0 || args.reference_spp < 2 * batch || !args.reference_spp.is_multiple_of(batch) {
        return Err(CliError(format!(
            "--reference-spp {} must be a multiple ≥ 2× of --reference-batch-spp {batch}",
            args.reference_spp
        )));
    }
    let key = ReferenceKey {
        scene: file_stem(key),
        width,
        height,
        frame,
        spp_per_batch: batch,
        batches: args.reference_spp / batch,
    };
    let cache = output_dir(&args.cache)?;
    let path = cache_path(&cache, &key);
    let mut reference = match Reference::load(&path) {
        Ok(r) if r.config == key.config(&scene.name) && (r.width, r.height) == (width, height) => r,
        _ => key.empty(&scene.name)?,
    };
    if reference.is_complete() {
        return Ok((reference, path, true));
    }
    super::reference::accumulate(&mut reference, scene, &path, "reference", None)?;
    if !reference.is_complete() {
        return Err(CliError(format!(
            "interrupted while computing the reference; checkpoint {} resumes next time",
            path.display()
        )));
    }
    Ok((reference, path, false))
}

/// Seconds per sample per pixel of the path tracer on this scene (median of 3 runs at 4 spp).
fn calibrate_pt(backend: &Backend, scene: &Scene, frames: u32) -> CliResult<f64> {
    let pt = Method::new(Pt { spp: 4 });
    let mut times = Vec::new();
    for seed in 0..3 {
        times.push(
            pt.render_on(backend, scene, frames, 1_000_000 + seed)?
                .seconds_per_frame
                / 4.0,
        );
    }
    times.sort_by(f64::total_cmp);
    Ok(times[1])
}

/// Paths of one method's images, relative to the output folder.
struct MethodImages {
    exr: String,
    png: String,
    abs_error: String,
    rel_error: String,
}

/// Scales of the error maps (shared by all methods, so maps are comparable).
struct Scales {
    absolute: f64,
    relative: f64,
}

/// Writes the reference, each method's replica-0 final frame (EXR + PNG) and its absolute and
/// relative error maps, all methods on one colour scale: the 99th percentile of all methods'
/// errors.
fn write_images(
    out: &Path,
    runs: &[(String, Method, Vec<Rendered>)],
    reference: &Reference,
) -> CliResult<(Vec<MethodImages>, Scales)> {
    let mean = reference.mean();
    let reference_image = Image {
        width: reference.width,
        height: reference.height,
        pixels: reference_pixels(reference),
    };
    reference_image.write_exr(out.join("reference.exr"))?;
    reference_image.write_png(out.join("reference.png"))?;
    let maps: Vec<(Vec<f64>, Vec<f64>)> = runs
        .iter()
        .filter_map(|(_, _, replicas)| error_maps(&replicas.first()?.image, &mean))
        .collect();
    let all_abs: Vec<f64> = maps.iter().flat_map(|m| m.0.iter().copied()).collect();
    let all_rel: Vec<f64> = maps.iter().flat_map(|m| m.1.iter().copied()).collect();
    let scales = Scales {
        absolute: quantile(&all_abs, 0.99),
        relative: quantile(&all_rel, 0.99),
    };
    let mut written = Vec::new();
    for ((spec, _, replicas), (abs, rel)) in
        runs.iter().filter(|(_, _, r)| !r.is_empty()).zip(&maps)
    {
        let stem = file_stem(spec);
        let names = MethodImages {
            exr: format!("{stem}.exr"),
            png: format!("{stem}.png"),
            abs_error: format!("{stem}-abs-error.png"),
            rel_error: format!("{stem}-rel-error.png"),
        };
        let image = &replicas[0].image;
        image.write_exr(out.join(&names.exr))?;
        image.write_png(out.join(&names.png))?;
        let (w, h) = (image.width, image.height);
        write_false_colour(abs, w, h, scales.absolute, &out.join(&names.abs_error))?;
        write_false_colour(rel, w, h, scales.relative, &out.join(&names.rel_error))?;
        written.push(names);
    }
    Ok((written, scales))
}

struct Context<'a> {
    args: &'a CompareArgs,
    backend: &'a Backend,
    scene: &'a Scene,
    regions: &'a Regions,
    reference: &'a Reference,
    reference_path: &'a Path,
    cached: bool,
    interrupted: bool,
    images: &'a (Vec<MethodImages>, Scales),
    results: &'a [MethodResult],
}

/// `results.json` (schema `reshift-compare/1`, docs/results-schema.md).
fn results_json(c: &Context) -> Value {
    let (images, scales) = c.images;
    let methods: Vec<Value> = c
        .results
        .iter()
        .zip(images)
        .map(|(r, i)| {
            let areas: Vec<Value> = r
                .metrics
                .iter()
                .map(|m| {
                    json!({
                        "area": m.area.name(),
                        "pixels": m.pixels,
                        "mse": json_number(m.mse),
                        "rel_mse": json_number(m.rel_mse),
                        "reference_mean": json_number(m.reference_mean),
                        "bias": json_number(m.bias),
                        "bias_ci99": json_opt(m.bias_ci),
                        "relative_bias": json_opt((m.reference_mean > 0.0).then(|| m.bias / m.reference_mean)),
                        "variance": json_opt(m.variance),
                        "reference_mse": json_number(m.reference_mse),
                        "efficiency": json_opt(efficiency(m.mse, r.seconds_per_frame)),
                    })
                })
                .collect();
            json!({
                "method": r.method,
                "spp": r.spp,
                "replicas": r.replicas,
                "seconds_per_frame": json_number(r.seconds_per_frame),
                "frames_rendered": r.frames_rendered,
                "nonfinite": r.nonfinite,
                "tonemapped_mse": json_number(r.tonemapped_mse),
                "tonemapped_rmse": json_number(r.tonemapped_mse.sqrt()),
                "images": {
                    "final_exr": i.exr,
                    "final_png": i.png,
                    "abs_error_png": i.abs_error,
                    "rel_error_png": i.rel_error,
                },
                "areas": areas,
            })
        })
        .collect();
    let regions: serde_json::Map<String, Value> = Region::ALL
        .iter()
        .map(|&r| (r.name().to_string(), json!(c.regions.count(r))))
        .collect();
    let reference = c.reference;
    json!({
        "schema": "reshift-compare/1",
        "scene": c.scene.name,
        "backend": c.backend.to_string(),
        "width": reference.width,
        "height": reference.height,
        "frames": c.args.frames,
        "frame": reference.config.frame,
        "replicas": c.args.replicas,
        "budget": {
            "mode": if c.args.equal_time.is_some() { "equal-time" } else { "equal-spp" },
            "seconds_per_frame": json_opt(c.args.equal_time),
        },
        "reference": {
            "path": c.reference_path.display().to_string(),
            "spp": reference.batches_done() as u64 * reference.config.spp_per_batch as u64,
            "batches": reference.batches_done(),
            "seed": reference.config.seed,
            "cached": c.cached,
        },
        "rel_epsilon": REL_EPSILON,
        "bias_confidence": BIAS_CONFIDENCE,
        "interrupted": c.interrupted,
        "regions": regions,
        "error_map_scale": {
            "absolute": json_number(scales.absolute),
            "relative": json_number(scales.relative),
        },
        "methods": methods,
    })
}
