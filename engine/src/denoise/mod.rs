//! The denoiser stage: what any method's frames pass through before they are judged the way the
//! field judges real-time renderers — paper 001 compares every method with and without a
//! denoiser at equal time [001 §6, Fig. 6–7].
//!
//! A denoiser takes the frames `0..n` of one replica's trajectory with their [`Guide`]s and
//! returns the denoised last frame:
//!
//! * [`Denoiser::Oidn`]: Intel Open Image Denoise's `RT` filter (HDR colour, first-hit albedo and
//!   shading normal as auxiliary images) on the last frame, through the library loaded at run
//!   time ([`oidn`]); it runs on the CPU whatever the backend;
//! * [`Denoiser::Svgf`]: the built-in spatiotemporal variance-guided filter ([`svgf`]) over the
//!   whole trajectory, on the run's backend (its GLSL twin on Vulkan).
//!
//! The reference is never denoised; a frame with a non-finite value is refused
//! ([`DenoiseError::NonFinite`]) rather than smeared over its neighbours.

pub mod guide;
pub mod oidn;
pub mod svgf;

use std::fmt;

pub use guide::Guide;

use crate::backend::Backend;
use crate::clock::{Stopwatch, Timing};
use crate::image::Image;

/// A denoiser of the stage.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Denoiser {
    Oidn,
    Svgf,
}

impl Denoiser {
    /// Every denoiser, in table order.
    pub const ALL: [Denoiser; 2] = [Denoiser::Oidn, Denoiser::Svgf];

    /// `oidn` or `svgf`: the name in flags, tables and file names.
    pub fn name(self) -> &'static str {
        match self {
            Denoiser::Oidn => "oidn",
            Denoiser::Svgf => "svgf",
        }
    }

    /// The denoiser called `name`.
    pub fn parse(name: &str) -> Option<Denoiser> {
        Denoiser::ALL.into_iter().find(|d| d.name() == name)
    }

    /// `Ok` when the denoiser can run here: the built-in filter always; OIDN when its library
    /// loads (else the one line of [`DenoiseError::Unavailable`]).
    pub fn available(self) -> Result<(), DenoiseError> {
        match self {
            Denoiser::Oidn => oidn::available(),
            Denoiser::Svgf => Ok(()),
        }
    }

    /// Whether the denoiser reads the whole trajectory (a temporal filter) or its last frame.
    pub fn temporal(self) -> bool {
        matches!(self, Denoiser::Svgf)
    }
}

impl fmt::Display for Denoiser {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A denoised frame and what it cost.
#[derive(Clone, Debug)]
pub struct Denoised {
    pub image: Image,
    /// The denoiser's time on its backend's clock ([`crate::clock`]; the guides' G-buffers
    /// excluded: a renderer has them).
    pub timing: Timing,
}

/// Why a frame could not be denoised; one line each.
#[derive(Clone, Debug, PartialEq)]
pub enum DenoiseError {
    /// The denoiser's library is not installed: where it was looked for and how to install it.
    Unavailable(String),
    /// The library or the device reported an error.
    Failed { denoiser: Denoiser, reason: String },
    /// Frame `frame` has `count` non-finite values.
    NonFinite { frame: u32, count: u64 },
    /// The frames and guides disagree (counts or sizes).
    Mismatch(String),
}

impl fmt::Display for DenoiseError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Unavailable(why) => f.write_str(why),
            Self::Failed { denoiser, reason } => write!(f, "denoiser {denoiser}: {reason}"),
            Self::NonFinite { frame, count } => write!(
                f,
                "frame {frame}: {count} pixel(s) with a NaN or infinite value, not denoised"
            ),
            Self::Mismatch(why) => write!(f, "denoiser input: {why}"),
        }
    }
}

impl std::error::Error for DenoiseError {}

/// Denoises the last of `frames` with `denoiser`. `guides` are those of a trajectory
/// ([`Guide::trajectory`]) and `frames` its last frames as rendered (at least one, at most as
/// many as guides; frame `i` of `frames` is guided by `guides[guides.len() − frames.len() + i]`).
/// A spatial denoiser reads only the last frame; a temporal one all of `frames` (pass the whole
/// trajectory for its full history), on `backend`.
pub fn denoise(
    denoiser: Denoiser,
    backend: &Backend,
    guides: &[Guide],
    frames: &[Image],
) -> Result<Denoised, DenoiseError> {
    let (guides, last) = validate(denoiser, guides, frames)?;
    let watch = Stopwatch::start(backend);
    let image = match denoiser {
        Denoiser::Oidn => oidn::denoise(guides.last().expect("checked"), last)?,
        Denoiser::Svgf => svgf::denoise_on(backend, guides, frames, &svgf::Params::default())?,
    };
    Ok(Denoised {
        image,
        timing: watch.read(),
    })
}

