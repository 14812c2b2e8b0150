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
}
