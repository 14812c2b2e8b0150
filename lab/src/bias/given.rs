//! Reference batches rendered once and handed to several bias tests of one scene
//! ([`ReferenceBatches`], [`BiasPlan::reference`]): the tests of a suite that run many methods
//! against the same reference render it once instead of once per method. A test accepts them
//! only where they are the batches it would render itself: the same scene name and camera, the
//! method's reference settings, the tested frame, the batch count and samples per batch.

use sss::InputError;
use sss::integrator::pt::PtSettings;
use sss::scene::Camera;

use super::Images;
use super::plan::BiasPlan;
use crate::error::Error;
use crate::reference_cache::REFERENCE_SEED;

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
