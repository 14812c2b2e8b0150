//! `model-gap`: where the volumetric random walk and the diffusion BSSRDF differ [000]. Per
//! scene, per walk boundary (`diffuse`, `dielectric`, `index_matched`, overriding every
//! material's) and per region, the walk's region mean minus the BSSRDF path tracer's is split
//! into three parts that add up to it exactly, sample by sample ([`terms`]):
//!
//! ```text
//! walk − BSSRDF = [walk₀ + walk₁ − R1]              low orders: exact paths vs the flat R1 profile
//!               + [walk≥2 − (R − R1)]               multiple scattering: walk vs paper 000's diffusion
//!               + [(R1 + (R − R1)) − BSSRDF]        profile: paper 000's R(α) vs the material's A R̄
//! ```
//!
//! with two controls: path-traced zero + single scattering against the walk's 0- and
//! 1-collision tallies (the same transport, must agree), and paper 000's hybrid estimator
//! (`single-scatter`) against the walk. Every part is relative to the walk's region mean, with
//! a 99% CI over K replicas (seeds `0..K`; every estimator of a replica at the same primary
//! hits, so the differences are paired: the replica is the unit of independence).

mod terms;

use std::fmt::Write as _;

use glam::DVec3;
use rayon::prelude::*;
use restir::stats::{Summary, student_t_quantile};
use serde_json::{Value, json};
use sss::material::{BoundaryKind, Material, Translucent};
use sss::random_walk::Medium;
use sss::scene::{GBuffer, Scene};

use terms::{
    BSSRDF, DIFFUSION_MULTIPLE, DIFFUSION_SINGLE, PATH_0, PATH_1, WALK_0, WALK_1, WALK_MULTIPLE,
};
pub use terms::{TERM_NAMES, Terms};

use lab::error::Error;
use lab::output::output_dir;
use lab::progress::Progress;
use lab::reference_cache::REFERENCE_SEED;
use lab::regions::{Region, Regions};
use lab::scenes::{load_scene, with_resolution};
use sss::color::luminance;

use super::setup::{FRAMES, Report, Settings};

/// The default scenes: the curved `bumpy` at its own and at ¼ and 4× mean free path, the flat
/// half-space `half-shadow` (diffusion's own geometry), the thin `slab`, and the measured
/// materials with the shortest and the longest mean free path relative to their sphere.
pub const SCENES: [&str; 7] = [
    "bumpy",
    "mfp-0.25",
    "mfp-4",
    "half-shadow",
    "slab",
    "sphere-cream",
    "sphere-chicken",
];

/// The walk boundaries compared (the BSSRDF is the same for all).
pub const BOUNDARIES: [BoundaryKind; 3] = [
    BoundaryKind::Diffuse,
    BoundaryKind::Dielectric,
    BoundaryKind::IndexMatched,
];

const CONFIDENCE: f64 = 0.99;

fn boundary_name(b: BoundaryKind) -> &'static str {
    match b {
        BoundaryKind::Diffuse => "diffuse",
        BoundaryKind::Dielectric => "dielectric",
        BoundaryKind::IndexMatched => "index_matched",
    }
}

/// The media of `scene`'s materials with every translucent one's boundary replaced.
fn media_with(scene: &Scene, boundary: BoundaryKind) -> Result<Vec<Option<Medium>>, Error> {
    scene
        .materials
        .iter()
        .enumerate()
        .map(|(i, m)| match m {
            Material::Translucent(t) => {
                let t = Translucent { boundary, ..*t };
                Ok(Some(Medium::from_translucent(
                    &t,
                    &scene.file,
                    &format!("materials[{i}]"),
                )?))
            }
            Material::Lambert(_) => Ok(None),
        })
        .collect()
}

