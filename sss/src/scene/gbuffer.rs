//! The G-buffer: primary hits x1 of one frame's camera rays (DESIGN §6, first pass).

use glam::Vec3;
use rayon::prelude::*;

use super::{Camera, Scene};

/// Reprojection checks ([`GBuffer::reproject`]): the earlier pixel must show the same object at a
/// view distance within this relative tolerance, with geometric normals at least this aligned.
pub const REPROJECTION_DEPTH_TOLERANCE: f32 = 0.1;
pub const REPROJECTION_NORMAL_COSINE: f32 = 0.9;

/// The primary hit of one pixel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GPixel {
    /// x1.
    pub position: Vec3,
    /// Unit geometric normal, flipped toward the camera.
    pub geometric_normal: Vec3,
    /// Unit interpolated normal, flipped together with the geometric one.
    pub shading_normal: Vec3,
    pub object: u32,
    pub prim: u32,
    /// Distance from the eye to x1 along the camera ray.
    pub depth: f32,
    /// Unit direction x1 → camera.
    pub view: Vec3,
    /// Where x1 was one frame earlier: `position` carried back with its object
    /// ([`super::Motion::carry`]); `position` itself where the object is at rest or at frame 0.
    /// The per-pixel motion that temporal reuse reprojects through.
    pub previous: Vec3,
}

/// Primary hits of every pixel of one frame, row-major from the top row; `None` where the camera
/// ray leaves the scene.
#[derive(Clone, Debug, PartialEq)]
pub struct GBuffer {
    pub width: u32,
    pub height: u32,
    pub frame: u32,
    pub pixels: Vec<Option<GPixel>>,
}

impl GBuffer {
    /// Traces the camera rays of `frame` in the scene posed there ([`Scene::at_frame`]; rayon
    /// over rows; the result does not depend on the thread count).
    pub fn render(scene: &Scene, frame: u32) -> GBuffer {
        let scene = &*scene.at_frame(frame);
        let (width, height) = (scene.camera.width(), scene.camera.height());
        let mut pixels = vec![None; width as usize * height as usize];
        pixels
            .par_chunks_mut(width as usize)
            .enumerate()
            .for_each(|(py, row)| {
                for (px, pixel) in row.iter_mut().enumerate() {
                    *pixel = primary_hit(scene, frame, px as u32, py as u32);
                }
            });
        GBuffer {
            width,
            height,
            frame,
            pixels,
        }
    }

    /// The pixel of this (earlier) frame that shows the primary hit `x` of a later frame:
    /// `floor(camera.project(self.frame, x.previous))` (x1 where its object was one frame
    /// earlier: this G-buffer is of the frame before `x`'s, or of any earlier frame where nothing
    /// moves), accepted if it shows the same object at a similar distance and normal (the
    /// constants above); `None` otherwise (a disocclusion). The rule of temporal reuse (engine's
    /// `reuse::temporal`) and of the adaptive sampler's history.
    pub fn reproject(&self, camera: &Camera, x: &GPixel) -> Option<u32> {
        let c = camera.project(self.frame, x.previous)?;
        let (qx, qy) = (c.x as u32, c.y as u32);
        self.shows_same_surface(camera, qx, qy, x)
            .then_some(qy * self.width + qx)
    }

    /// Whether pixel `(qx, qy)` of this (earlier) frame shows the surface of the primary hit `x`
    /// of a later frame: the same object at a view distance within
    /// [`REPROJECTION_DEPTH_TOLERANCE`] of `x`'s distance from this frame's eye, with geometric
    /// normals at least [`REPROJECTION_NORMAL_COSINE`] aligned; `false` outside the image or on a
    /// miss. The checks of [`Self::reproject`].
    pub fn shows_same_surface(&self, camera: &Camera, qx: u32, qy: u32, x: &GPixel) -> bool {
        let Some(earlier) = self.get(qx, qy) else {
            return false;
        };
        let depth = (x.previous - camera.eye(self.frame)).length();
        earlier.object == x.object
            && (earlier.depth - depth).abs() <= REPROJECTION_DEPTH_TOLERANCE * depth
            && earlier.geometric_normal.dot(x.geometric_normal) >= REPROJECTION_NORMAL_COSINE
    }

    /// The pixel at column `px`, row `py` (`None` outside the image or on a miss).
    pub fn get(&self, px: u32, py: u32) -> Option<&GPixel> {
        if px >= self.width || py >= self.height {
            return None;
        }
        self.pixels[(py * self.width + px) as usize].as_ref()
    }
}

