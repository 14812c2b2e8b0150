//! `image-space[:spp]`: image-space subsurface scattering of paper 002 (Mertens et al. 2003) with
//! the Jensen dipole ([`cpu`]): per pass, the irradiance of every
//! translucent pixel from the eye [002 Eq. 5], then a gather of `R_d · E` over the image on each
//! pixel's tangent plane [002 Eq. 4, 8–9]; `spp` passes are averaged. Lambert pixels take the
//! path tracer's samples. Memoryless: only the final frame is rendered. On Vulkan its twin
//! `method_image_space.glsl` ([`vulkan`]).
//!
//! The folder is the whole method: this file (its registry entry and [`Estimator`]), the CPU
//! estimator [`cpu`] and its GLSL twin `image_space.glsl`, the kernel `method_image_space.glsl`
//! with its host code [`vulkan`], what the two languages share ([`contract`]) and the parity
//! tests of the kernel against the CPU (`parity.rs`).
//!
//! Its reference is the path tracer with the dipole profile of the same materials
//! (`ProfileKind::Dipole`, [`Estimator::reference`]): `reshift bias` measures it against that, so
//! its bias is the screen-space approximation alone (entry points the image does not show, pixel
//! discretisation, the tangent-plane disk). `compare` measures every method against the default
//! (Burley) reference, so there it also carries the dipole–Burley profile difference.

pub mod contract;
pub mod cpu;
#[cfg(test)]
mod parity;
pub mod vulkan;

use engine::{Backend, PipelineError};
use sss::integrator::pt::PtSettings;
use sss::profile::ProfileKind;
use sss::scene::{GBuffer, Scene};

use self::cpu::ImageSpaceSettings;
use crate::estimator::{Entry, LastFrame};
use crate::per_sample::{self, PerSample};
use crate::pt::to_image;

pub const ENTRY: Entry = Entry {
    family: ImageSpace::FAMILY,
    usage: "image-space[:spp]",
    about: "image-space dipole integration over the G-buffer [002], spp passes; \
            `bias` measures it against pt with the dipole profile",
    build: per_sample::build::<ImageSpace>,
};

/// `spp` passes of the image-space method with the default sample counts per pass
/// ([`ImageSpaceSettings::default`]: 1 light sample for `E`, 8 dipole and 2 uniform gather
/// samples).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ImageSpace {
    pub spp: u32,
}

impl PerSample for ImageSpace {
    const FAMILY: &'static str = "image-space";

    fn at(spp: u32) -> ImageSpace {
        ImageSpace { spp }
    }

    fn samples(&self) -> u32 {
        self.spp
    }

    fn render_frame(
        &self,
        backend: &Backend,
        scene: &Scene,
        frame: u32,
        seed: u64,
    ) -> Result<LastFrame, PipelineError> {
        let (image, nonfinite) = match backend.renderer() {
            Some(mut renderer) => vulkan::render(&mut renderer, scene, frame, seed, self.spp)?,
            None => {
                let gbuffer = GBuffer::render(scene, frame);
                let settings = ImageSpaceSettings::default();
                let frame = cpu::render(scene, &gbuffer, &settings, seed, self.spp);
                (to_image(&frame.image), frame.image.nonfinite)
            }
        };
        Ok(LastFrame {
            image,
            frames_rendered: 1,
            nonfinite,
            passes: Vec::new(),
        })
    }

    /// The path tracer with the dipole profile of the same materials.
    fn reference_settings(&self) -> PtSettings {
        PtSettings {
            profile: ProfileKind::Dipole,
            ..PtSettings::default()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Method;
    use engine::vulkan::testing::backend_or_skip;

    fn scene(name: &str) -> Scene {
        let mut scene = Scene::builtin(name).expect("built-in scene");
        scene.camera = scene.camera.with_resolution(16, 12);
        scene
    }

    #[test]
    fn parses_to_its_canonical_name_and_scales_its_passes() {
        let method = Method::parse("image-space").unwrap();
        assert_eq!((method.name(), method.spp()), ("image-space:1".into(), 1));
        assert_eq!(Method::parse(&method.name()).unwrap(), method);
        assert_eq!(method.with_spp(3), Method::parse("image-space:3").unwrap());
        for bad in ["image-space:0", "image-space:x", "image-space:-2"] {
            assert!(Method::parse(bad).is_err(), "{bad}");
        }
        assert_eq!(method.reference().profile, ProfileKind::Dipole);
        assert_eq!(
            Method::parse("pt").unwrap().reference().profile,
            ProfileKind::Burley,
            "negative control: the path tracer's reference is Burley's"
        );
    }

    /// Through the registry the method is [`cpu::render`] on the last
    /// frame, bit for bit and deterministic; negative control: another seed gives other bits.
    #[test]
    fn renders_the_integrator_on_the_last_frame() {
        let scene = scene("bumpy");
        let method = Method::parse("image-space:2").unwrap();
        let a = method.render(&scene, 3, 5).unwrap();
        let again = method.render(&scene, 3, 5).unwrap();
        let other = method.render(&scene, 3, 6).unwrap();
        let direct = cpu::render(
            &scene,
            &GBuffer::render(&scene, 2),
            &ImageSpaceSettings::default(),
            5,
            2,
        );
        let direct: Vec<_> = direct.image.pixels.iter().map(|p| p.as_vec3()).collect();
        assert_eq!(a.image.pixels, direct);
        assert_eq!(a.image.pixels, again.image.pixels);
        assert_ne!(a.image.pixels, other.image.pixels);
        assert_eq!((a.frames_rendered, a.nonfinite, a.spp), (1, 0, 2.0));
        assert!(a.counts.is_none());
        assert!(a.image.pixels.iter().any(|p| p.max_element() > 0.0));
    }

    /// On Vulkan the method renders `bumpy` through its kernel: no non-finite pixel, lit
    /// translucent pixels, and not the CPU's image of another seed (per-pixel parity with the
    /// CPU is `parity.rs`).
    #[test]
    fn renders_on_vulkan() {
        let Some(backend) = backend_or_skip("image_space::renders_on_vulkan") else {
            return;
        };
        let method = Method::parse("image-space").unwrap();
        let gpu = method.render_on(&backend, &scene("bumpy"), 2, 5).unwrap();
        assert_eq!((gpu.nonfinite, gpu.frames_rendered), (0, 1));
        assert!(gpu.image.pixels.iter().all(|p| p.is_finite()));
        assert!(gpu.image.pixels.iter().any(|p| p.max_element() > 0.0));
    }
}
