//! `report.html` opens in a browser and shows something: a small comparison writes it, headless
//! Chromium renders it to a screenshot, and the screenshot must not be blank (enough non-white
//! pixels and distinct colours). A blank page, rendered the same way, must fail the same check.
//!
//! Needs Debian's `chromium` (`scripts/test` installs it when run as root; `RESHIFT_CHROMIUM`
//! names another binary). Without it the test says why and passes, unless
//! `RESHIFT_REQUIRE_BROWSER=1` (set by `.ci/run` wherever Chromium is or can be installed),
//! when it fails.

use std::path::{Path, PathBuf};
use std::process::Command;

use engine::Backend;
use engine::denoise::Denoiser;
use lab::compare::{Comparison, parse_methods, run};
use lab::progress::Silent;
use lab::reference_cache::ReferenceSource;
use lab::report;
use lab::report::html::base64;
use lab::scenes::with_resolution;
use sss::scene::Scene;

/// Window of the screenshot.
const WINDOW: (u32, u32) = (1280, 1600);

/// The Chromium binary, or why there is none.
fn chromium() -> Result<PathBuf, String> {
    let names = std::env::var("RESHIFT_CHROMIUM")
        .map(|n| vec![n])
        .unwrap_or_else(|_| vec!["chromium".into(), "chromium-browser".into()]);
    let path = std::env::var_os("PATH").unwrap_or_default();
    names
        .iter()
        .flat_map(|n| {
            let n = PathBuf::from(n);
            if n.is_absolute() {
                vec![n]
            } else {
                std::env::split_paths(&path).map(|d| d.join(&n)).collect()
            }
        })
        .find(|p| p.is_file())
        .ok_or_else(|| format!("no Chromium found (tried {names:?} on PATH)"))
}

/// Renders `page` headless into a PNG screenshot in `dir` and decodes it.
fn screenshot(browser: &Path, page: &Path, dir: &Path) -> image::RgbImage {
    let shot = dir.join(format!(
        "{}.png",
        page.file_stem().unwrap().to_string_lossy()
    ));
    let profile = dir.join(format!(
        "profile-{}",
        page.file_stem().unwrap().to_string_lossy()
    ));
    let output = Command::new(browser)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--hide-scrollbars",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .arg(format!("--screenshot={}", shot.display()))
        .arg(format!("--window-size={},{}", WINDOW.0, WINDOW.1))
        .arg(format!("file://{}", page.display()))
        .output()
        .expect("run chromium");
    assert!(
        shot.is_file(),
        "no screenshot; chromium exited {:?}: {}",
        output.status,
        String::from_utf8_lossy(&output.stderr)
    );
    image::open(&shot).expect("screenshot decodes").to_rgb8()
}

/// `(fraction of non-white pixels, distinct colours)` of a screenshot.
fn content(shot: &image::RgbImage) -> (f64, usize) {
    let pixels = shot.pixels().count() as f64;
    let coloured = shot.pixels().filter(|p| p.0 != [255, 255, 255]).count() as f64;
    let distinct: std::collections::HashSet<[u8; 3]> = shot.pixels().map(|p| p.0).collect();
    (coloured / pixels, distinct.len())
}

/// The screenshot shows a page with images: ≥ 10% non-white pixels and ≥ 500 distinct colours
/// (text alone anti-aliases to a few hundred greys; the figures bring thousands).
fn not_blank(shot: &image::RgbImage) -> Result<(), String> {
    let (fraction, colours) = content(shot);
    if fraction >= 0.10 && colours >= 500 {
        Ok(())
    } else {
        Err(format!(
            "{:.1}% non-white pixels, {colours} colours",
            100.0 * fraction
        ))
    }
}

/// Every frame of the animated PNG at `path`, as RGB bytes.
fn apng_frames(path: &Path) -> Vec<Vec<u8>> {
    let file = std::fs::File::open(path).unwrap();
    let mut reader = png::Decoder::new(std::io::BufReader::new(file))
        .read_info()
        .unwrap();
    let control = *reader.info().animation_control().expect("animated");
    assert_eq!(control.num_plays, 0, "loops forever");
    (0..control.num_frames)
        .map(|_| {
            let mut buffer = vec![0; reader.output_buffer_size().unwrap()];
            reader.next_frame(&mut buffer).unwrap();
            buffer
        })
        .collect()
}

