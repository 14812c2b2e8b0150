//! `report.html`: one page per comparison (every still image embedded as a base64 data URI, no
//! script) with the run's settings, the efficiency verdicts over the baseline, the inset
//! figure, the convergence plot, the error maps, the trajectory videos (animated PNGs, which
//! browsers play), the flicker table and the full table, all read from [`Results`] and the
//! images it names. The videos are linked, not embedded: they are files beside the page
//! (`video/`), a few megabytes each, which base64 would make a third larger inside it.

use std::fmt::Write as _;
use std::path::Path;

use crate::error::Error;
use crate::method_result::Measured;
use crate::report::results::{AreaEntry, MethodEntry, Results};
use crate::uncertainty::Interval;

use super::tables::{sig, verdict_word, with_ci};

const STYLE: &str = "body{font-family:sans-serif;margin:24px;color:#111;max-width:1500px}\
    table{border-collapse:collapse;margin:12px 0}td,th{border:1px solid #bbb;padding:3px 8px;\
    text-align:right;font-size:13px}th{background:#eee}td:first-child,th:first-child{text-align:left}\
    .better{background:#cdeccd}.worse{background:#f6cfcf}.inconclusive{background:#f3f3d8}\
    img{max-width:100%;border:1px solid #ddd}.maps img{width:260px}\
    .note{color:#555;font-size:13px}";