/// The G-buffer entry of one pixel.
fn primary_hit(scene: &Scene, frame: u32, px: u32, py: u32) -> Option<GPixel> {
    let ray = scene.camera.ray(frame, px, py);
    let hit = scene.geometry.closest_hit(&ray)?;
    let view = -Vec3::from(ray.dir);
    let n = scene.geometry.geometric_normal(hit.prim);
    let side = if n.dot(view) < 0.0 { -1.0 } else { 1.0 };
    let position = scene.geometry.position(hit.prim, hit.bary);
    let previous = match (&scene.motion, frame.checked_sub(1)) {
        (Some(motion), Some(before)) => motion.carry(hit.object, frame, before, position),
        _ => position,
    };
    Some(GPixel {
        position,
        previous,
        geometric_normal: side * n,
        shading_normal: side * scene.geometry.shading_normal(hit.prim, hit.bary),
        object: hit.object,
        prim: hit.prim,
        depth: hit.t,
        view,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    /// A sphere of radius 0.5 at the origin in front of a 3 × 3 quad at z = −1 whose normal
    /// points away from the camera (−z), seen from z = 3.
    const SCENE: &str = r#"
[camera]
resolution = [48, 36]
vfov = 40.0
eye = [0.0, 0.0, 3.0]
target = [0.0, 0.0, 0.0]

[[materials]]
name = "wax"
type = "translucent"
albedo = [0.8, 0.6, 0.4]
mfp = [0.1, 0.05, 0.02]

[[materials]]
name = "wall"
type = "lambert"
albedo = [0.5, 0.5, 0.5]

[[objects]]
name = "ball"
material = "wax"
shape = { type = "sphere", radius = 0.5, segments = 128, rings = 64 }

[[objects]]
name = "wall"
material = "wall"
shape = { type = "quad", size = [3.0, 3.0] }
transform = { rotate = [-90.0, 0.0, 0.0], translate = [0.0, 0.0, -1.0] }

[[lights]]
type = "point"
position = [0.0, 2.0, 2.0]
intensity = [1.0, 1.0, 1.0]
"#;

    fn scene() -> Scene {
        Scene::from_toml_str(SCENE, Path::new("gbuffer-test.toml")).unwrap()
    }

    /// What each pixel must see, from an analytic intersection of its camera ray, where the
    /// ray is not within `margin` of a silhouette or the wall's border: (object, depth, normal).
    fn expected(ray: &geometry::Ray, margin: f32) -> Option<Option<(u32, f32, Vec3)>> {
        let (o, d) = (Vec3::from(ray.origin), Vec3::from(ray.dir));
        let b = o.dot(d);
        let miss_distance = (o - b * d).length();
        if (miss_distance - 0.5).abs() < margin {
            return None;
        }
        if miss_distance < 0.5 {
            let t = -b - (0.25 - miss_distance * miss_distance).sqrt();
            return Some(Some((0, t, (o + t * d) / 0.5)));
        }
        let t = (-1.0 - o.z) / d.z;
        let p = o + t * d;
        let inside = p.x.abs().max(p.y.abs());
        if (inside - 1.5).abs() < margin {
            return None;
        }
        Some((inside < 1.5).then_some((1, t, Vec3::Z)))
    }

    /// Every pixel away from silhouettes sees the analytically expected object, depth and
    /// normal; the wall is hit from its back and its normal is flipped toward the camera.
    #[test]
    fn gbuffer_matches_analytic_scene() {
        let scene = scene();
        let frame = 3;
        let g = GBuffer::render(&scene, frame);
        assert_eq!(
            (g.width, g.height, g.frame, g.pixels.len()),
            (48, 36, 3, 48 * 36)
        );
        let mut counts = [0usize; 3];
        for py in 0..g.height {
            for px in 0..g.width {
                let ray = scene.camera.ray(frame, px, py);
                let Some(want) = expected(&ray, 0.01) else {
                    continue;
                };
                let got = g.get(px, py);
                match (want, got) {
                    (None, None) => counts[2] += 1,
                    (Some((object, depth, normal)), Some(gp)) => {
                        counts[object as usize] += 1;
                        assert_eq!(gp.object, object, "pixel ({px}, {py})");
                        assert!(
                            (gp.depth - depth).abs() < 2e-3,
                            "({px}, {py}): depth {} vs {depth}",
                            gp.depth
                        );
                        assert!(
                            gp.geometric_normal.angle_between(normal) < 0.05,
                            "({px}, {py})"
                        );
                        assert!(
                            gp.geometric_normal.dot(gp.view) > 0.0
                                && gp.shading_normal.dot(gp.view) > 0.0
                        );
                        let eye = scene.camera.eye(frame);
                        assert!((eye - gp.depth * gp.view - gp.position).length() < 1e-4);
                    }
                    (want, got) => panic!("pixel ({px}, {py}): expected {want:?}, got {got:?}"),
                }
            }
        }
        assert!(
            counts.iter().all(|&c| c > 50),
            "every case is exercised: {counts:?}"
        );
    }

    /// With the camera at rest (frames 15 and 16 of bumpy: only the jitter moves) every accepted
    /// pixel reprojects onto itself, and a rejected one fails one of the checks (the jitter moved it
    /// across a silhouette or onto a facet of another normal: 5% of the pixels here). Along the
    /// moving trajectory (frame 5 → 4) an accepted pixel shows the same object, on the bumpy
    /// object within 1.5 pixel footprints of x1 for 97% of the pixels where it is not seen at a
    /// grazing angle (the rest: a bump that hides x1 in frame 4 passes the 10% depth check), and
    /// the moved camera disoccludes some pixels.
    #[test]
    fn reprojection_finds_the_same_surface() {
        let mut scene = Scene::builtin("bumpy").expect("built-in scene");
        scene.camera = scene.camera.with_resolution(64, 48);
        let (g15, g16) = (GBuffer::render(&scene, 15), GBuffer::render(&scene, 16));
        let (mut same, mut total) = (0, 0);
        for (p, x) in g16.pixels.iter().enumerate() {
            let Some(x) = x else { continue };
            total += 1;
            match g15.reproject(&scene.camera, x) {
                Some(q) => {
                    assert_eq!(q as usize, p, "a resting camera moves pixel {p}");
                    same += 1;
                }
                None => assert!(g15.pixels[p].is_none_or(|e| e.object != x.object
                    || (e.depth - x.depth).abs() > 0.1 * x.depth
                    || e.geometric_normal.dot(x.geometric_normal) < 0.9)),
            }
        }
        assert!(same as f64 > 0.9 * total as f64, "{same} of {total}");

        let (g4, g5) = (GBuffer::render(&scene, 4), GBuffer::render(&scene, 5));
        let (mut accepted, mut rejected, mut near, mut checked) = (0, 0, 0, 0);
        for x in g5.pixels.iter().flatten() {
            let Some(q) = g4.reproject(&scene.camera, x) else {
                rejected += 1;
                continue;
            };
            accepted += 1;
            let e = g4.pixels[q as usize].unwrap();
            assert_eq!(e.object, x.object);
            // The footprint on the bumpy object where it is not seen at a grazing angle (the plate
            // is a thin box: a pixel may show another of its faces).
            let cos = e.geometric_normal.dot(e.view);
            if x.object == 0 && cos > 0.5 {
                let footprint =
                    2.0 * scene.camera.tan_half_fov() * e.depth / (g4.height as f32 * cos);
                checked += 1;
                near += ((e.position - x.position).length() < 1.5 * footprint) as u32;
            }
        }
        assert!(
            accepted > 1500 && rejected > 0,
            "{accepted} accepted, {rejected} rejected"
        );
        // A bump that hides x1 in the earlier frame passes the depth check: a few far matches.
        assert!(
            near as f64 > 0.97 * checked as f64,
            "{near} of {checked} near x1"
        );
    }

    /// On `passing` (the wax sphere, object 1, moves 0.06 units a frame and turns), a sphere
    /// pixel's `previous` is x1 carried back with the sphere, and reprojecting through it finds
    /// the sphere in the previous frame within 1.5 pixel footprints of where x1 was, for 95% of
    /// the sphere's pixels; the jade object's pixels keep `previous = position`. Control:
    /// reprojecting the sphere's x1 where it is now (the camera's motion alone) finds the same
    /// point for under half of them.
    #[test]
    fn reprojection_follows_a_moving_object() {
        let mut scene = Scene::builtin("passing").expect("built-in scene");
        scene.camera = scene.camera.with_resolution(128, 96);
        let motion = scene.motion.clone().expect("the sphere moves");
        let (g6, g7) = (GBuffer::render(&scene, 6), GBuffer::render(&scene, 7));
        let footprint = |e: &GPixel| {
            2.0 * scene.camera.tan_half_fov() * e.depth
                / (g6.height as f32 * e.geometric_normal.dot(e.view).max(0.5))
        };
        let (mut sphere, mut followed, mut still) = (0, 0, 0);
        for x in g7.pixels.iter().flatten() {
            if x.object != 1 {
                assert_eq!(x.previous, x.position);
                continue;
            }
            sphere += 1;
            assert!((x.previous - motion.carry(1, 7, 6, x.position)).length() < 1e-6);
            let near = |q: Option<u32>| {
                q.and_then(|q| g6.pixels[q as usize]).is_some_and(|e| {
                    e.object == 1 && (e.position - x.previous).length() < 1.5 * footprint(&e)
                })
            };
            followed += near(g6.reproject(&scene.camera, x)) as u32;
            let at_rest = GPixel {
                previous: x.position,
                ..*x
            };
            still += near(g6.reproject(&scene.camera, &at_rest)) as u32;
        }
        assert!(sphere > 300, "{sphere} sphere pixels");
        assert!(
            followed as f64 > 0.95 * sphere as f64,
            "{followed} of {sphere}"
        );
        assert!(
            (still as f64) < 0.5 * sphere as f64,
            "control: {still} of {sphere}"
        );
    }

    #[test]
    fn gbuffer_is_independent_of_thread_count() {
        let scene = scene();
        let pool = |n| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .unwrap()
        };
        let one = pool(1).install(|| GBuffer::render(&scene, 5));
        let three = pool(3).install(|| GBuffer::render(&scene, 5));
        assert_eq!(one, three);
        assert_ne!(
            one,
            GBuffer::render(&scene, 6),
            "another frame has another jitter"
        );
    }
}
