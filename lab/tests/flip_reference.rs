//! [`lab::flip`] (the `nv-flip` crate, NVIDIA's C++ FLIP 1.2) agrees with NVIDIA's reference
//! implementation, the `flip-evaluator` Python package: for synthetic frame pairs (a noisy
//! rendering, a smooth one with blotches, edges moved by a pixel), both frames are tonemapped
//! and written as PNG, `flip_evaluator.evaluate(reference, test, "LDR")` runs on them at the
//! same 67 pixels per degree, and the mean FLIP must agree within 1e-3 (FLIP's values lie in
//! [0, 1]; the two implementations differ only in floating-point order and version, so a larger
//! gap would be a different algorithm or a different input). The largest per-pixel difference
//! is printed.
//!
//! Needs `python3` with `flip_evaluator` (`scripts/test` installs it with pip when it can).
//! Without it the test says why and passes, unless `RESHIFT_REQUIRE_FLIP=1` (set by `.ci/run`),
//! when it fails.

use std::path::Path;
use std::process::Command;

use engine::Image;
use engine::image::tonemap;
use glam::{DVec3, Vec3};
use lab::flip::{PIXELS_PER_DEGREE, area_mean, flip_map};
use restir::rng::StreamKey;

const W: u32 = 96;
const H: u32 = 64;

/// Agreement required of the two means.
const MEAN_TOLERANCE: f64 = 1e-3;

/// Reads two PNGs, runs LDR-FLIP, writes the map as little-endian f32 and prints the mean.
const EVALUATE: &str = r#"
import sys, flip_evaluator
reference, test, out, ppd = sys.argv[1], sys.argv[2], sys.argv[3], float(sys.argv[4])
error_map, mean, _ = flip_evaluator.evaluate(
    flip_evaluator.load(reference), flip_evaluator.load(test), "LDR",
    applyMagma=False, parameters={"ppd": ppd})
error_map.astype("<f4").tofile(out)
print(repr(float(mean)))
"#;

/// Why `python3` cannot run `flip_evaluator` here, if it cannot.
fn flip_evaluator_missing() -> Option<String> {
    match Command::new("python3")
        .args(["-c", "import flip_evaluator"])
        .output()
    {
        Err(e) => Some(format!("python3 could not be run: {e}")),
        Ok(o) if !o.status.success() => Some(format!(
            "python3 cannot import flip_evaluator ({})",
            String::from_utf8_lossy(&o.stderr)
                .trim()
                .lines()
                .last()
                .unwrap_or("")
        )),
        Ok(_) => None,
    }
}

/// A scene-like reference: a bright disc, a dark square, a horizontal gradient and fine stripes.
fn reference() -> Vec<DVec3> {
    (0..W * H)
        .map(|p| {
            let (x, y) = ((p % W) as f64, (p / W) as f64);
            let (dx, dy) = (x - 30.0, y - 30.0);
            if dx * dx + dy * dy < 225.0 {
                DVec3::new(3.0, 1.5, 0.6)
            } else if (60.0..80.0).contains(&x) && (20.0..44.0).contains(&y) {
                DVec3::splat(0.02)
            } else if y > 52.0 && (x as u32 / 2).is_multiple_of(2) {
                DVec3::new(0.9, 0.9, 1.2)
            } else {
                DVec3::new(0.1 + x / 120.0, 0.3, 0.5 - x / 400.0)
            }
        })
        .collect()
}

fn image(f: impl Fn(usize, DVec3) -> DVec3, reference: &[DVec3]) -> Image {
    Image {
        width: W,
        height: H,
        pixels: reference
            .iter()
            .enumerate()
            .map(|(p, r)| f(p, *r).as_vec3())
            .collect(),
    }
}

/// The frames compared with the reference, by name.
fn frames(reference: &[DVec3]) -> Vec<(&'static str, Image)> {
    let mut stream = StreamKey::new(0, 0, 0xF11B, 0).stream(1);
    let noise: Vec<f64> = (0..reference.len()).map(|_| stream.next_f64()).collect();
    vec![
        // Monte Carlo-like noise: each pixel scaled by a factor uniform on [0.2, 1.8].
        ("noisy", image(|p, r| r * (0.2 + 1.6 * noise[p]), reference)),
        // A denoiser's blotches: a smooth multiplicative error of ±20%.
        (
            "blotchy",
            image(
                |p, r| {
                    let (x, y) = ((p as u32 % W) as f64, (p as u32 / W) as f64);
                    r * (1.0 + 0.2 * (x / 9.0).sin() * (y / 7.0).cos())
                },
                reference,
            ),
        ),
        // Every edge moved one pixel to the right.
        (
            "shifted",
            image(|p, _| reference[p.saturating_sub(1)], reference),
        ),
    ]
}

/// Writes the tonemapped frame as an 8-bit PNG: what [`flip_map`] compares.
fn write_tonemapped(path: &Path, pixels: impl Iterator<Item = Vec3>) {
    let rgb: Vec<u8> = pixels.flat_map(tonemap).collect();
    image::RgbImage::from_raw(W, H, rgb)
        .unwrap()
        .save(path)
        .unwrap();
}

#[test]
fn nv_flip_agrees_with_nvidias_flip_evaluator() {
    if let Some(why) = flip_evaluator_missing() {
        if std::env::var("RESHIFT_REQUIRE_FLIP").as_deref() == Ok("1") {
            panic!("RESHIFT_REQUIRE_FLIP=1 but {why}");
        }
        eprintln!("flip_reference: skipped: {why}");
        return;
    }
    let dir = std::env::temp_dir().join(format!("reshift-flip-ref-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let reference = reference();
    let reference_png = dir.join("reference.png");
    write_tonemapped(&reference_png, reference.iter().map(|r| r.as_vec3()));
    let all: Vec<usize> = (0..reference.len()).collect();
    for (name, frame) in frames(&reference) {
        let ours = flip_map(&frame, &reference).unwrap();
        let test_png = dir.join(format!("{name}.png"));
        write_tonemapped(&test_png, frame.pixels.iter().copied());
        let theirs_path = dir.join(format!("{name}.f32"));
        let output = Command::new("python3")
            .args(["-c", EVALUATE])
            .args([&reference_png, &test_png, &theirs_path])
            .arg(PIXELS_PER_DEGREE.to_string())
            .output()
            .unwrap();
        assert!(
            output.status.success(),
            "flip_evaluator failed on {name}: {}",
            String::from_utf8_lossy(&output.stderr)
        );
        let their_mean: f64 = String::from_utf8_lossy(&output.stdout)
            .trim()
            .parse()
            .unwrap();
        let theirs: Vec<f32> = std::fs::read(&theirs_path)
            .unwrap()
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes(b.try_into().unwrap()))
            .collect();
        assert_eq!(theirs.len(), ours.len(), "{name}: map sizes");
        let our_mean = area_mean(&ours, &all);
        let max_diff = ours
            .iter()
            .zip(&theirs)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0f32, f32::max);
        eprintln!(
            "{name}: mean FLIP nv-flip {our_mean:.6}, flip-evaluator {their_mean:.6} \
             (difference {:.2e}); largest per-pixel difference {max_diff:.2e}",
            (our_mean - their_mean).abs()
        );
        assert!(
            (our_mean - their_mean).abs() <= MEAN_TOLERANCE,
            "{name}: mean FLIP {our_mean} (nv-flip) against {their_mean} (flip-evaluator)"
        );
        // The frames differ visibly from the reference: a vacuous agreement at 0 is no check.
        assert!(our_mean > 0.01, "{name}: mean FLIP {our_mean}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
