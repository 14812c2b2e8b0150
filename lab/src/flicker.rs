//! Temporal stability: how much a method's error against the reference changes from one frame
//! of the camera's trajectory to the next (flicker), per area, over replicas.
//!
//! With `e_t(p) = Y(I_t(p)) − Y(R̂_t(p))` the signed luminance error of frame `t` at pixel `p`
//! (Y: Rec. 709 luminance of linear radiance; `R̂_t` the reference of frame `t`), replica k's
//! flicker in area A is
//!
//! `f_k = mean_{t=1..T−1} mean_{p ∈ A_t} |e_t(p) − e_{t−1}(p)|`
//!
//! over the consecutive measured frames (`A_t`: the area at frame `t`; frames where it is empty
//! are skipped). Subtracting the reference takes out the image's own change under the camera's
//! motion, so what remains is the change of the error: noise that is not carried over between
//! frames, and errors that switch on and off. The reported value is `mean_k f_k` with its 95%
//! interval over replicas ([`crate::uncertainty`]). The references' own noise enters `e_t` as
//! well (the earlier frames' references are cheap, [`crate::compare::frame_reference_spp`]), so
//! a method cannot measure below the references' frame-to-frame noise; the flicker is a
//! comparison between methods, not an absolute.
//!
//! Beside it, [`reference_change`]: the same mean over the references,
//! `mean_t mean_{p ∈ A_t} |Y(R̂_t(p)) − Y(R̂_{t−1}(p))|`, the scale of how much the image itself
//! changes per frame (the camera's motion plus the references' noise).

use engine::Image;
use sss::color::luminance;

use crate::metrics::Area;
use crate::reference_cache::FrameReference;
use crate::regions::Regions;
use crate::uncertainty::Estimate;

/// One method's flicker in one area, over replicas.
#[derive(Clone, Debug, PartialEq)]
pub struct AreaFlicker {
    pub area: Area,
    pub flicker: Estimate,
}

/// Whether `references` are at least 2 consecutive frames: what a flicker needs.
pub fn measurable(references: &[(FrameReference, Regions)]) -> bool {
    references.len() >= 2
        && references
            .windows(2)
            .all(|w| w[1].0.frame == w[0].0.frame + 1)
}

/// The flicker of `replicas` (each the frames of `references`, same order) in every area that
/// has pixels at some frame after the first; `None` unless the references are [`measurable`]
/// and every size agrees.
pub fn flicker(
    replicas: &[&[Image]],
    references: &[(FrameReference, Regions)],
) -> Option<Vec<AreaFlicker>> {
    if !measurable(references) || replicas.is_empty() {
        return None;
    }
    let per_replica = replicas
        .iter()
        .map(|frames| {
            if frames.len() != references.len() {
                return None;
            }
            let errors = frames
                .iter()
                .zip(references)
                .map(|(image, (reference, _))| {
                    let same = image.pixels.len() == reference.mean.len();
                    same.then(|| {
                        image
                            .pixels
                            .iter()
                            .zip(&reference.mean)
                            .map(|(&x, &r)| luminance(x.as_dvec3()) - luminance(r))
                            .collect()
                    })
                })
                .collect::<Option<Vec<Vec<f64>>>>()?;
            Some(mean_change(&errors, references))
        })
        .collect::<Option<Vec<_>>>()?;
    Some(
        Area::ALL
            .into_iter()
            .filter_map(|area| {
                let samples: Vec<f64> = per_replica
                    .iter()
                    .map(|areas| areas.iter().find(|(a, _)| *a == area).map(|x| x.1))
                    .collect::<Option<_>>()?;
                Some(AreaFlicker {
                    area,
                    flicker: Estimate::mean(&samples),
                })
            })
            .collect(),
    )
}

/// The references' own frame-to-frame change per area (module documentation); empty unless
/// they are [`measurable`].
pub fn reference_change(references: &[(FrameReference, Regions)]) -> Vec<(Area, f64)> {
    if !measurable(references) {
        return Vec::new();
    }
    let values: Vec<Vec<f64>> = references
        .iter()
        .map(|(r, _)| r.mean.iter().map(|&p| luminance(p)).collect())
        .collect();
    mean_change(&values, references)
}

