//! Videos of a comparison's trajectory ([`write_videos`]): per method, replica 0's every frame
//! side by side with that frame's reference and the luminance of its absolute error (the error
//! maps' colour ramp and scale, [`crate::draw::false_colour`]), then the same frame through each
//! denoiser of the comparison with its error, one labelled strip per frame, at
//! [`FPS`] frames per second, looping. Each is written as an animated PNG (APNG: browsers play
//! it natively, nothing need be installed), and as H.264 MP4 through `ffmpeg` where it is on
//! the PATH (else one note says so). Tiles are at the comparison's resolution: a pixel of noise
//! stays a pixel.

use std::io::Write as _;
use std::path::Path;
use std::process::{Command, Stdio};

use plotters::prelude::*;
use rayon::prelude::*;

use crate::compare::{Video, VideoTrajectory};
use crate::draw::{FONT, draw_error, false_colour, register_font};
use crate::error::Error;
use crate::metrics::error_maps;
use crate::output::file_stem;
use engine::Image;
use engine::image::tonemap;

use super::results::VideoEntry;

/// Frames per second of every video.
pub const FPS: u16 = 8;

/// The program MP4s are encoded with, looked up on the PATH.
pub const FFMPEG: &str = "ffmpeg";

/// Height of the label strip above each frame's tiles, in pixels (even: H.264's 4:2:0 needs
/// even sizes).
const LABEL_HEIGHT: u32 = 20;

/// What [`write_videos`] wrote.
pub struct Videos {
    /// One per method, in the order of the video's trajectories.
    pub entries: Vec<VideoEntry>,
    /// What the videos leave out or could not write, one line each.
    pub notes: Vec<String>,
}

/// Writes `video/<method>.png` (and `.mp4` with `ffmpeg`) into `out` for every trajectory of
/// `video`, the error tiles scaled from 0 to `error_scale` (the absolute error maps' scale).
pub fn write_videos(out: &Path, video: &Video, error_scale: f64) -> Result<Videos, Error> {
    write_videos_with(out, video, error_scale, FFMPEG)
}

/// [`write_videos`] with MP4s encoded by `ffmpeg` (a program name or path).
fn write_videos_with(
    out: &Path,
    video: &Video,
    error_scale: f64,
    ffmpeg: &str,
) -> Result<Videos, Error> {
    let dir = out.join("video");
    std::fs::create_dir_all(&dir).map_err(|e| Error::Io(format!("{}: {e}", dir.display())))?;
    let max = if error_scale > 0.0 && error_scale.is_finite() {
        error_scale
    } else {
        1.0
    };
    let mut notes = Vec::new();
    if !video.own_references {
        notes.push(
            "frames without their own reference (no convergence record) show the last frame's"
                .to_string(),
        );
    }
    for t in &video.trajectories {
        for (d, failed) in &t.denoised {
            if let Err(e) = failed {
                notes.push(format!("{}: no {d} frames in its video: {e}", t.spec));
            }
        }
    }
    // Strips in parallel per method; each file's bytes depend on its method alone.
    let strips: Vec<(String, (u32, u32), Vec<Vec<u8>>)> = video
        .trajectories
        .par_iter()
        .map(|trajectory| {
            let spec = &trajectory.spec;
            let strips = (0..trajectory.frames.len())
                .map(|t| strip(trajectory, t, &video.references[t], max))
                .collect::<Result<Vec<_>, Error>>()?;
            let size = trajectory
                .frames
                .first()
                .map_or((0, 0), |f| strip_size(f, tile_count(trajectory)));
            let stem = file_stem(spec);
            write_apng(&dir.join(format!("{stem}.png")), &strips, size)?;
            Ok((spec.clone(), size, strips))
        })
        .collect::<Result<_, Error>>()?;
    let mut entries = Vec::new();
    let mut mp4 = true;
    for (spec, size, frames) in &strips {
        let stem = file_stem(spec);
        let file = format!("video/{stem}.mp4");
        mp4 = mp4 && write_mp4(ffmpeg, &out.join(&file), frames, *size)?;
        entries.push(VideoEntry {
            method: spec.clone(),
            apng: format!("video/{stem}.png"),
            mp4: mp4.then_some(file),
        });
    }
    if !mp4 {
        notes.push(format!(
            "no MP4 videos: {ffmpeg} is not on the PATH (the animated PNGs need nothing installed)"
        ));
    }
    Ok(Videos { entries, notes })
}

