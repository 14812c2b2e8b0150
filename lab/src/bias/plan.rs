//! What a bias test runs ([`BiasPlan`]): the scene, the method, the replicas (a fixed number or
//! a time budget, [`Replicas`]), the tolerance and level, the reference; checked in one line per
//! option at fault; reference batches rendered once and handed to several tests of one scene
//! ([`ReferenceBatches`]), accepted only where they are the batches the test would render
//! itself: the same scene name and camera, the method's reference settings, the tested frame,
//! the batch count and samples per batch.

use std::ops::Range;
use std::path::Path;
use std::sync::Arc;
use std::time::Duration;

use engine::Backend;
use methods::Method;
use sss::InputError;
use sss::integrator::pt::PtSettings;
use sss::limits::{self, MAX_SPP};
use sss::scene::{Camera, Scene};

use super::test_bytes;
use super::{Images, Protocol};
use crate::error::Error;
use crate::limits::MAX_REPLICAS;
use crate::reference_cache::REFERENCE_SEED;

/// Pixels of a bias test's image unless the user gives a size: 64 × 48, the size its recorded
/// verdicts and power plans were made at.
pub const DEFAULT_PIXELS: u32 = 64 * 48;

/// The default size of a bias test on a scene of `width × height`: the scene's aspect ratio at
/// about [`DEFAULT_PIXELS`] pixels (64 × 48 for a 4:3 scene; 45 × 68 for the portrait 720 × 1080),
/// each side at least 1.
pub fn default_resolution(width: u32, height: u32) -> (u32, u32) {
    let aspect = width as f64 / height.max(1) as f64;
    let h = (DEFAULT_PIXELS as f64 / aspect).sqrt();
    let w = (h * aspect).round().max(1.0);
    (w as u32, h.round().max(1.0) as u32)
}

#[cfg(test)]
#[test]
fn default_resolution_keeps_the_aspect_at_about_3072_pixels() {
    assert_eq!(default_resolution(256, 192), (64, 48));
    assert_eq!(default_resolution(160, 120), (64, 48));
    assert_eq!(default_resolution(720, 1080), (45, 68));
    assert_eq!(default_resolution(128, 128), (55, 55));
    let (w, h) = default_resolution(1, 16384);
    assert!(w >= 1 && h <= 16384, "{w}x{h}");
}

/// How many replicas a bias test runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Replicas {
    /// Exactly this many (seeds `S..S+n`, `S` the plan's first seed), one test at level α
    /// (`--replicas`).
    Fixed(u32),
    /// As many as the group-sequential design needs and this much time (on the backend's
    /// clock, `engine::clock`) allows (`--budget`).
    Budget(Duration),
}

/// What to test, where, and how strictly. [`BiasPlan::validate`] names the fields by the
/// `reshift bias` options that set them one to one (`--replicas`, `--delta`, …).
pub struct BiasPlan {
    /// The scene with the camera at the test's resolution.
    pub scene: Scene,
    /// The method under test as requested (the outcome's `method`), and the method.
    pub spec: String,
    pub method: Method,
    /// Independent replicas (seeds `first_seed..first_seed + n`), fixed or within a budget.
    pub replicas: Replicas,
    /// The seed of the first replica (`--first-seed`): a test whose seeds do not overlap an
    /// earlier test's shares no random number with it (a confirmatory test); 0 unless asked.
    pub first_seed: u64,
    /// Frames of the camera trajectory; the last one is tested.
    pub frames: u32,
    /// Tolerance δ and level α.
    pub protocol: Protocol,
    /// Independent path-traced reference batches, and the samples per pixel of each.
    pub reference_batches: u32,
    pub reference_batch_spp: u32,
    pub backend: Backend,
    /// The reference batches rendered beforehand and shared by several tests of one scene
    /// ([`ReferenceBatches::render`]), or `None` to render them in the test. Only the fixed
    /// design takes them (the budgeted one grows its reference as it plans).
    pub reference: Option<Arc<ReferenceBatches>>,
}

impl BiasPlan {
    /// The seeds of replicas `k` in `indices`: `first_seed + k` (`validate` keeps them in range).
    pub(super) fn seeds(&self, indices: Range<u64>) -> Range<u64> {
        self.first_seed.saturating_add(indices.start)..self.first_seed.saturating_add(indices.end)
    }