/// Per pixel, the mean of `spp` samples of every term (0 off translucent objects), for replica
/// `seed`; and the samples whose chain was cut.
fn render(
    scene: &Scene,
    gbuffer: &GBuffer,
    media: &[Option<Medium>],
    seed: u64,
    spp: u32,
) -> (Vec<[DVec3; 8]>, u64) {
    let rows: Vec<(Vec<[DVec3; 8]>, u64)> = gbuffer
        .pixels
        .par_chunks(gbuffer.width.max(1) as usize)
        .enumerate()
        .map(|(row, pixels)| {
            let (mut hits, mut truncated) = (Vec::new(), 0);
            let means = pixels
                .iter()
                .enumerate()
                .map(|(column, g)| {
                    let mut sum = [DVec3::ZERO; 8];
                    let Some(g) = g else { return sum };
                    let pixel = (row * gbuffer.width as usize + column) as u32;
                    for s in 0..spp {
                        let at = [pixel, gbuffer.frame, s];
                        let sample = terms::sample(scene, media, g, at, seed, &mut hits);
                        let Some(sample) = sample else { break };
                        truncated += sample.truncated as u64;
                        for (total, v) in sum.iter_mut().zip(sample.values) {
                            *total += v.as_dvec3() / spp as f64;
                        }
                    }
                    sum
                })
                .collect();
            (means, truncated)
        })
        .collect();
    let truncated = rows.iter().map(|r| r.1).sum();
    (rows.into_iter().flat_map(|r| r.0).collect(), truncated)
}

/// A part of the gap relative to the walk's region mean: `mean(d) / mean(w)` over paired
/// replicas, with the half-width of its CI by the delta method (`z_k = d_k − r w_k`, Student-t
/// with K − 1 degrees of freedom).
fn relative(d: &[f64], w: &[f64]) -> [f64; 2] {
    let k = d.len() as f64;
    let (d_mean, w_mean) = (d.iter().sum::<f64>() / k, w.iter().sum::<f64>() / k);
    let r = d_mean / w_mean;
    let z: Vec<f64> = d.iter().zip(w).map(|(d, w)| d - r * w).collect();
    let se = Summary::from_samples(&z).std_err / w_mean.abs();
    [r, student_t_quantile(0.5 + 0.5 * CONFIDENCE, k - 1.0) * se]
}