/// The report's videos: each APNG holds every frame, no two consecutive alike, none of one
/// colour (decoded here); the report links each file; and Chromium's own image decoder (the
/// WebCodecs `ImageDecoder` behind `<img>`) reads each as an animation that loops forever, with
/// every frame, consecutive frames different and none blank. (Headless screenshots cannot show
/// it play: they capture an animated image at its first frame whatever the time budget.)
fn videos_play(browser: &Path, out: &Path, html: &str, dir: &Path) {
    let results: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("results.json")).unwrap()).unwrap();
    let videos = results["videos"].as_array().unwrap();
    assert_eq!(videos.len(), 2);
    for (k, v) in videos.iter().enumerate() {
        let file = v["apng"].as_str().unwrap();
        assert!(
            html.contains(&format!("<img src=\"{file}\"")),
            "{file} is not linked"
        );
        let frames = apng_frames(&out.join(file));
        assert_eq!(frames.len(), 3);
        assert!(frames.windows(2).all(|w| w[0] != w[1]), "{v}");
        for f in &frames {
            let distinct: std::collections::HashSet<&[u8]> = f.chunks(3).collect();
            assert!(distinct.len() > 100, "{v}: {} colours", distinct.len());
        }
        let seen = chromium_decodes(
            browser,
            &out.join(file),
            &dir.join(format!("video{k}.html")),
        );
        let want =
            "animated=true frames=3 repetition=Infinity consecutive_differ=true colours_min=";
        assert!(seen.starts_with(want), "{file}: Chromium reads {seen:?}");
        let colours: usize = seen[want.len()..].parse().unwrap();
        assert!(
            colours > 100,
            "{file}: a frame of {colours} colours in Chromium"
        );
    }
    // Control: a still PNG of the same report is read as one frame, not an animation.
    let still = results["methods"][0]["images"]["final_png"].as_str();
    let still = out.join(still.expect("a final frame in results.json"));
    let seen = chromium_decodes(browser, &still, &dir.join("still.html"));
    assert!(seen.starts_with("animated=false frames=1 "), "{seen}");
}

/// What Chromium's `ImageDecoder` reads of the PNG `file`: a line `animated=… frames=…
/// repetition=… consecutive_differ=… colours_min=…` (the fewest distinct colours of a frame),
/// from a page written to `page` and printed with `--dump-dom` once its script has run.
fn chromium_decodes(browser: &Path, file: &Path, page: &Path) -> String {
    let bytes = std::fs::read(file).unwrap();
    let script = format!(
        r#"(async () => {{
  const out = document.getElementById("r");
  try {{
    const bin = atob("{}");
    const data = Uint8Array.from(bin, c => c.charCodeAt(0));
    const decoder = new ImageDecoder({{data, type: "image/png"}});
    await decoder.tracks.ready;
    await decoder.completed;
    const track = decoder.tracks.selectedTrack;
    let previous = null, differ = true, fewest = Infinity;
    for (let i = 0; i < track.frameCount; i++) {{
      const {{image}} = await decoder.decode({{frameIndex: i}});
      const canvas = new OffscreenCanvas(image.displayWidth, image.displayHeight);
      const context = canvas.getContext("2d");
      context.drawImage(image, 0, 0);
      const px = context.getImageData(0, 0, canvas.width, canvas.height).data;
      const colours = new Set();
      for (let j = 0; j < px.length; j += 4) colours.add((px[j] << 16) | (px[j + 1] << 8) | px[j + 2]);
      fewest = Math.min(fewest, colours.size);
      const text = px.join(",");
      if (previous !== null && text === previous) differ = false;
      previous = text;
    }}
    out.textContent = `animated=${{track.animated}} frames=${{track.frameCount}} ` +
      `repetition=${{track.repetitionCount}} consecutive_differ=${{differ}} colours_min=${{fewest}}`;
  }} catch (e) {{
    out.textContent = "error " + e;
  }}
}})();"#,
        base64(&bytes)
    );
    std::fs::write(
        page,
        format!("<!DOCTYPE html><html><body><pre id=\"r\">pending</pre><script>{script}</script></body></html>"),
    )
    .unwrap();
    // The decoding is real work on Chromium's threads while the page's clock is virtual: on a
    // loaded machine the budget can run out first, leaving "pending". Only then is the page
    // read again with a longer budget; a result, right or wrong, is returned as it is.
    let mut seen = String::new();
    for budget in [10_000, 60_000, 300_000] {
        let output = Command::new(browser)
            .args([
                "--headless",
                "--no-sandbox",
                "--disable-gpu",
                "--no-first-run",
            ])
            .arg(format!(
                "--user-data-dir={}",
                page.with_extension("profile").display()
            ))
            .arg(format!("--virtual-time-budget={budget}"))
            .arg("--dump-dom")
            .arg(format!("file://{}", page.display()))
            .output()
            .expect("run chromium");
        let dom = String::from_utf8_lossy(&output.stdout);
        let start = dom
            .find("<pre id=\"r\">")
            .map(|i| i + "<pre id=\"r\">".len());
        seen = start
            .and_then(|i| dom[i..].find("</pre>").map(|j| dom[i..i + j].to_string()))
            .unwrap_or_else(|| format!("no result in the DOM: {}", &dom[..dom.len().min(300)]));
        if seen != "pending" {
            break;
        }
    }
    seen
}

