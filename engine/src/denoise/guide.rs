//! The denoisers' guide: per frame, what the G-buffer says of each pixel's primary hit — the
//! auxiliary images a denoiser needs (first-hit albedo, shading normal) and the edge-stopping
//! and reprojection inputs of a spatiotemporal filter (view depth, object, where the surface lay
//! in the previous frame). A guide depends on the scene and the frame only (the camera
//! trajectory, jitter included, is a function of the frame), so one set serves every method and
//! replica.

use glam::{Vec2, Vec3};
use sss::material::Material;
use sss::scene::{Camera, GBuffer, GPixel, Scene};

/// Marks "no pixel" in [`Guide::object`].
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
    /// Where the primary hit lay in the previous frame ([`Reprojection::NONE`] at frame 0 and on
    /// a miss).
    pub previous: Vec<Reprojection>,
}

/// Where a pixel's surface lay in the previous frame: the 2×2 bilinear footprint through which
/// SVGF's temporal accumulation reads its history (Schied et al. 2017, `[SVGF]` §4.1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reprojection {
    /// Continuous coordinates in the previous frame's grid of pixel samples, pixel `(x, y)`'s
    /// sample at `(x, y)`: the camera's projection into that frame ([`Camera::project`]) less
    /// the half pixel of the pixel centre and less that frame's jitter.
    pub position: Vec2,
    /// Bit `t` (0–3) set where tap `t` of the footprint, pixel
    /// `floor(position) + (t & 1, t >> 1)`, shows the same surface
    /// ([`GBuffer::shows_same_surface`], the checks of temporal reuse); 0 where none does, at
    /// frame 0 and on a miss.
    pub taps: u32,
}

impl Reprojection {
    /// No history.
    pub const NONE: Reprojection = Reprojection {
        position: Vec2::ZERO,
        taps: 0,
    };

    /// The reprojection of the primary hit `hit` into `earlier`'s frame ([`Self::NONE`] where
    /// it projects behind the eye or outside the image).
    pub fn of(camera: &Camera, earlier: &GBuffer, hit: &GPixel) -> Reprojection {
        let Some(c) = camera.project(earlier.frame, hit.position) else {
            return Reprojection::NONE;
        };
        // The pixel centre's half and the earlier frame's jitter: pixel `(x, y)` sampled
        // `(x + ½, y + ½) + jitter` ([`Camera::ray`]).
        let position = c - 0.5 - camera.jitter(earlier.frame);
        Reprojection::at(camera, earlier, hit, position)
    }

    /// The footprint at `position` in `earlier`'s grid of samples: its taps that show `hit`'s
    /// surface.
    pub fn at(camera: &Camera, earlier: &GBuffer, hit: &GPixel, position: Vec2) -> Reprojection {
        let corner = position.floor();
        let mut taps = 0;
        for t in 0..4 {
            let x = corner.x as i64 + i64::from(t & 1);
            let y = corner.y as i64 + i64::from(t >> 1);
            let (Ok(x), Ok(y)) = (u32::try_from(x), u32::try_from(y)) else {
                continue;
            };
            if earlier.shows_same_surface(camera, x, y, hit) {
                taps |= 1 << t;
            }
        }
        Reprojection { position, taps }
    }
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
            previous: vec![Reprojection::NONE; n],
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
            if let Some(earlier) = earlier {
                guide.previous[p] = Reprojection::of(&scene.camera, earlier, hit);
            }
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
    /// reprojection is [`Reprojection::of`] the earlier G-buffer.
    #[test]
    fn a_guide_is_read_off_the_gbuffer() {
        let scene = Scene::builtin("bumpy").unwrap();
        let scene = Scene {
            camera: scene.camera.with_resolution(24, 18),
            ..scene
        };
        let guides = Guide::trajectory(&scene, 2);
        let (g0, g1) = (GBuffer::render(&scene, 0), GBuffer::render(&scene, 1));
        assert!(guides[0].previous.iter().all(|&p| p == Reprojection::NONE));
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
                    let previous = Reprojection::of(&scene.camera, &g0, hit);
                    assert_eq!(guide.previous[p], previous);
                    reprojected += (previous.taps != 0) as u32;
                }
            }
        }
        assert!(reprojected > 100, "{reprojected} pixels reprojected");
    }

    /// With the camera at rest (frames 15 → 16 of `bumpy`: only the jitter moves) every
    /// footprint lies at its own pixel moved by `jitter(16) − jitter(15)`, within 2e-3 px (the
    /// projection's error); control: without the earlier frame's jitter the positions miss by
    /// more than 0.1 px. Along the moving trajectory (frame 4 → 5) a footprint's taps are those
    /// that pass the reprojection checks, and the nearest pixel of temporal reuse
    /// ([`GBuffer::reproject`]), where it keeps one, is a kept tap.
    #[test]
    fn a_footprint_lies_where_the_earlier_samples_were() {
        let mut scene = Scene::builtin("bumpy").unwrap();
        scene.camera = scene.camera.with_resolution(24, 18);
        let camera = &scene.camera;
        let (g15, g16) = (GBuffer::render(&scene, 15), GBuffer::render(&scene, 16));
        let shift = camera.jitter(16) - camera.jitter(15);
        let (mut worst, mut unjittered) = (0.0f32, f32::INFINITY);
        for (p, hit) in g16.pixels.iter().enumerate() {
            let Some(hit) = hit else { continue };
            let r = Reprojection::of(camera, &g15, hit);
            let pixel = Vec2::new((p % 24) as f32, (p / 24) as f32);
            worst = worst.max((r.position - (pixel + shift)).abs().max_element());
            let without = r.position + camera.jitter(15);
            unjittered = unjittered.min((without - (pixel + shift)).abs().max_element());
        }
        assert!(worst < 2e-3, "worst position error {worst} px");
        assert!(
            unjittered > 0.1,
            "control: without the jitter {unjittered} px"
        );

        let (g4, g5) = (GBuffer::render(&scene, 4), GBuffer::render(&scene, 5));
        let mut nearest = 0;
        for hit in g5.pixels.iter().flatten() {
            let r = Reprojection::of(camera, &g4, hit);
            let corner = r.position.floor();
            for t in 0..4u32 {
                let x = corner.x as i64 + i64::from(t & 1);
                let y = corner.y as i64 + i64::from(t >> 1);
                let passes = u32::try_from(x)
                    .ok()
                    .zip(u32::try_from(y).ok())
                    .is_some_and(|(x, y)| g4.shows_same_surface(camera, x, y, hit));
                assert_eq!((r.taps >> t) & 1 == 1, passes, "tap {t} of {r:?}");
            }
            if let Some(q) = g4.reproject(camera, hit) {
                let (qx, qy) = ((q % 24) as f32, (q / 24) as f32);
                let t = (qx - corner.x) as u32 + 2 * (qy - corner.y) as u32;
                assert!(
                    (0.0..2.0).contains(&(qx - corner.x))
                        && (0.0..2.0).contains(&(qy - corner.y))
                        && (r.taps >> t) & 1 == 1,
                    "nearest pixel {q} outside {r:?}"
                );
                nearest += 1;
            }
        }
        assert!(nearest > 100, "{nearest} pixels kept by the nearest pixel");
    }
}