/// `mean_t mean_{p ∈ A_t} |v_t(p) − v_{t−1}(p)|` per area that has pixels at some `t ≥ 1`
/// (`A_t` from the regions of `references[t]`), in [`Area::ALL`] order.
fn mean_change(values: &[Vec<f64>], references: &[(FrameReference, Regions)]) -> Vec<(Area, f64)> {
    Area::ALL
        .into_iter()
        .filter_map(|area| {
            let per_frame: Vec<f64> = (1..values.len())
                .filter_map(|t| {
                    let pixels = area.pixels(&references[t].1);
                    (!pixels.is_empty()).then(|| {
                        let sum: f64 = pixels
                            .iter()
                            .map(|&p| (values[t][p] - values[t - 1][p]).abs())
                            .sum();
                        sum / pixels.len() as f64
                    })
                })
                .collect();
            (!per_frame.is_empty())
                .then(|| (area, per_frame.iter().sum::<f64>() / per_frame.len() as f64))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::regions::VISIBILITY_SAMPLES;
    use glam::{DVec3, Vec3};

    /// 2 × 1: pixel 0 lit, pixel 1 shadowed.
    fn regions() -> Regions {
        Regions::from_visible_samples(2, 1, vec![Some(VISIBILITY_SAMPLES), Some(0)]).unwrap()
    }

    fn reference(frame: u32, values: [f64; 2]) -> (FrameReference, Regions) {
        let reference = FrameReference {
            frame,
            mean: values.iter().map(|&v| DVec3::splat(v)).collect(),
            std_err: vec![DVec3::ZERO; 2],
            batches: 2,
            spp: 2,
        };
        (reference, regions())
    }

    fn image(values: [f32; 2]) -> Image {
        Image {
            width: 2,
            height: 1,
            pixels: values.iter().map(|&v| Vec3::splat(v)).collect(),
        }
    }

    /// A grey value's luminance is the value: the error's change is read off by hand.
    #[test]
    fn flicker_is_the_mean_change_of_the_error() {
        let references = [reference(0, [1.0, 2.0]), reference(1, [3.0, 2.0])];
        // Replica 0: errors (0, 0) then (0, 1): changes 0 and 1. Replica 1: (1, 0) then
        // (−1, 0): changes 2 and 0.
        let a = [image([1.0, 2.0]), image([3.0, 3.0])];
        let b = [image([2.0, 2.0]), image([2.0, 2.0])];
        let f = flicker(&[&a, &b], &references).unwrap();
        let of = |area| f.iter().find(|x| x.area == area).unwrap().flicker.value;
        assert!((of(Area::Image) - 0.75).abs() < 1e-12, "{f:?}");
        let lit = Area::Region(crate::regions::Region::Lit);
        let shadowed = Area::Region(crate::regions::Region::Shadowed);
        assert!((of(lit) - 1.0).abs() < 1e-12);
        assert!((of(shadowed) - 0.5).abs() < 1e-12);
        assert!(
            f.iter()
                .all(|x| x.area != Area::Region(crate::regions::Region::Penumbra))
        );
        let change = reference_change(&references);
        assert_eq!(change[0], (Area::Image, 1.0));
    }

    /// A method that follows the reference exactly does not flicker, however much the image
    /// changes; without consecutive frames there is nothing to measure.
    #[test]
    fn an_exact_method_does_not_flicker_and_gaps_are_refused() {
        let references = [reference(0, [1.0, 5.0]), reference(1, [4.0, 0.5])];
        let exact = [image([1.0, 5.0]), image([4.0, 0.5])];
        let f = flicker(&[&exact], &references).unwrap();
        assert!(f.iter().all(|x| x.flicker.value == 0.0), "{f:?}");
        let gap = [reference(0, [1.0, 5.0]), reference(2, [4.0, 0.5])];
        assert!(flicker(&[&exact], &gap).is_none());
        assert!(reference_change(&gap).is_empty());
        assert!(
            flicker(&[&exact[..1]], &references).is_none(),
            "a frame short"
        );
    }
}