/// The parts of one scene, boundary and region.
#[derive(Clone, Debug, PartialEq)]
pub struct Gap {
    pub scene: String,
    pub boundary: BoundaryKind,
    pub region: Region,
    pub pixels: usize,
    /// The walk's region mean luminance over replicas.
    pub walk: Summary,
    /// `(name, [relative value, CI half-width])`, in [`PARTS`] order.
    pub parts: Vec<(&'static str, [f64; 2])>,
    /// Samples whose chain was cut (all replicas).
    pub truncated: u64,
}

/// The parts, as sums of term indices with signs.
pub const PARTS: [(&str, &[(usize, f64)]); 9] = [
    (
        "walk − BSSRDF",
        &[
            (WALK_0, 1.0),
            (WALK_1, 1.0),
            (WALK_MULTIPLE, 1.0),
            (BSSRDF, -1.0),
        ],
    ),
    (
        "orders 0+1: walk − R1",
        &[(WALK_0, 1.0), (WALK_1, 1.0), (DIFFUSION_SINGLE, -1.0)],
    ),
    (
        "orders ≥2: walk − (R − R1)",
        &[(WALK_MULTIPLE, 1.0), (DIFFUSION_MULTIPLE, -1.0)],
    ),
    (
        "profile: R(α) − BSSRDF",
        &[
            (DIFFUSION_SINGLE, 1.0),
            (DIFFUSION_MULTIPLE, 1.0),
            (BSSRDF, -1.0),
        ],
    ),
    (
        "control: path 0+1 − walk 0+1",
        &[(PATH_0, 1.0), (PATH_1, 1.0), (WALK_0, -1.0), (WALK_1, -1.0)],
    ),
    (
        "single-scatter − walk",
        &[
            (PATH_0, 1.0),
            (PATH_1, 1.0),
            (DIFFUSION_MULTIPLE, 1.0),
            (WALK_0, -1.0),
            (WALK_1, -1.0),
            (WALK_MULTIPLE, -1.0),
        ],
    ),
    ("walk 0 share", &[(WALK_0, 1.0)]),
    ("walk 1 share", &[(WALK_1, 1.0)]),
    ("walk ≥2 share", &[(WALK_MULTIPLE, 1.0)]),
];

/// The gaps of `replicas` (per replica, per pixel, the term means) in every non-empty region.
fn gaps(
    scene: &str,
    boundary: BoundaryKind,
    replicas: &[Vec<[DVec3; 8]>],
    regions: &Regions,
    truncated: u64,
) -> Vec<Gap> {
    Region::ALL
        .into_iter()
        .filter_map(|region| {
            let pixels = regions.pixels(region);
            if pixels.is_empty() {
                return None;
            }
            // Per replica, the region mean luminance of every term.
            let means: Vec<[f64; 8]> = replicas
                .iter()
                .map(|image| {
                    std::array::from_fn(|t| {
                        pixels
                            .iter()
                            .map(|&p| luminance(image[p][t].as_vec3().as_dvec3()))
                            .sum::<f64>()
                            / pixels.len() as f64
                    })
                })
                .collect();
            let walk: Vec<f64> = means
                .iter()
                .map(|m| m[WALK_0] + m[WALK_1] + m[WALK_MULTIPLE])
                .collect();
            let parts = PARTS
                .iter()
                .map(|(name, terms)| {
                    let d: Vec<f64> = means
                        .iter()
                        .map(|m| terms.iter().map(|&(t, sign)| sign * m[t]).sum())
                        .collect();
                    (*name, relative(&d, &walk))
                })
                .collect();
            Some(Gap {
                scene: scene.to_string(),
                boundary,
                region,
                pixels: pixels.len(),
                walk: Summary::from_samples(&walk),
                parts,
                truncated,
            })
        })
        .collect()
}

/// The medium of the scene's first translucent material: `ℓ = 1/σt`, `α`, and paper 000's total
/// diffuse albedo `A(α)` relative to the material's `A` (the profile part's origin).
fn medium_line(scene: &Scene) -> Option<String> {
    let media = Medium::of_scene(scene).ok()?;
    let (index, medium) = media
        .iter()
        .enumerate()
        .find_map(|(i, m)| Some((i, (*m)?)))?;
    let Material::Translucent(t) = scene.materials[index] else {
        return None;
    };
    let mfp = 1.0 / medium.sigma_t();
    let alpha = medium.albedo();
    let ratio: [f32; 3] = std::array::from_fn(|c| {
        sss::profile::single_scattering::surface_albedo(alpha[c]) / t.albedo[c]
    });
    Some(format!(
        "| {} | {:.4}, {:.4}, {:.4} | {:.4}, {:.4}, {:.4} | {:.3}, {:.3}, {:.3} |",
        scene.name, mfp.x, mfp.y, mfp.z, alpha.x, alpha.y, alpha.z, ratio[0], ratio[1], ratio[2]
    ))
}

/// Runs the experiment on `settings.scenes` (empty: [`SCENES`]); each replica renders
/// `reference_spp / replicas` samples per pixel of every term.
pub fn run(settings: &Settings, progress: &mut dyn Progress) -> Result<Report, Error> {
    let names: Vec<String> = if settings.scenes.is_empty() {
        SCENES.iter().map(|s| s.to_string()).collect()
    } else {
        settings.scenes.clone()
    };
    let spp = settings.reference_spp / settings.replicas.max(1);
    if settings.replicas < 2 || spp == 0 {
        return Err(Error::Invalid(format!(
            "{} replicas of {} spp in all: need ≥ 2 replicas of ≥ 1 spp",
            settings.replicas, settings.reference_spp
        )));
    }
    let out = output_dir(&settings.out_dir("model-gap"))?;
    let frame = FRAMES - 1;
    let (mut all, mut notes) = (Vec::new(), String::new());
    let mut media_table =
        String::from("| scene | ℓ = 1/σt (RGB) | α (RGB) | A(α) / A (RGB) |\n|---|---|---|---|\n");
    'scenes: for name in &names {
        let scene = with_resolution(load_scene(name)?.scene, Some(settings.resolution));
        if let Some(line) = medium_line(&scene) {
            media_table.push_str(&line);
            media_table.push('\n');
        }
        let gbuffer = GBuffer::render(&scene, frame);
        let regions = Regions::classify(&scene, &gbuffer, REFERENCE_SEED);
        for boundary in BOUNDARIES {
            let media = media_with(&scene, boundary)?;
            progress.begin(
                &format!("{name} {}", boundary_name(boundary)),
                settings.replicas as u64,
                0,
            );
            let (mut replicas, mut truncated) = (Vec::new(), 0);
            for seed in 0..settings.replicas as u64 {
                let (image, cut) = render(&scene, &gbuffer, &media, seed, spp);
                replicas.push(image);
                truncated += cut;
                progress.step();
                if progress.stop_requested() {
                    progress.end();
                    break 'scenes;
                }
            }
            progress.end();
            let found = gaps(name, boundary, &replicas, &regions, truncated);
            if found.iter().all(|g| g.walk.mean == 0.0) {
                notes.push_str(&format!(
                    "\n{name}, {}: the walk is 0 in every replica (a delta light cannot be reached \
                     through a specular boundary); left out.\n",
                    boundary_name(boundary)
                ));
            } else {
                all.extend(found);
            }
        }
    }
    let table = markdown(&all);
    let json = json!({
        "schema": "reshift-model-gap/1",
        "resolution": [settings.resolution.0, settings.resolution.1],
        "replicas": settings.replicas,
        "spp_per_replica": spp,
        "confidence": CONFIDENCE,
        "gaps": all.iter().map(gap_json).collect::<Vec<_>>(),
    });
    lab::output::write_text(
        &out.join("results.json"),
        &serde_json::to_string_pretty(&json).expect("JSON values"),
    )?;
    Report {
        table: format!("{media_table}\n{table}{notes}"),
        findings: findings(&all),
        out,
        json,
    }
    .write()
}