/// The guides of `frames` (the last `frames.len()` of `guides`) and the last frame, if every
/// frame `denoiser` reads is finite and of its guide's size.
fn validate<'a>(
    denoiser: Denoiser,
    guides: &'a [Guide],
    frames: &'a [Image],
) -> Result<(&'a [Guide], &'a Image), DenoiseError> {
    let Some(last) = frames.last() else {
        return Err(DenoiseError::Mismatch("no frame to denoise".into()));
    };
    if guides.len() < frames.len() {
        return Err(DenoiseError::Mismatch(format!(
            "{} frames but {} guides",
            frames.len(),
            guides.len()
        )));
    }
    let guides = &guides[guides.len() - frames.len()..];
    let read = if denoiser.temporal() {
        frames
    } else {
        std::slice::from_ref(last)
    };
    let first = frames.len() - read.len();
    for (frame, guide) in read.iter().zip(&guides[first..]) {
        if (frame.width, frame.height) != (guide.width, guide.height) {
            return Err(DenoiseError::Mismatch(format!(
                "frame {} is {}×{} but its guide {}×{}",
                guide.frame, frame.width, frame.height, guide.width, guide.height
            )));
        }
        let count = frame.non_finite_count();
        if count > 0 {
            return Err(DenoiseError::NonFinite {
                frame: guide.frame,
                count,
            });
        }
    }
    Ok((guides, last))
}

/// Every frame of a trajectory as [`denoise`] gives it when that frame is the last one rendered:
/// frame `t` denoised from `frames[..=t]` guided by `guides[..=t]` (`guides` those of the
/// trajectory from frame 0, as many as frames) — what a viewer of the denoised stream sees at each frame, for the
/// trajectory videos. SVGF on the CPU filters the trajectory once ([`svgf::filter_every`]);
/// elsewhere a temporal filter runs once per prefix (`T(T + 1)/2` frame passes for `T` frames).
/// The last output is bit-identical to [`denoise`] of the whole trajectory.
pub fn denoise_every_frame(
    denoiser: Denoiser,
    backend: &Backend,
    guides: &[Guide],
    frames: &[Image],
) -> Result<Vec<Image>, DenoiseError> {
    if guides.len() != frames.len() {
        let why = format!("{} frames but {} guides", frames.len(), guides.len());
        return Err(DenoiseError::Mismatch(why));
    }
    if denoiser == Denoiser::Svgf && backend.renderer().is_none() {
        validate(denoiser, guides, frames)?;
        return Ok(svgf::filter_every(guides, frames, &svgf::Params::default()));
    }
    (1..=frames.len())
        .map(|n| Ok(denoise(denoiser, backend, &guides[..n], &frames[..n])?.image))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn names_round_trip() {
        for d in Denoiser::ALL {
            assert_eq!(Denoiser::parse(d.name()), Some(d));
        }
        assert_eq!(Denoiser::parse("optix"), None);
    }

    /// A NaN in the frame is refused with its frame and count, before any denoiser runs.
    #[test]
    fn a_non_finite_frame_is_refused() {
        let scene = sss::scene::Scene::builtin("bumpy").unwrap();
        let scene = sss::scene::Scene {
            camera: scene.camera.with_resolution(8, 6),
            ..scene
        };
        let guides = Guide::trajectory(&scene, 2);
        let mut frames = vec![Image::black(8, 6), Image::black(8, 6)];
        frames[1].pixels[3] = Vec3::new(f32::NAN, 0.0, 0.0);
        for d in Denoiser::ALL {
            let e = denoise(d, &Backend::Cpu, &guides, &frames).unwrap_err();
            assert_eq!(e, DenoiseError::NonFinite { frame: 1, count: 1 }, "{d}");
        }
        let e = denoise(Denoiser::Svgf, &Backend::Cpu, &guides[..1], &frames).unwrap_err();
        assert!(matches!(e, DenoiseError::Mismatch(_)), "{e}");
    }

    /// Every frame of a trajectory denoised: frame `t` is the denoised last frame of the first
    /// `t + 1` frames, the last one the whole trajectory's (SVGF, temporal); control: the first
    /// frame differs from the last (the filter sees the history).
    #[test]
    fn every_frame_is_the_denoised_last_frame_of_its_prefix() {
        let scene = sss::scene::Scene::builtin("bumpy").unwrap();
        let scene = sss::scene::Scene {
            camera: scene.camera.with_resolution(16, 12),
            ..scene
        };
        let frames: Vec<Image> = (0..3)
            .map(|f| {
                let pixels =
                    (0..16 * 12).map(|p| Vec3::splat(((p * 7 + f * 13) % 11) as f32 / 11.0));
                Image {
                    width: 16,
                    height: 12,
                    pixels: pixels.collect(),
                }
            })
            .collect();
        let guides = Guide::trajectory(&scene, 3);
        let every = denoise_every_frame(Denoiser::Svgf, &Backend::Cpu, &guides, &frames).unwrap();
        assert_eq!(every.len(), 3);
        for t in 0..3 {
            let alone = denoise(Denoiser::Svgf, &Backend::Cpu, &guides[..=t], &frames[..=t]);
            assert_eq!(every[t].pixels, alone.unwrap().image.pixels, "frame {t}");
        }
        let whole = denoise(Denoiser::Svgf, &Backend::Cpu, &guides, &frames)
            .unwrap()
            .image;
        assert_eq!(every[2].pixels, whole.pixels);
        assert!(every[0].pixels != every[2].pixels, "control");
    }
}