/// RFC 4648 base64 of `bytes`, with padding.
pub fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let n = chunk
            .iter()
            .enumerate()
            .fold(0u32, |n, (i, &b)| n | (b as u32) << (16 - 8 * i));
        for i in 0..4 {
            if i <= chunk.len() {
                out.push(ALPHABET[(n >> (18 - 6 * i) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// `text` with `& < > "` escaped.
pub fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// An `<img>` of the PNG `file` in `out`, embedded.
fn image(out: &Path, file: &str, alt: &str) -> Result<String, Error> {
    let path = out.join(file);
    let bytes = std::fs::read(&path).map_err(|e| Error::Io(format!("{}: {e}", path.display())))?;
    Ok(format!(
        "<img src=\"data:image/png;base64,{}\" alt=\"{}\">",
        base64(&bytes),
        escape(alt)
    ))
}

/// The entry's row name: the method, with `+<denoiser>` for denoised frames.
fn label(m: &MethodEntry) -> String {
    match &m.denoiser {
        Some(d) => format!("{}+{d}", m.method),
        None => m.method.clone(),
    }
}

/// The groups of entries: the raw frames (`None`), then each denoiser's.
fn groups(r: &Results) -> Vec<Option<&str>> {
    std::iter::once(None)
        .chain(r.denoisers.iter().map(|d| Some(d.as_str())))
        .collect()
}

fn measured(value: Option<f64>, ci: Option<Interval>) -> Option<Measured> {
    value.map(|value| Measured { value, ci })
}

/// Seconds `value` and their interval in milliseconds.
fn milliseconds(value: f64, ci: Option<Interval>) -> Option<Measured> {
    let ms = |s: f64| 1e3 * s;
    measured(
        Some(ms(value)),
        ci.map(|i| Interval {
            lo: ms(i.lo),
            hi: ms(i.hi),
        }),
    )
}

/// The page of `results`, whose images lie in `out`.
pub fn report(results: &Results, out: &Path) -> Result<String, Error> {
    let r = results;
    let mut page = format!(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
         <title>reshift compare: {scene}</title><style>{STYLE}</style></head><body>\n\
         <h1>reshift compare: {scene}</h1>\n",
        scene = escape(&r.scene)
    );
    let frame_spp: Vec<String> = r
        .frame_references
        .iter()
        .filter(|f| f.frame != r.frame)
        .map(|f| f.spp.to_string())
        .collect();
    let _ = writeln!(
        page,
        "<p>{w}×{h}, {frames} frames (tables: frame {frame}), {k} replicas per method, backend \
         {backend} (ms/frame: {clock}; wall ms/frame: wall time, reported only), budget {mode}. \
         Reference of frame {frame}: {spp} spp in {batches} batches; \
         earlier frames: {earlier}. Intervals: {conf}% confidence, {how}. Bias: {bconf}% \
         Student-t over replicas.{stopped}</p>",
        w = r.width,
        h = r.height,
        frames = r.frames,
        frame = r.frame,
        k = r.replicas,
        backend = escape(&r.backend),
        clock = escape(&r.clock),
        mode = r.budget.mode,
        spp = r.reference.spp,
        batches = r.reference.batches,
        earlier = if frame_spp.is_empty() {
            "not measured".to_string()
        } else {
            format!("{} spp each", frame_spp[0])
        },
        conf = 100.0 * r.confidence,
        how = escape(&r.interval_method),
        bconf = 100.0 * r.bias_confidence,
        stopped = if r.interrupted {
            " <b>Interrupted: partial results.</b>"
        } else {
            ""
        },
    );
    for group in groups(r) {
        verdicts(&mut page, r, group);
    }
    for e in &r.denoise_errors {
        let _ = writeln!(page, "<p><b>Denoiser:</b> {}</p>", escape(e));
    }
    let _ = writeln!(
        page,
        "<h2>Figure</h2>{}",
        image(out, &r.figures.figure, "figure")?
    );
    let _ = writeln!(
        page,
        "<h2>Convergence over frames</h2>{}",
        image(out, &r.figures.convergence, "convergence")?
    );
    page.push_str(
        "<h2>Images and error maps (last frame, replica 0)</h2>\n<table class=\"maps\">\
         <tr><th>method</th><th>frame</th><th>absolute error</th><th>relative error</th>\
         <th>FLIP</th><th>low-frequency error</th></tr>",
    );
    for m in &r.methods {
        let name = label(m);
        let _ = writeln!(
            page,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            escape(&name),
            image(out, &m.images.final_png, &name)?,
            image(out, &m.images.abs_error_png, "absolute error")?,
            image(out, &m.images.rel_error_png, "relative error")?,
            image(out, &m.images.flip_png, "FLIP")?,
            image(out, &m.images.low_frequency_png, "low-frequency error")?
        );
    }
    page.push_str("</table>\n");
    videos(&mut page, r);
    flicker(&mut page, r);
    full_table(&mut page, r);
    page.push_str(
        "<p class=\"note\">Data: <a href=\"results.json\">results.json</a>, \
         <a href=\"table.csv\">table.csv</a>, <a href=\"convergence.csv\">convergence.csv</a> \
         (docs/results-schema.md).</p>\n</body></html>\n",
    );
    Ok(page)
}

/// The efficiency ratio over the baseline per method and area, coloured by its verdict, for
/// the raw frames (`denoiser` `None`) or one denoiser's.
fn verdicts(page: &mut String, r: &Results, denoiser: Option<&str>) {
    let Some(baseline) = &r.baseline else {
        if denoiser.is_none() {
            page.push_str("<p>No baseline among the methods: no efficiency ratios.</p>\n");
        }
        return;
    };
    let in_group = |m: &&MethodEntry| m.denoiser.as_deref() == denoiser;
    let areas: Vec<&str> = r
        .methods
        .iter()
        .filter(in_group)
        .find(|m| &m.method == baseline)
        .map(|m| m.areas.iter().map(|a| a.area.as_str()).collect())
        .unwrap_or_default();
    let (title, through) = match denoiser {
        None => (String::new(), String::new()),
        Some(d) => (
            format!(", denoised with {}", escape(d)),
            format!(
                " Both through {}; its time is counted at equal time only.",
                escape(d)
            ),
        ),
    };
    let _ = write!(
        page,
        "<h2>Efficiency over {b}{title}</h2><p>Ratio of 1/(MSE·s) per frame to {b}'s, with its \
         {c}% interval; green: better (interval above 1), red: worse, yellow: \
         inconclusive.{through}</p><table><tr><th>method</th>",
        b = escape(baseline),
        c = 100.0 * r.confidence
    );
    for a in &areas {
        let _ = write!(page, "<th>{a}</th>");
    }
    page.push_str("</tr>\n");
    for m in r
        .methods
        .iter()
        .filter(in_group)
        .filter(|m| &m.method != baseline)
    {
        let _ = write!(page, "<tr><td>{}</td>", escape(&label(m)));
        for a in &areas {
            let cell = m
                .areas
                .iter()
                .find(|e| e.area == *a)
                .and_then(|e| measured(e.efficiency_ratio, e.efficiency_ratio_ci));
            match cell {
                Some(x) => {
                    let word = verdict_word(&x);
                    let _ = write!(
                        page,
                        "<td class=\"{word}\">{} {word}</td>",
                        with_ci(Some(x))
                    );
                }
                None => page.push_str("<td>-</td>"),
            }
        }
        page.push_str("</tr>\n");
    }
    page.push_str("</table>\n");
}

/// Each method's trajectory video, the animated PNG (and the MP4 where one was written), linked,
/// with a caption saying what its tiles show.
fn videos(page: &mut String, r: &Results) {
    if r.videos.is_empty() {
        return;
    }
    let _ = writeln!(
        page,
        "<h2>Trajectories (replica 0)</h2><p class=\"note\">Every frame 0–{} at {} frames per \
         second, looping: the method's frame, the reference of the same frame, and the luminance \
         of |I − R| on the absolute error maps' scale (0 to {}).</p>",
        r.frames - 1,
        super::video::FPS,
        sig(r.error_map_scale.absolute)
    );
    for note in &r.video_notes {
        let _ = writeln!(page, "<p class=\"note\">Videos: {}.</p>", escape(note));
    }
    for v in &r.videos {
        let _ = write!(
            page,
            "<figure class=\"video\"><img src=\"{}\" alt=\"{} trajectory\">",
            escape(&v.apng),
            escape(&v.method)
        );
        if let Some(mp4) = &v.mp4 {
            let _ = write!(
                page,
                "<br><video controls loop muted src=\"{}\"></video>",
                escape(mp4)
            );
        }
        let _ = writeln!(
            page,
            "<figcaption>{}: animated PNG{}</figcaption></figure>",
            escape(&v.method),
            if v.mp4.is_some() {
                ", and H.264 MP4"
            } else {
                ""
            }
        );
    }
}

/// The flicker of every entry that has one per area with its interval, under the references'
/// own change.
fn flicker(page: &mut String, r: &Results) {
    if r.reference_flicker.is_empty() {
        return;
    }
    let _ = write!(
        page,
        "<h2>Temporal stability (flicker)</h2><p>Mean over frames and pixels of \
         |e<sub>t</sub> − e<sub>t−1</sub>|, e<sub>t</sub> = Y(I<sub>t</sub>) − Y(R<sub>t</sub>) the \
         luminance error of frame t against its reference (lower: steadier), with its {}% interval \
         over replicas. The reference row is its own change |Y(R<sub>t</sub>) − \
         Y(R<sub>t−1</sub>)|: the camera's motion plus its noise.</p><table><tr><th>method</th>",
        100.0 * r.confidence
    );
    for a in &r.reference_flicker {
        let _ = write!(page, "<th>{}</th>", a.area);
    }
    page.push_str("</tr>\n<tr><td>reference</td>");
    for a in &r.reference_flicker {
        let _ = write!(page, "<td>{}</td>", sig(a.change));
    }
    page.push_str("</tr>\n");
    for m in r.methods.iter().filter(|m| !m.flicker.is_empty()) {
        let _ = write!(page, "<tr><td>{}</td>", escape(&label(m)));
        for a in &r.reference_flicker {
            let cell = m
                .flicker
                .iter()
                .find(|f| f.area == a.area)
                .and_then(|f| measured(Some(f.flicker), f.flicker_ci));
            let _ = write!(page, "<td>{}</td>", with_ci(cell));
        }
        page.push_str("</tr>\n");
    }
    page.push_str("</table>\n");
}

/// Every method and area with every number and its interval.
fn full_table(page: &mut String, r: &Results) {
    let _ = write!(
        page,
        "<h2>All numbers (frame {})</h2><table><tr><th>method</th><th>spp</th><th>area</th>\
         <th>px</th><th>MSE</th><th>relMSE</th><th>bias ± 99%</th><th>ms/frame</th>\
         <th>wall ms/frame</th><th>efficiency</th><th>eff. ratio</th><th>MSE ratio</th><th>FLIP</th>\
         <th>low-freq. MSE</th></tr>\n",
        r.frame
    );
    for m in &r.methods {
        let ms = milliseconds(m.seconds_per_frame, m.seconds_per_frame_ci);
        let wall = milliseconds(m.wall_seconds_per_frame, m.wall_seconds_per_frame_ci);
        for a in &m.areas {
            let AreaEntry {
                area,
                pixels,
                bias,
                bias_ci99,
                ..
            } = a;
            let bias = match bias_ci99 {
                Some(ci) => format!("{} ± {}", sig(*bias), sig(*ci)),
                None => sig(*bias),
            };
            let _ = writeln!(
                page,
                "<tr><td>{}</td><td>{}</td><td>{area}</td><td>{pixels}</td><td>{}</td><td>{}</td>\
                 <td>{bias}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td>\
                 <td>{}</td></tr>",
                escape(&label(m)),
                m.spp,
                with_ci(measured(Some(a.mse), a.mse_ci)),
                with_ci(measured(Some(a.rel_mse), a.rel_mse_ci)),
                with_ci(ms),
                with_ci(wall),
                with_ci(measured(a.efficiency, a.efficiency_ci)),
                with_ci(measured(a.efficiency_ratio, a.efficiency_ratio_ci)),
                with_ci(measured(a.mse_ratio, a.mse_ratio_ci)),
                with_ci(measured(a.flip, a.flip_ci)),
                with_ci(measured(a.low_frequency_mse, a.low_frequency_mse_ci)),
            );
        }
    }
    page.push_str("</table>\n");
}

#[cfg(test)]
mod tests {
    use super::*;

    /// RFC 4648 §10 test vectors.
    #[test]
    fn base64_matches_the_rfc_vectors() {
        for (plain, coded) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(base64(plain.as_bytes()), coded, "{plain:?}");
        }
        assert_eq!(base64(&[0xff, 0xfe]), "//4=");
    }

    #[test]
    fn markup_is_escaped() {
        assert_eq!(escape("a<b>&\"c\""), "a&lt;b&gt;&amp;&quot;c&quot;");
    }
}
