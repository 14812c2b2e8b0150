//! A comparison's outputs ([`write`]): `table.md` (with verdicts over the baseline and a group
//! per denoiser), `table.csv`, `convergence.csv`, `results.json` ([`Results`]), the reference and
//! per-method images and maps ([`super::images`]), `figure.png` and `convergence.png`
//! ([`super::plots`], [`super::figure`]), the trajectory videos ([`super::video`]) and
//! `report.html` ([`super::html`]), from the
//! [`Outcome`] that [`crate::compare::run`] measured.

use engine::clock::Clock;
use engine::denoise::Denoiser;

use crate::compare::{Comparison, Outcome};
use crate::error::Error;
use crate::method_result::MethodResult;
use crate::output::write_text;

use super::images::write_comparison_images;
use super::results::{
    FrameReferenceEntry, MethodEntry, ReferenceEntry, ReferenceFlickerEntry, Results, RunEntry,
};
use super::video::write_videos;
use super::{figure, html, plots, tables};

/// What [`write`] wrote that a caller prints.
pub struct Written {
    /// The contents of `results.json`.
    pub results: Results,
    /// The contents of `table.md`.
    pub markdown: String,
}

/// Writes the outputs of `outcome`, the comparison `plan` measured, into its folder
/// (`outcome.out`).
pub fn write(plan: &Comparison, outcome: &Outcome) -> Result<Written, Error> {
    let out = &outcome.out;
    let reference = &outcome.reference.reference;
    let baseline = outcome.rows.iter().find(|r| r.method == plan.baseline);
    let groups = outcome.groups();
    // Every row with its replica-0 last frame.
    let labelled: Vec<(&MethodResult, String, &engine::Image)> = outcome
        .finals
        .iter()
        .filter_map(|f| {
            let (_, group) = groups.iter().find(|(d, _)| *d == f.denoiser)?;
            let row = group.iter().find(|r| r.method == f.method)?;
            Some((row, row.label(), &f.image))
        })
        .collect();
    let finals: Vec<(&str, &engine::Image)> =
        labelled.iter().map(|(_, l, i)| (l.as_str(), *i)).collect();
    let (images, scale) = write_comparison_images(out, &finals, reference)?;
    let scale_absolute = scale.absolute;
    let bands: Vec<figure::Band> = groups
        .iter()
        .map(|(denoiser, group)| figure::Band {
            denoiser: *denoiser,
            rows: group,
            baseline: group.iter().find(|r| r.method == plan.baseline),
            finals: labelled
                .iter()
                .filter(|(r, _, _)| r.denoiser == *denoiser)
                .map(|(r, _, i)| (r.method.as_str(), *i))
                .collect(),
        })
        .collect();
    let figures = plots::write_figures(out, &outcome.rows, &bands, reference, &outcome.regions)?;
    let (markdown, csv) = table_texts(plan, outcome, &groups);
    write_text(&out.join("table.md"), &markdown)?;
    write_text(&out.join("table.csv"), &csv)?;
    write_text(
        &out.join("convergence.csv"),
        &tables::convergence_csv(&outcome.rows),
    )?;
    let run = RunEntry {
        scene: plan.scene.name.clone(),
        backend: plan.backend.to_string(),
        clock: Clock::of(&plan.backend),
        width: reference.width,
        height: reference.height,
        frames: plan.frames,
        replicas: plan.replicas,
        first_seed: plan.first_seed,
        equal_time: plan.equal_time,
        baseline: baseline.map(|b| b.method.clone()),
        interrupted: outcome.interrupted,
    };
    let entries = labelled
        .iter()
        .zip(images)
        .map(|((r, _, _), files)| {
            let base = groups
                .iter()
                .find(|(d, _)| *d == r.denoiser)
                .and_then(|(_, g)| g.iter().find(|b| b.method == plan.baseline));
            MethodEntry::new(r, base, files)
        })
        .collect();
    let reference_entry =
        ReferenceEntry::new(reference, &outcome.reference.path, outcome.reference.cached);
    let mut results = Results::new(
        run,
        reference_entry,
        outcome
            .frame_references
            .iter()
            .map(FrameReferenceEntry::new)
            .collect(),
        &outcome.regions,
        scale,
        figures,
        outcome
            .denoised
            .iter()
            .map(|(d, _)| d.name().to_string())
            .collect(),
        outcome.denoise_errors.clone(),
        entries,
    );
    results.reference_flicker = outcome
        .reference_flicker
        .iter()
        .map(|(area, change)| ReferenceFlickerEntry {
            area: area.name().to_string(),
            change: *change,
        })
        .collect();
    if let Some(video) = &outcome.video {
        let videos = write_videos(out, video, scale_absolute)?;
        results.videos = videos.entries;
        results.video_notes = videos.notes;
    }
    write_text(&out.join("results.json"), &results.to_json_pretty())?;
    write_text(&out.join("report.html"), &html::report(&results, out)?)?;
    Ok(Written { results, markdown })
}

/// `table.md` and `table.csv` of the row `groups` of `outcome` (the raw rows, then each
/// denoiser's): per group its table with verdicts over the baseline, then the perceptual
/// metrics of every row and the denoisers' errors.
fn table_texts(
    plan: &Comparison,
    outcome: &Outcome,
    groups: &[(Option<Denoiser>, &[MethodResult])],
) -> (String, String) {
    let mut markdown = String::new();
    let mut csv = String::new();
    for (denoiser, group) in groups {
        let base = group.iter().find(|r| r.method == plan.baseline);
        if let Some(d) = denoiser {
            let counted = if plan.equal_time.is_some() {
                "counted in ms/frame and efficiency (equal time), as its mean over these rows"
            } else {
                "not counted in ms/frame and efficiency (equal spp)"
            };
            markdown.push_str(&format!(
                "\nDenoised with {d} (last frame of every replica; ratios to {}; the denoiser's \
                 time {counted}):\n\n",
                base.map_or("-".into(), |b| b.label())
            ));
        }
        markdown.push_str(&format!(
            "{}\n{}",
            tables::markdown(group, base),
            tables::verdict(group, base)
        ));
        if denoiser.is_some() {
            markdown.push_str(&format!("\n{}", tables::denoiser_time(group)));
        }
        let table = tables::csv(group, base);
        let skip = if csv.is_empty() { 0 } else { 1 };
        for line in table.lines().skip(skip) {
            csv.push_str(line);
            csv.push('\n');
        }
    }
    let all_rows: Vec<MethodResult> = groups.iter().flat_map(|(_, g)| g.iter().cloned()).collect();
    markdown.push_str(&format!("\n{}", tables::perceptual(&all_rows)));
    markdown.push_str(&format!(
        "\n{}",
        tables::flicker(&outcome.rows, &outcome.reference_flicker)
    ));
    markdown.push_str(&format!(
        "\n{}\n",
        tables::time_note(Clock::of(&plan.backend))
    ));
    for e in &outcome.denoise_errors {
        markdown.push_str(&format!("\nDenoiser: {e}\n"));
    }
    (markdown, csv)
}
