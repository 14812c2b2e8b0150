//! The denoisers' guide: per frame, what the G-buffer says of each pixel's primary hit — the
//! auxiliary images a denoiser needs (first-hit albedo, shading normal) and the edge-stopping
//! and reprojection inputs of a spatiotemporal filter (view depth, object, the previous frame's
//! pixel). A guide depends on the scene and the frame only (the camera trajectory, jitter
//! included, is a function of the frame), so one set serves every method and replica.

use glam::Vec3;
use sss::material::Material;
use sss::scene::{GBuffer, Scene};

/// Marks "no pixel" in [`Guide::object`] and [`Guide::previous`].
pub const NONE: u32 = crate::contract::NO_PIXEL;

/// One frame's guide, row-major from the top row like the frames it guides.
#[derive(Clone, Debug, PartialEq)]
pub struct Guide {
    pub width: u32,
    pub height: u32,
    pub frame: u32,
    /// The albedo of the primary hit's material (0 where the camera ray leaves the scene).
    pub albedo: Vec<Vec3>,
    /// The unit shading normal of the primary hit, facing the camera (0 on a miss).
    pub normal: Vec<Vec3>,
    /// Distance from the eye to the primary hit (0 on a miss).
    pub depth: Vec<f32>,
    /// The primary hit's object ([`NONE`] on a miss).
    pub object: Vec<u32>,
    /// The pixel of the previous frame that shows the same surface ([`GBuffer::reproject`], the
    /// rule of temporal reuse); [`NONE`] at frame 0, on a disocclusion or a miss.
    pub previous: Vec<u32>,
}

impl Guide {
    /// The guide of `gbuffer`'s frame; `earlier` is the previous frame's G-buffer (`None` at
    /// frame 0).
    pub fn new(scene: &Scene, gbuffer: &GBuffer, earlier: Option<&GBuffer>) -> Guide {
        let n = gbuffer.pixels.len();
        let mut guide = Guide {
            width: gbuffer.width,
            height: gbuffer.height,
            frame: gbuffer.frame,
            albedo: vec![Vec3::ZERO; n],
            normal: vec![Vec3::ZERO; n],
            depth: vec![0.0; n],
            object: vec![NONE; n],
            previous: vec![NONE; n],
        };
        for (p, hit) in gbuffer.pixels.iter().enumerate() {
            let Some(hit) = hit else { continue };
            let material = scene.objects[hit.object as usize].material as usize;
            guide.albedo[p] = match &scene.materials[material] {
                Material::Translucent(t) => t.albedo,
                Material::Lambert(l) => l.albedo,
            };
            guide.normal[p] = hit.shading_normal;
            guide.depth[p] = hit.depth;
            guide.object[p] = hit.object;
            guide.previous[p] = earlier
                .and_then(|e| e.reproject(&scene.camera, hit))
                .unwrap_or(NONE);
        }
        guide
    }

    /// The guides of frames `0..frames` of `scene`'s trajectory.
    pub fn trajectory(scene: &Scene, frames: u32) -> Vec<Guide> {
        let mut guides = Vec::with_capacity(frames as usize);
        let mut earlier: Option<GBuffer> = None;
        for frame in 0..frames {
            let gbuffer = GBuffer::render(scene, frame);
            guides.push(Guide::new(scene, &gbuffer, earlier.as_ref()));
            earlier = Some(gbuffer);
        }
        guides
    }

    pub fn len(&self) -> usize {
        self.albedo.len()
    }

    pub fn is_empty(&self) -> bool {
        self.albedo.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every entry is the G-buffer's (albedo through the hit object's material), and the
    /// previous pixel is the G-buffer's reprojection.
    #[test]
    fn a_guide_is_read_off_the_gbuffer() {
        let scene = Scene::builtin("bumpy").unwrap();
        let scene = Scene {
            camera: scene.camera.with_resolution(24, 18),
            ..scene
        };
        let guides = Guide::trajectory(&scene, 2);
        let (g0, g1) = (GBuffer::render(&scene, 0), GBuffer::render(&scene, 1));
        assert!(guides[0].previous.iter().all(|&p| p == NONE));
        let mut reprojected = 0;
        for (p, hit) in g1.pixels.iter().enumerate() {
            let guide = &guides[1];
            match hit {
                None => {
                    assert_eq!(guide.object[p], NONE);
                    assert_eq!(guide.albedo[p], Vec3::ZERO);
                    assert_eq!(guide.normal[p], Vec3::ZERO);
                }
                Some(hit) => {
                    let m = scene.objects[hit.object as usize].material as usize;
                    let albedo = match &scene.materials[m] {
                        Material::Translucent(t) => t.albedo,
                        Material::Lambert(l) => l.albedo,
                    };
                    assert_eq!(guide.albedo[p], albedo);
                    assert_eq!(guide.normal[p], hit.shading_normal);
                    assert_eq!(guide.depth[p], hit.depth);
                    assert_eq!(guide.object[p], hit.object);
                    let previous = g0.reproject(&scene.camera, hit).unwrap_or(NONE);
                    assert_eq!(guide.previous[p], previous);
                    reprojected += (previous != NONE) as u32;
                }
            }
        }
        assert!(reprojected > 100, "{reprojected} pixels reprojected");
    }
}