    /// The plan's values within range, as one line that names the option at fault (in `origin`):
    /// δ finite and > 0, 0 < α < 1; at least two replicas and two reference batches (for their
    /// standard errors), a budget > 0, every count within `sss::limits` and [`MAX_REPLICAS`],
    /// and the test within the memory budget ([`test_bytes`]; a budgeted test keeps region means
    /// only, so its replicas count as two).
    pub fn validate(&self, origin: &Path) -> Result<(), InputError> {
        let Protocol { delta, alpha } = self.protocol;
        if !(delta.is_finite() && delta > 0.0) {
            let reason = "the tolerance must be a finite number > 0";
            return Err(InputError::new(
                origin,
                "--delta",
                delta.to_string(),
                reason,
            ));
        }
        if !(alpha > 0.0 && alpha < 1.0) {
            let reason = "the level must be in (0, 1)";
            return Err(InputError::new(
                origin,
                "--alpha",
                alpha.to_string(),
                reason,
            ));
        }
        let count = |field: &str, n: u32, min: u32, max: u32| {
            limits::count(origin, field, n as u64, min as u64, max as u64)
        };
        let kept = match self.replicas {
            Replicas::Fixed(n) => {
                count("--replicas", n, 2, MAX_REPLICAS)?;
                n
            }
            Replicas::Budget(_) if self.reference.is_some() => {
                let reason = "a reference rendered beforehand serves the fixed design only";
                return Err(InputError::new(origin, "--budget", "given", reason));
            }
            Replicas::Budget(budget) => {
                if budget.is_zero() {
                    let reason = "the time budget must be > 0";
                    return Err(InputError::new(origin, "--budget", "0s", reason));
                }
                2
            }
        };
        let most = match self.replicas {
            Replicas::Fixed(n) => n,
            Replicas::Budget(_) => MAX_REPLICAS,
        };
        if self.first_seed.checked_add(most as u64).is_none() {
            let reason = format!(
                "with {most} replicas it passes the largest seed, {}",
                u64::MAX
            );
            return Err(InputError::new(
                origin,
                "--first-seed",
                self.first_seed.to_string(),
                reason,
            ));
        }
        count(
            "--reference-batches",
            self.reference_batches,
            2,
            MAX_REPLICAS,
        )?;
        count(
            "--reference-batch-spp",
            self.reference_batch_spp,
            1,
            MAX_SPP,
        )?;
        limits::frames(origin, "--frames", self.frames)?;
        let (width, height) = (self.scene.camera.width(), self.scene.camera.height());
        let value = format!(
            "{kept} replicas, {} reference batches, {} frames at {width}×{height}",
            self.reference_batches, self.frames
        );
        let pixels = width as u64 * height as u64;
        let needed = test_bytes(pixels, kept, self.reference_batches, self.frames);
        limits::memory(origin, "--replicas", &value, needed, "the bias test")
    }
}

/// The reference batches of a plan and what they were rendered with.
#[derive(Clone, Debug)]
pub struct ReferenceBatches {
    scene: String,
    camera: Camera,
    settings: PtSettings,
    frame: u32,
    batch_spp: u32,
    pub images: Images,
}

impl ReferenceBatches {
    /// The reference batches `plan` would render (its scene at the last frame, the method's
    /// reference settings, `plan.reference_batches` batches of `plan.reference_batch_spp`
    /// samples from the reference seed). Any `plan.reference` is ignored.
    pub fn render(plan: &BiasPlan) -> Result<ReferenceBatches, Error> {
        let (settings, frame) = (plan.method.reference(), plan.frames.saturating_sub(1));
        let images = super::reference_images_with(
            &settings,
            &plan.scene,
            frame,
            plan.reference_batches,
            plan.reference_batch_spp,
            REFERENCE_SEED,
        )?;
        Ok(ReferenceBatches {
            scene: plan.scene.name.clone(),
            camera: plan.scene.camera.clone(),
            settings,
            frame,
            batch_spp: plan.reference_batch_spp,
            images,
        })
    }

    /// Whether these are the batches `plan` would render: one line naming the first setting
    /// that differs.
    pub(super) fn check(&self, plan: &BiasPlan) -> Result<(), InputError> {
        let differs = |field: &str, value: String| {
            let reason = "differs from the plan's: the given reference is not this test's";
            Err(InputError::new("(bias reference)", field, value, reason))
        };
        if self.scene != plan.scene.name || self.camera != plan.scene.camera {
            return differs("scene", self.scene.clone());
        }
        if self.settings != plan.method.reference() {
            return differs("settings", format!("{:?}", self.settings));
        }
        if self.frame + 1 != plan.frames {
            return differs("frame", self.frame.to_string());
        }
        if self.images.rgb.len() != plan.reference_batches as usize {
            return differs("batches", self.images.rgb.len().to_string());
        }
        if self.batch_spp != plan.reference_batch_spp {
            return differs("spp per batch", self.batch_spp.to_string());
        }
        Ok(())
    }
}
