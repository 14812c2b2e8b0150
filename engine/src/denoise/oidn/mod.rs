//! Intel Open Image Denoise as a denoiser of the stage: its `RT` filter (the generic ray-tracing
//! denoiser) on one HDR frame, with the guide's first-hit albedo and shading normal as auxiliary
//! images, on OIDN's CPU device whatever the run's backend. The library is found and loaded at
//! run time ([`library`]).

pub mod library;

use std::ffi::CStr;

use glam::Vec3;

use super::{DenoiseError, Denoiser, Guide};
use crate::image::Image;
use library::Oidn;

/// The filter's boolean options: `hdr`, the colour is linear radiance, not a [0, 1] image;
/// `cleanAux`, the auxiliary images are noise-free — they are: [`aux_images`] reads the
/// G-buffer's one deterministic primary hit per pixel, the hit the frame's paths start from, so
/// OIDN need not prefilter them.
const OPTIONS: [(&CStr, bool); 2] = [(c"hdr", true), (c"cleanAux", true)];

/// The auxiliary images OIDN receives, by their filter names: the first-hit `albedo` and the
/// unit shading `normal` of `guide` (both 0 where the camera ray leaves the scene).
pub fn aux_images(guide: &Guide) -> [(&'static CStr, &[Vec3]); 2] {
    [(c"albedo", &guide.albedo), (c"normal", &guide.normal)]
}

/// `frame` denoised by OIDN's `RT` filter guided by `guide` (the same size, checked by the
/// caller); [`DenoiseError::Unavailable`] where OIDN cannot be loaded.
pub fn denoise(guide: &Guide, frame: &Image) -> Result<Image, DenoiseError> {
    denoise_with(library::shared()?, guide, frame)
}

fn denoise_with(oidn: &Oidn, guide: &Guide, frame: &Image) -> Result<Image, DenoiseError> {
    let mut inputs = vec![(c"color", &frame.pixels[..])];
    inputs.extend(aux_images(guide));
    let mut image = Image::black(frame.width, frame.height);
    let size = (frame.width, frame.height);
    oidn.run(c"RT", size, &inputs, &OPTIONS, &mut image.pixels)?;
    match image.non_finite_count() {
        0 => Ok(image),
        count => Err(DenoiseError::Failed {
            denoiser: Denoiser::Oidn,
            reason: format!("{count} NaN or infinite values in OIDN's output"),
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::RunConfig;
    use sss::material::Material;
    use sss::scene::{GBuffer, Scene};

    /// `bumpy` at `width × height`.
    fn bumpy(width: u32, height: u32) -> Scene {
        let scene = Scene::builtin("bumpy").unwrap();
        Scene {
            camera: scene.camera.with_resolution(width, height),
            ..scene
        }
    }

    /// What OIDN receives is the G-buffer's: each hit pixel's material albedo and shading
    /// normal, 0 on a miss.
    #[test]
    fn the_aux_images_are_the_gbuffers() {
        let scene = bumpy(24, 18);
        let guide = &Guide::trajectory(&scene, 1)[0];
        let gbuffer = GBuffer::render(&scene, 0);
        let [(albedo_name, albedo), (normal_name, normal)] = aux_images(guide);
        assert_eq!((albedo_name, normal_name), (c"albedo", c"normal"));
        assert_eq!(
            (albedo.len(), normal.len()),
            (gbuffer.pixels.len(), gbuffer.pixels.len())
        );
        let mut hits = 0;
        for (p, hit) in gbuffer.pixels.iter().enumerate() {
            let Some(hit) = hit else {
                assert_eq!(
                    (albedo[p], normal[p]),
                    (Vec3::ZERO, Vec3::ZERO),
                    "pixel {p}"
                );
                continue;
            };
            let material = scene.objects[hit.object as usize].material as usize;
            let expected = match &scene.materials[material] {
                Material::Translucent(t) => t.albedo,
                Material::Lambert(l) => l.albedo,
            };
            assert_eq!(albedo[p], expected, "pixel {p}");
            assert_eq!(normal[p], hit.shading_normal, "pixel {p}");
            hits += 1;
        }
        assert!(hits > 100, "{hits} hit pixels");
    }
}