/// Tiles of a strip of `trajectory`: frame, reference and error, and a frame and its error per
/// denoiser that denoised it.
fn tile_count(trajectory: &VideoTrajectory) -> u32 {
    let denoised = trajectory
        .denoised
        .iter()
        .filter(|(_, d)| d.is_ok())
        .count();
    3 + 2 * denoised as u32
}

/// Width and height of one frame's strip of `tiles` tiles of `image`'s size under the labels.
fn strip_size(image: &Image, tiles: u32) -> (u32, u32) {
    (tiles * image.width, image.height + LABEL_HEIGHT)
}

/// Frame `t` of `trajectory` as RGB bytes, each tile under its label: `[frame | reference |
/// |I − R|]`, then `[denoised | |D − R|]` per denoiser.
fn strip(
    trajectory: &VideoTrajectory,
    t: usize,
    reference: &Image,
    max: f64,
) -> Result<Vec<u8>, Error> {
    let spec = &trajectory.spec;
    let image = &trajectory.frames[t];
    let (w, h) = (image.width as usize, image.height as usize);
    let reference_mean: Vec<glam::DVec3> = reference.pixels.iter().map(|p| p.as_dvec3()).collect();
    let error = |image: &Image| {
        error_maps(image, &reference_mean)
            .map(|(absolute, _)| false_colour(&absolute, max))
            .ok_or_else(|| {
                Error::Invalid(format!(
                    "{spec}: frame {t} differs in size from its reference"
                ))
            })
    };
    let shown = |image: &Image| image.pixels.iter().flat_map(|&p| tonemap(p)).collect();
    let mut tiles: Vec<Vec<u8>> = vec![shown(image), shown(reference), error(image)?];
    let mut labels = vec![
        format!("{spec}, frame {t}"),
        "reference".to_string(),
        format!("|I − R| (0 to {max:.2e})"),
    ];
    for (d, frames) in &trajectory.denoised {
        if let Ok(frames) = frames {
            tiles.extend([shown(&frames[t]), error(&frames[t])?]);
            labels.extend([format!("{d}"), format!("|{d} − R|")]);
        }
    }
    let (sw, sh) = strip_size(image, tiles.len() as u32);
    let mut rgb = vec![255u8; sw as usize * sh as usize * 3];
    for (i, tile) in tiles.iter().enumerate() {
        for y in 0..h {
            let row = &tile[3 * y * w..3 * (y + 1) * w];
            let at = 3 * ((y + LABEL_HEIGHT as usize) * sw as usize + i * w);
            rgb[at..at + 3 * w].copy_from_slice(row);
        }
    }
    register_font();
    let path = Path::new(spec);
    let fail = draw_error(path);
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (sw, sh)).into_drawing_area();
        for (i, label) in labels.into_iter().enumerate() {
            let x = (i * w) as i32 + 4;
            root.draw(&Text::new(label, (x, 3), (FONT, 13)))
                .map_err(|e| fail(&e))?;
        }
        root.present().map_err(|e| fail(&e))?;
    }
    Ok(rgb)
}

/// Writes `frames` (RGB bytes of `size` each) to `path` as an animated PNG at [`FPS`], looping
/// forever.
pub fn write_apng(path: &Path, frames: &[Vec<u8>], (w, h): (u32, u32)) -> Result<(), Error> {
    let fail = |e: &dyn std::fmt::Display| Error::Io(format!("{}: {e}", path.display()));
    let file = std::fs::File::create(path).map_err(|e| fail(&e))?;
    let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), w, h);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_compression(png::Compression::High);
    // 0 plays: loop forever.
    encoder
        .set_animated(frames.len() as u32, 0)
        .map_err(|e| fail(&e))?;
    encoder.set_frame_delay(1, FPS).map_err(|e| fail(&e))?;
    let mut writer = encoder.write_header().map_err(|e| fail(&e))?;
    for frame in frames {
        writer.write_image_data(frame).map_err(|e| fail(&e))?;
    }
    writer.finish().map_err(|e| fail(&e))
}