fn percent([value, half]: [f64; 2]) -> String {
    format!("{:+.1}% ± {:.1}", 100.0 * value, 100.0 * half)
}

/// One row per scene, boundary and region: the walk's mean, then every part in percent of it.
pub fn markdown(gaps: &[Gap]) -> String {
    let mut out = String::from("| scene | boundary | region | px | walk ± s.e. |");
    for (name, _) in PARTS {
        let _ = write!(out, " {name} |");
    }
    out.push_str("\n|---|---|---|---:|---:|");
    out.push_str(&"---:|".repeat(PARTS.len()));
    out.push('\n');
    for g in gaps {
        let _ = write!(
            out,
            "| {} | {} | {} | {} | {:.3e} ± {:.1e} |",
            g.scene,
            boundary_name(g.boundary),
            g.region,
            g.pixels,
            g.walk.mean,
            g.walk.std_err
        );
        for (_, part) in &g.parts {
            let _ = write!(out, " {} |", percent(*part));
        }
        out.push('\n');
    }
    let cut: u64 = gaps
        .iter()
        .filter(|g| g.region == Region::Translucent)
        .map(|g| g.truncated)
        .sum();
    let _ = writeln!(
        out,
        "\nParts in percent of the walk's region mean, ± the 99% CI half-width over replicas. \
         Samples with a cut chain: {cut}."
    );
    out
}

fn gap_json(g: &Gap) -> Value {
    let parts: serde_json::Map<String, Value> = g
        .parts
        .iter()
        .map(|(name, [v, half])| (name.to_string(), json!({ "value": v, "ci_half": half })))
        .collect();
    json!({
        "scene": g.scene,
        "boundary": boundary_name(g.boundary),
        "region": g.region.name(),
        "pixels": g.pixels,
        "walk_mean": g.walk.mean,
        "walk_std_err": g.walk.std_err,
        "parts": parts,
        "truncated": g.truncated,
    })
}

/// The control of every scene and boundary (translucent pixels): path-traced zero and single
/// scattering agree with the walk's 0- and 1-collision tallies (99% CI contains 0).
fn findings(gaps: &[Gap]) -> String {
    let mut out =
        String::from("| scene | boundary | finding | holds | measured |\n|---|---|---|---|---|\n");
    for g in gaps.iter().filter(|g| g.region == Region::Translucent) {
        let Some(&(_, [v, half])) = g.parts.iter().find(|(name, _)| name.starts_with("control"))
        else {
            continue;
        };
        let holds = if (v).abs() <= half { "yes" } else { "**no**" };
        let _ = writeln!(
            out,
            "| {} | {} | path-traced orders 0+1 agree with the walk's (control) | {holds} | {} |",
            g.scene,
            boundary_name(g.boundary),
            percent([v, half])
        );
    }
    out
}
