//! `reshift view` end to end. Without a display or a Vulkan device it says so in one line and
//! exits non-zero. On a virtual X display (Xvfb) with lavapipe, a script switches the preset by
//! key and moves the camera; the screenshots the viewer takes of its own window are not blank,
//! an unchanged step leaves the rendered part unchanged, the preset switch and the camera move
//! change it; the window closes cleanly on a scripted close and on Ctrl-C (SIGINT), and the
//! recording holds one frame and one pose per rendered frame.
//!
//! Xvfb missing: the window tests say why and skip, unless `RESHIFT_REQUIRE_DISPLAY=1` (CI); the
//! same for Vulkan with `RESHIFT_REQUIRE_VULKAN=1`.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::sync::atomic::{AtomicU32, Ordering};
use std::time::{Duration, Instant};

/// Image size of every window test, and the screen pixels per image pixel.
const WIDTH: u32 = 64;
const HEIGHT: u32 = 48;
const SCALE: u32 = 4;

/// How long a viewer run may take on lavapipe (kernel compilation included) before the test
/// fails rather than hangs.
const PATIENCE: Duration = Duration::from_secs(300);

fn reshift() -> Command {
    Command::new(env!("CARGO_BIN_EXE_reshift"))
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A fresh folder for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("reshift-view-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

/// Exit status 1 and one stderr line `reshift: …` containing `needle`, no panic.
fn fails_in_one_line(o: &Output, needle: &str) {
    let text = stderr(o);
    assert_eq!(o.status.code(), Some(1), "{text}");
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 1, "{text}");
    assert!(lines[0].starts_with("reshift: "), "{text}");
    assert!(text.contains(needle), "{text}");
    assert!(!text.contains("panicked"), "{text}");
}

fn view_args() -> Vec<String> {
    [
        "view",
        "--scene",
        "bumpy",
        "--resolution",
        "64x48",
        "--window",
        "2",
    ]
    .into_iter()
    .map(String::from)
    .chain(["--scale".into(), SCALE.to_string()])
    .collect()
}

#[test]
fn without_a_display_it_says_so_in_one_line() {
    let o = reshift()
        .args(view_args())
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .expect("run reshift");
    fails_in_one_line(&o, "no display");
}

#[test]
fn without_a_vulkan_device_it_says_so_in_one_line() {
    let o = reshift()
        .args(view_args())
        // A display is named (never opened: the device is looked for first).
        .env("DISPLAY", ":12345")
        .env("VK_ICD_FILENAMES", "/nonexistent/icd.json")
        .env("VK_DRIVER_FILES", "/nonexistent/icd.json")
        .output()
        .expect("run reshift");
    fails_in_one_line(&o, "Vulkan");
}

/// Lavapipe's ICD file: the window tests render and present on it.
fn lavapipe() -> Option<PathBuf> {
    std::fs::read_dir("/usr/share/vulkan/icd.d")
        .ok()?
        .flatten()
        .map(|e| e.path())
        .find(|p| {
            p.file_name()
                .is_some_and(|n| n.to_string_lossy().starts_with("lvp_icd"))
        })
}

/// Why the window tests cannot run here, or `None`; a requirement (CI) turns a reason into a
/// failure.
fn unavailable(test: &str) -> Option<String> {
    let reason = if Command::new("Xvfb").arg("-help").output().is_err() {
        Some((
            "RESHIFT_REQUIRE_DISPLAY",
            "Xvfb is not installed (apt-get install xvfb)".to_string(),
        ))
    } else if lavapipe().is_none() {
        Some((
            "RESHIFT_REQUIRE_VULKAN",
            "lavapipe is not installed (apt-get install mesa-vulkan-drivers)".to_string(),
        ))
    } else {
        None
    }?;
    let (required, why) = reason;
    if std::env::var(required).as_deref() == Ok("1") {
        panic!("{test}: {required}=1 but {why}");
    }
    eprintln!("{test}: skipped: {why}");
    Some(why)
}

/// An Xvfb server on a free display number, stopped on drop.
struct Xvfb {
    child: Child,
    display: String,
}

impl Xvfb {
    fn start() -> Xvfb {
        // Pid-spread numbers so test processes rarely race for one; the tests of this process
        // take turns through `NEXT`. A server is ours when its lock file names its pid.
        static NEXT: AtomicU32 = AtomicU32::new(0);
        let first = 100 + (std::process::id() % 400);
        for _ in 0..100 {
            let n = first + NEXT.fetch_add(1, Ordering::SeqCst) % 400;
            let (socket, lock) = (format!("/tmp/.X11-unix/X{n}"), format!("/tmp/.X{n}-lock"));
            if Path::new(&socket).exists() || Path::new(&lock).exists() {
                continue;
            }
            let child = Command::new("Xvfb")
                .args([
                    &format!(":{n}"),
                    "-screen",
                    "0",
                    "1280x1024x24",
                    "-nolisten",
                    "tcp",
                ])
                .stdout(Stdio::null())
                .stderr(Stdio::null())
                .spawn()
                .expect("start Xvfb");
            let mut server = Xvfb {
                child,
                display: format!(":{n}"),
            };
            let started = Instant::now();
            while started.elapsed() < Duration::from_secs(20) {
                let owner = std::fs::read_to_string(&lock).ok();
                let ours = owner.is_some_and(|pid| pid.trim() == server.child.id().to_string());
                if ours && Path::new(&socket).exists() {
                    return server;
                }
                if server.child.try_wait().ok().flatten().is_some() {
                    break;
                }
                std::thread::sleep(Duration::from_millis(50));
            }
            drop(server);
        }
        panic!("Xvfb did not start on any free display");
    }
}

impl Drop for Xvfb {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// `reshift view` on `display` with lavapipe, `extra` arguments after the common ones.
fn viewer(display: &str, extra: &[&str]) -> Child {
    reshift()
        .args(view_args())
        .args(extra)
        .env("DISPLAY", display)
        .env_remove("WAYLAND_DISPLAY")
        .env("VK_ICD_FILENAMES", lavapipe().expect("lavapipe"))
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run reshift view")
}

/// Waits for `child` up to [`PATIENCE`]; kills it and fails past that.
fn finish(mut child: Child) -> Output {
    let started = Instant::now();
    while child.try_wait().expect("wait").is_none() {
        if started.elapsed() > PATIENCE {
            let _ = child.kill();
            let o = child.wait_with_output().expect("output");
            panic!(
                "reshift view still running after {PATIENCE:?}\n{}",
                stderr(&o)
            );
        }
        std::thread::sleep(Duration::from_millis(100));
    }
    child.wait_with_output().expect("output")
}

/// `reshift view` on a fresh Xvfb display running `script` and recording into `record`; it
/// must exit 0.
fn record_script(script: &Path, record: &Path) {
    let xvfb = Xvfb::start();
    let o = finish(viewer(
        &xvfb.display,
        &[
            "--script",
            script.to_str().unwrap(),
            "--record",
            record.to_str().unwrap(),
        ],
    ));
    assert!(o.status.success(), "exit {:?}\n{}", o.status, stderr(&o));
}

/// The rendered part of a screenshot (the image at the top-left corner, `SCALE` times), as RGB.
fn rendered_part(path: &Path) -> Vec<[u8; 3]> {
    let shot = image::open(path).expect("a PNG screenshot").to_rgb8();
    assert_eq!(shot.width(), WIDTH * SCALE + 300, "{}", path.display());
    let mut out = Vec::new();
    for y in 0..HEIGHT * SCALE {
        for x in 0..WIDTH * SCALE {
            out.push(shot.get_pixel(x, y).0);
        }
    }
    out
}

/// The fraction of pixels that differ between two rendered parts.
fn changed(a: &[[u8; 3]], b: &[[u8; 3]]) -> f64 {
    a.iter().zip(b).filter(|(p, q)| p != q).count() as f64 / a.len() as f64
}

/// Not blank: many distinct colours, and not all dark.
fn assert_not_blank(part: &[[u8; 3]], what: &str) {
    let mut colours: Vec<[u8; 3]> = part.to_vec();
    colours.sort_unstable();
    colours.dedup();
    assert!(colours.len() > 50, "{what}: {} colours", colours.len());
    let mean: f64 = part
        .iter()
        .flat_map(|p| p.iter())
        .map(|&c| c as f64)
        .sum::<f64>()
        / (3 * part.len()) as f64;
    assert!(mean > 10.0, "{what}: mean {mean}");
}

#[test]
fn a_scripted_session_switches_the_preset_moves_the_camera_and_records() {
    if unavailable("a_scripted_session_switches_the_preset_moves_the_camera_and_records").is_some()
    {
        return;
    }
    let dir = scratch("scripted");
    let shot = |name: &str| dir.join(format!("{name}.png"));
    let script = dir.join("script.txt");
    std::fs::write(
        &script,
        format!(
            "wait 1\nscreenshot {}\nwait 2\nscreenshot {}\nkey p\nscreenshot {}\norbit 60 0\nscreenshot {}\nclose\n",
            shot("start").display(),
            shot("rest").display(),
            shot("preset").display(),
            shot("moved").display(),
        ),
    )
    .unwrap();
    let record = dir.join("record");
    record_script(&script, &record);
    let [start, rest, preset, moved] =
        ["start", "rest", "preset", "moved"].map(|n| rendered_part(&shot(n)));
    for (part, what) in [(&start, "start"), (&preset, "preset"), (&moved, "moved")] {
        assert_not_blank(part, what);
    }
    assert_eq!(
        changed(&start, &rest),
        0.0,
        "an unchanged step changed the rendered part"
    );
    let by_preset = changed(&rest, &preset);
    assert!(
        by_preset > 0.05,
        "the preset switch changed {by_preset} of the pixels"
    );
    let by_move = changed(&preset, &moved);
    assert!(
        by_move > 0.2,
        "the camera move changed {by_move} of the pixels"
    );
    // One frame and one pose per rendered frame: start, preset, moved.
    let path = record.join("trajectory.toml");
    let recorded = sss::scene::Trajectory::load(&path).unwrap();
    let poses = &recorded.poses;
    assert_eq!(poses.len(), 3, "{recorded:?}");
    assert_eq!(poses[0], poses[1], "the preset switch kept the pose");
    assert_ne!(poses[1].eye, poses[2].eye, "the orbit moved the eye");
    assert_eq!(
        poses[1].target, poses[2].target,
        "the orbit kept the target"
    );
    // The first pose is where the viewer starts: the scene camera's last, bit for bit.
    let camera = sss::scene::Scene::builtin("bumpy").unwrap().camera;
    let start = camera.pose(sss::scene::FRAMES - 1);
    assert_eq!((poses[0].eye, poses[0].target), (start.eye, start.target));
    // `compare --trajectory` replays it: one frame per recorded pose.
    let compared = Command::new(env!("CARGO_BIN_EXE_reshift"))
        .args([
            "compare",
            "--scene",
            "bumpy",
            "--methods",
            "pt:2",
            "--baseline",
            "pt:2",
        ])
        .args([
            "--replicas",
            "2",
            "--resolution",
            "16x12",
            "--reference-spp",
            "16",
        ])
        .args([
            "--reference-batch-spp",
            "8",
            "--denoise",
            "none",
            "--no-video",
            "--json",
        ])
        .args(["--trajectory", path.to_str().unwrap()])
        .args(["--out", dir.join("compare").to_str().unwrap()])
        .args(["--cache", dir.join("cache").to_str().unwrap()])
        .output()
        .unwrap();
    assert!(compared.status.success(), "{}", stderr(&compared));
    let results: serde_json::Value = serde_json::from_slice(&compared.stdout).unwrap();
    assert_eq!(results["frames"], 3);
    let video = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(record.join("view.png")).unwrap(),
    ))
    .read_info()
    .unwrap();
    assert_eq!(
        video.info().animation_control().map(|a| a.num_frames),
        Some(3)
    );
    assert_eq!((video.info().width, video.info().height), (WIDTH, HEIGHT));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The `frames.tsv` of a recording: per frame, its method, live stream frame and confidence.
fn recorded_frames(record: &Path) -> Vec<(String, u32, f64)> {
    let table = std::fs::read_to_string(record.join("frames.tsv")).unwrap();
    let mut lines = table.lines();
    let header: Vec<&str> = lines.next().unwrap().split('\t').collect();
    let column = |name| header.iter().position(|h| *h == name).unwrap();
    let (method, index, confidence) = (
        column("method"),
        column("stream_frame"),
        column("confidence"),
    );
    lines
        .map(|line| {
            let cells: Vec<&str> = line.split('\t').collect();
            let number = |i: usize| {
                cells[i]
                    .parse::<f64>()
                    .unwrap_or_else(|e| panic!("{line}: {e}"))
            };
            (
                cells[method].to_string(),
                number(index) as u32,
                number(confidence),
            )
        })
        .collect()
}

/// Temporal reuse follows the flown camera: while a script orbits the camera frame after frame,
/// the displayed ReSTIR frames are one live stream's (stream frames 0, 1, 2, …) and the mean
/// confidence of their final reservoirs grows past the first frame's (by more than half: one
/// frame of temporal reuse adds the previous frame's confidence). Control in the same run: a
/// switch to another preset and back starts a new stream, whose first frame's confidence is
/// back within 20% of the flight's first (the value a viewer that reset its state at every
/// pose would show throughout).
#[test]
fn an_orbiting_camera_carries_temporal_history() {
    if unavailable("an_orbiting_camera_carries_temporal_history").is_some() {
        return;
    }
    const STEPS: usize = 6;
    let dir = scratch("orbit");
    let script = dir.join("script.txt");
    let mut text = String::from("wait 1\n");
    text += &"orbit 8 0\n".repeat(STEPS);
    text += &"preset reconnection\npreset hybrid\norbit 8 0\n".repeat(2);
    text += "close\n";
    std::fs::write(&script, text).unwrap();
    let record = dir.join("record");
    record_script(&script, &record);
    let frames = recorded_frames(&record);
    eprintln!("{frames:?}");
    let (flight, restarts) = frames.split_at(STEPS + 1);
    for (f, (method, index, _)) in flight.iter().enumerate() {
        assert_eq!((method.as_str(), *index), ("restir:hybrid", f as u32));
    }
    let first = flight[0].2;
    assert!(first > 0.0);
    assert!(
        flight[STEPS].2 > 1.5 * first,
        "the flight's confidence did not grow: {flight:?}"
    );
    // Control: each switch restarts the stream; back on the hybrid preset, its first frame
    // has a first frame's confidence and the orbit's frame is the new stream's second.
    assert_eq!(restarts.len(), 6, "{restarts:?}");
    for step in restarts.chunks(3) {
        let indices: Vec<(&str, u32)> = step.iter().map(|(m, i, _)| (m.as_str(), *i)).collect();
        let expected = [
            ("restir:reconnection", 0),
            ("restir:hybrid", 0),
            ("restir:hybrid", 1),
        ];
        assert_eq!(indices, expected, "{restarts:?}");
        assert!((step[1].2 - first).abs() < 0.2 * first, "{restarts:?}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn ctrl_c_closes_the_window_cleanly() {
    if unavailable("ctrl_c_closes_the_window_cleanly").is_some() {
        return;
    }
    let dir = scratch("sigint");
    let (script, up) = (dir.join("script.txt"), dir.join("up.png"));
    std::fs::write(&script, format!("wait 1\nscreenshot {}\n", up.display())).unwrap();
    let xvfb = Xvfb::start();
    let child = viewer(&xvfb.display, &["--script", script.to_str().unwrap()]);
    let started = Instant::now();
    while !up.exists() && started.elapsed() < PATIENCE {
        std::thread::sleep(Duration::from_millis(100));
    }
    assert!(up.exists(), "the viewer never showed a frame");
    let sent = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .expect("kill -INT");
    assert!(sent.success());
    let o = finish(child);
    assert!(o.status.success(), "exit {:?}\n{}", o.status, stderr(&o));
    std::fs::remove_dir_all(&dir).unwrap();
}