/// Encodes `frames` (RGB bytes of `size` each) as H.264 MP4 at `path` with the program
/// `ffmpeg`; `false` when it is not found (nothing written).
fn write_mp4(
    ffmpeg: &str,
    path: &Path,
    frames: &[Vec<u8>],
    (w, h): (u32, u32),
) -> Result<bool, Error> {
    let fail = |e: &dyn std::fmt::Display| Error::Io(format!("{}: {ffmpeg}: {e}", path.display()));
    let spawned = Command::new(ffmpeg)
        .args([
            "-y",
            "-loglevel",
            "error",
            "-f",
            "rawvideo",
            "-pixel_format",
            "rgb24",
        ])
        .args([
            "-video_size",
            &format!("{w}x{h}"),
            "-framerate",
            &FPS.to_string(),
        ])
        .args(["-i", "-", "-c:v", "libx264", "-pix_fmt", "yuv420p"])
        .args([
            "-vf",
            "pad=ceil(iw/2)*2:ceil(ih/2)*2",
            "-movflags",
            "+faststart",
        ])
        .arg(path)
        .stdin(Stdio::piped())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn();
    let mut child = match spawned {
        Ok(child) => child,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(false),
        Err(e) => return Err(fail(&e)),
    };
    if let Some(mut stdin) = child.stdin.take() {
        for frame in frames {
            stdin.write_all(frame).map_err(|e| fail(&e))?;
        }
    }
    let output = child.wait_with_output().map_err(|e| fail(&e))?;
    if !output.status.success() {
        let why = String::from_utf8_lossy(&output.stderr);
        let line = why.lines().next().unwrap_or("no message");
        return Err(fail(&format!("{}: {line}", output.status)));
    }
    Ok(true)
}

#[cfg(test)]
mod tests {
    use super::*;
    use engine::denoise::Denoiser;
    use glam::Vec3;

    /// A 2-frame video of a method that is the reference plus a moving bright pixel.
    fn video() -> Video {
        let reference = Image {
            width: 6,
            height: 4,
            pixels: vec![Vec3::splat(0.5); 24],
        };
        let frames = (0..2)
            .map(|t| {
                let mut image = reference.clone();
                image.pixels[5 + t].x = 4.0;
                image
            })
            .collect();
        Video {
            references: vec![reference.clone(), reference],
            own_references: true,
            trajectories: vec![VideoTrajectory {
                spec: "pt:2".into(),
                frames,
                denoised: Vec::new(),
            }],
        }
    }

    /// The APNG decodes to 2 looping frames of the strip's size that differ, and a missing
    /// `ffmpeg` leaves no MP4, with one note, and no error.
    #[test]
    fn an_animated_png_loops_over_different_frames_and_no_ffmpeg_is_a_note() {
        let dir = std::env::temp_dir().join(format!("reshift-video-{}", std::process::id()));
        let written = write_videos_with(&dir, &video(), 1.0, "reshift-no-such-ffmpeg").unwrap();
        assert_eq!(written.entries.len(), 1);
        assert_eq!(written.entries[0].apng, "video/pt-2.png");
        assert!(written.entries[0].mp4.is_none());
        assert_eq!(written.notes.len(), 1, "{:?}", written.notes);
        assert!(written.notes[0].contains("reshift-no-such-ffmpeg is not on the PATH"));
        assert!(!dir.join("video/pt-2.mp4").exists());
        let file = std::fs::File::open(dir.join(&written.entries[0].apng)).unwrap();
        let mut reader = png::Decoder::new(std::io::BufReader::new(file))
            .read_info()
            .unwrap();
        let control = reader.info().animation_control().copied().unwrap();
        assert_eq!((control.num_frames, control.num_plays), (2, 0));
        assert_eq!(
            (reader.info().width, reader.info().height),
            (18, 4 + LABEL_HEIGHT)
        );
        let mut frames = Vec::new();
        for _ in 0..2 {
            let mut buffer = vec![0; reader.output_buffer_size().unwrap()];
            reader.next_frame(&mut buffer).unwrap();
            frames.push(buffer);
        }
        assert_ne!(frames[0], frames[1]);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// A denoiser's frames add a frame and an error tile to every strip; one that failed adds
    /// none and leaves one note naming the method and the denoiser.
    #[test]
    fn denoised_frames_widen_the_strip_and_a_failure_is_a_note() {
        let dir = std::env::temp_dir().join(format!("reshift-video-d-{}", std::process::id()));
        let mut video = video();
        let frames = video.trajectories[0].frames.clone();
        video.trajectories[0].denoised = vec![
            (Denoiser::Svgf, Ok(frames)),
            (Denoiser::Oidn, Err("not installed".into())),
        ];
        let written = write_videos_with(&dir, &video, 1.0, "reshift-no-such-ffmpeg").unwrap();
        assert!(
            written
                .notes
                .iter()
                .any(|n| n == "pt:2: no oidn frames in its video: not installed"),
            "{:?}",
            written.notes
        );
        let file = std::fs::File::open(dir.join(&written.entries[0].apng)).unwrap();
        let reader = png::Decoder::new(std::io::BufReader::new(file))
            .read_info()
            .unwrap();
        assert_eq!(
            (reader.info().width, reader.info().height),
            (30, 4 + LABEL_HEIGHT)
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