#[test]
fn the_report_renders_in_a_browser() {
    let browser = match chromium() {
        Ok(b) => b,
        Err(reason) if std::env::var("RESHIFT_REQUIRE_BROWSER").as_deref() != Ok("1") => {
            eprintln!("skipped: {reason}; set RESHIFT_REQUIRE_BROWSER=1 to fail instead");
            return;
        }
        Err(reason) => panic!("RESHIFT_REQUIRE_BROWSER=1: {reason}"),
    };
    let dir = std::env::temp_dir().join(format!("reshift-report-html-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let plan = Comparison {
        scene: with_resolution(Scene::builtin("bumpy").unwrap(), Some((48, 36))),
        scene_key: "bumpy".into(),
        methods: parse_methods(&["pt", "restir:hybrid"]).unwrap(),
        baseline: "pt".into(),
        replicas: 3,
        first_seed: 0,
        frames: 3,
        equal_time: None,
        reference: ReferenceSource::Cache {
            dir: dir.join("cache"),
            spp: 16,
            batch_spp: 8,
        },
        frame_reference_spp: Some(16),
        out: dir.join("out"),
        backend: Backend::Cpu,
        // Every denoiser installed here (the built-in filter always): the denoised images are
        // part of the page.
        video: true,
        denoise: Denoiser::ALL
            .into_iter()
            .filter(|d| d.available().is_ok())
            .collect(),
    };
    let outcome = run(&plan, &mut Silent).unwrap();
    report::write(&plan, &outcome).unwrap();
    assert!(
        outcome.denoise_errors.is_empty(),
        "{:?}",
        outcome.denoise_errors
    );
    let page = outcome.out.join("report.html");
    let html = std::fs::read_to_string(&page).unwrap();
    assert!(
        !html.contains("src=\"http") && !html.contains("<script"),
        "no remote resource, no script"
    );
    // Embedded: the figure and the convergence plot, then per entry (2 methods, raw and through
    // each denoiser) its frame and four maps; linked: a video per method, beside the page.
    let entries = 2 * (1 + plan.denoise.len());
    assert_eq!(
        html.matches("data:image/png;base64,").count(),
        2 + 5 * entries
    );
    assert_eq!(html.matches("<img src=\"video/").count(), 2);
    assert!(html.contains("Temporal stability (flicker)"));
    for d in &plan.denoise {
        assert!(html.contains(&format!("restir:hybrid+{d}")), "{d} rows");
    }
    let shot = screenshot(&browser, &page, &dir);
    assert_eq!(shot.dimensions(), WINDOW);
    not_blank(&shot).unwrap();
    videos_play(&browser, &outcome.out, &html, &dir);
    // Negative control: a blank page fails the same check.
    let blank = dir.join("blank.html");
    std::fs::write(&blank, "<!DOCTYPE html><html><body></body></html>").unwrap();
    let blank_shot = screenshot(&browser, &blank, &dir);
    assert!(not_blank(&blank_shot).is_err(), "a blank page passed");
    std::fs::remove_dir_all(&dir).unwrap();
}
