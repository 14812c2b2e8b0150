//! Pixel regions of a frame for per-region error and bias tables (DESIGN §7).
//!
//! Rule, per pixel of one frame's G-buffer:
//! * **translucent**: the primary hit x1 lies on an object with a translucent material. Only these
//!   pixels are resampled by ReSTIR SSS, so every region is a subset of them; pixels on Lambert
//!   surfaces or with no hit belong to no region.
//! * **lit / penumbra / shadowed** split the translucent pixels by the light visibility at x1:
//!   [`VISIBILITY_SAMPLES`] light samples are drawn from x1 (light picked by power, point on it
//!   stratified on an 8 × 8 jittered grid), each shadow-tested from x1 to x3. All visible → lit,
//!   none → shadowed, otherwise penumbra. A sample that cannot emit toward x1 counts as not
//!   visible.
//!
//! * **disoccluded**: the translucent pixels whose primary hit does not reproject into the
//!   previous frame ([`GBuffer::reproject`], the rule of temporal reuse: off-screen there, or
//!   another object, depth or normal), so temporal reuse has no history for them this frame;
//!   at frame 0 every translucent pixel is disoccluded. It overlaps lit, penumbra and shadowed,
//!   and is reported beside them ([`Region::ALL`]) but is not one of the bias protocol's
//!   regions ([`Region::VISIBILITY`]): a border strip of a few pixels has per-replica CVs that
//!   no ±2% power plan affords, and its bias is part of the translucent row's.
//!
//! The classification looks at x1, not at the entry points x2 that carry the light, so a
//! "shadowed" pixel near the shadow edge still receives light through the medium; the regions are
//! chosen to separate failure modes of the shifts (visibility, Jacobians near edges), not to be
//! exact light-transport categories. The light samples come from keyed streams
//! ([`REGIONS_PASS`]), so the classification is deterministic and independent of any estimator's
//! random numbers.

use std::fmt;

use geometry::Ray;
use glam::{Vec3, Vec3A};
use rayon::prelude::*;
use restir::rng::StreamKey;
use sss::integrator::pt::SHADOW_EPSILON;
use sss::material::Material;
use sss::scene::{GBuffer, GPixel, Scene};

/// Strata per axis of the light-sample grid.
const STRATA: u32 = 8;

/// Light samples per pixel for the visibility fraction.
pub const VISIBILITY_SAMPLES: u32 = STRATA * STRATA;

/// The `pass` of the classification's stream keys (ASCII "REGN"): apart from every pipeline pass.
pub const REGIONS_PASS: u32 = 0x5245_474E;

/// A region of the image.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Region {
    /// Every pixel whose primary hit is on a translucent object.
    Translucent,
    /// Translucent, every light sample from x1 visible.
    Lit,
    /// Translucent, some but not all light samples from x1 visible.
    Penumbra,
    /// Translucent, no light sample from x1 visible.
    Shadowed,
    /// Translucent, its primary hit not reprojected into the previous frame.
    Disoccluded,
}

impl Region {
    /// All regions, in table order.
    pub const ALL: [Region; 5] = [
        Region::Translucent,
        Region::Lit,
        Region::Penumbra,
        Region::Shadowed,
        Region::Disoccluded,
    ];

    /// The translucent pixels and their split by light visibility: the regions of the bias
    /// protocol (`lab::bias`), which partition into lit, penumbra and shadowed.
    pub const VISIBILITY: [Region; 4] = [
        Region::Translucent,
        Region::Lit,
        Region::Penumbra,
        Region::Shadowed,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Region::Translucent => "translucent",
            Region::Lit => "lit",
            Region::Penumbra => "penumbra",
            Region::Shadowed => "shadowed",
            Region::Disoccluded => "disoccluded",
        }
    }
}

impl fmt::Display for Region {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.pad(self.name())
    }
}

/// The region membership of every pixel of one frame (row-major, as the G-buffer).
#[derive(Clone, Debug, PartialEq)]
pub struct Regions {
    pub width: u32,
    pub height: u32,
    /// Per pixel: `None` if x1 is not on a translucent object, else the number of visible light
    /// samples out of [`VISIBILITY_SAMPLES`].
    visible: Vec<Option<u32>>,
    /// Per pixel: whether its primary hit failed to reproject into the previous frame.
    disoccluded: Vec<bool>,
}

impl Regions {
    /// Classifies the pixels of `gbuffer` (a frame of `scene`, whose previous frame it renders
    /// for the reprojection; light samples see the scene posed at the frame); `seed` keys the
    /// light samples.
    pub fn classify(scene: &Scene, gbuffer: &GBuffer, seed: u64) -> Regions {
        let scene = &*scene.at_frame(gbuffer.frame);
        let previous = (gbuffer.frame.checked_sub(1)).map(|f| GBuffer::render(scene, f));
        let disoccluded = (gbuffer.pixels.iter())
            .map(|g| {
                g.as_ref().is_some_and(|g| {
                    (previous.as_ref()).is_none_or(|p| p.reproject(&scene.camera, g).is_none())
                })
            })
            .collect();
        // Parallel over pixels; each pixel's light samples come from its own keyed stream.
        let visible = gbuffer
            .pixels
            .par_iter()
            .enumerate()
            .map(|(pixel, g)| {
                let g = g.as_ref()?;
                matches!(scene.material_of_object(g.object), Material::Translucent(_))
                    .then(|| visible_light_samples(scene, g, pixel as u32, gbuffer.frame, seed))
            })
            .collect();
        Regions {
            width: gbuffer.width,
            height: gbuffer.height,
            visible,
            disoccluded,
        }
    }

    /// Regions from per-pixel visible-sample counts (`None` = not translucent), every pixel
    /// reprojected; `None` if `visible` does not hold `width · height` pixels or a count exceeds
    /// [`VISIBILITY_SAMPLES`].
    pub fn from_visible_samples(
        width: u32,
        height: u32,
        visible: Vec<Option<u32>>,
    ) -> Option<Regions> {
        let valid = visible.len() == width as usize * height as usize
            && visible.iter().flatten().all(|&v| v <= VISIBILITY_SAMPLES);
        valid.then(|| Regions {
            width,
            height,
            disoccluded: vec![false; visible.len()],
            visible,
        })
    }

    /// Number of pixels.
    pub fn len(&self) -> usize {
        self.visible.len()
    }

    pub fn is_empty(&self) -> bool {
        self.visible.is_empty()
    }

    /// Visible light samples at `pixel` out of [`VISIBILITY_SAMPLES`]; `None` off translucent
    /// objects or outside the image.
    pub fn visible_samples(&self, pixel: usize) -> Option<u32> {
        self.visible.get(pixel).copied().flatten()
    }

    /// Whether `pixel` belongs to `region`.
    pub fn contains(&self, region: Region, pixel: usize) -> bool {
        let Some(visible) = self.visible_samples(pixel) else {
            return false;
        };
        match region {
            Region::Translucent => true,
            Region::Lit => visible == VISIBILITY_SAMPLES,
            Region::Penumbra => visible > 0 && visible < VISIBILITY_SAMPLES,
            Region::Shadowed => visible == 0,
            Region::Disoccluded => self.disoccluded[pixel],
        }
    }

    /// The pixels of `region`, ascending.
    pub fn pixels(&self, region: Region) -> Vec<usize> {
        (0..self.len())
            .filter(|&p| self.contains(region, p))
            .collect()
    }

    /// The number of pixels of `region`.
    pub fn count(&self, region: Region) -> usize {
        (0..self.len())
            .filter(|&p| self.contains(region, p))
            .count()
    }
}

/// Light samples from x1 whose shadow segment x1 → x3 is free, out of [`VISIBILITY_SAMPLES`].
fn visible_light_samples(scene: &Scene, g: &GPixel, pixel: u32, frame: u32, seed: u64) -> u32 {
    let mut stream = StreamKey {
        pixel,
        frame,
        pass: REGIONS_PASS,
        purpose: 0,
    }
    .stream(seed);
    let mut visible = 0;
    for i in 0..VISIBILITY_SAMPLES {
        let (sx, sy) = ((i % STRATA) as f32, (i / STRATA) as f32);
        let u = [
            stream.next_f32(),
            (sx + stream.next_f32()) / STRATA as f32,
            (sy + stream.next_f32()) / STRATA as f32,
        ];
        let Some(light) = scene.lights.sample(g.position, u) else {
            continue;
        };
        visible += u32::from(!occluded(scene, g, light.point));
    }
    visible
}

/// Whether the segment from x1 (lifted off its surface toward x3's side by the path tracer's
/// [`SHADOW_EPSILON`]) to x3 hits geometry.
fn occluded(scene: &Scene, g: &GPixel, x3: Vec3) -> bool {
    let side = if g.geometric_normal.dot(x3 - g.position) < 0.0 {
        -1.0
    } else {
        1.0
    };
    let origin = g.position + side * SHADOW_EPSILON * g.geometric_normal;
    scene
        .geometry
        .occluded(&Ray::segment(Vec3A::from(origin), Vec3A::from(x3)))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Built-in scene `name` at `width × height`.
    fn builtin(name: &str, width: u32, height: u32) -> Scene {
        let scene = Scene::builtin(name).expect("built-in");
        Scene {
            camera: scene.camera.with_resolution(width, height),
            ..scene
        }
    }

    /// `half-shadow` (directional light straight down, occluder over x < 0): the classification
    /// matches the analytic shadow edge x = 0 for every translucent pixel farther than 1e-3 from
    /// it, and a directional light has no penumbra. Negative control: the same scene without
    /// its occluder must classify the x < 0 half as lit, i.e. fail the same check.
    #[test]
    fn half_shadow_matches_analytic_edge() {
        let scene = builtin("half-shadow", 24, 24);
        let gbuffer = GBuffer::render(&scene, 15);
        let regions = Regions::classify(&scene, &gbuffer, 7);
        assert_eq!(
            mismatches_with_half_plane(&regions, &gbuffer),
            Vec::<usize>::new()
        );
        assert_eq!(regions.count(Region::Penumbra), 0);
        let (lit, shadowed) = (regions.count(Region::Lit), regions.count(Region::Shadowed));
        assert!(lit > 50 && shadowed > 50, "lit {lit}, shadowed {shadowed}");
        assert_eq!(lit + shadowed, regions.count(Region::Translucent));

        let text = include_str!("../../scenes/half-shadow.toml");
        let occluder = text
            .find("[[objects]]\nname = \"occluder\"")
            .expect("occluder");
        let lights = text.find("[[lights]]").expect("lights");
        let open = format!("{}{}", &text[..occluder], &text[lights..]);
        let open = Scene::from_toml_str(&open, std::path::Path::new("half-shadow-open.toml"))
            .expect("parses");
        let open = Scene {
            camera: open.camera.with_resolution(24, 24),
            ..open
        };
        let open_gbuffer = GBuffer::render(&open, 15);
        let control = Regions::classify(&open, &open_gbuffer, 7);
        let wrong = mismatches_with_half_plane(&control, &open_gbuffer).len();
        assert!(
            wrong > 50,
            "negative control: without the occluder only {wrong} pixels disagree with x < 0"
        );
    }

    /// Translucent pixels at |x| > 1e-3 whose class disagrees with "shadowed ⇔ x < 0".
    fn mismatches_with_half_plane(regions: &Regions, gbuffer: &GBuffer) -> Vec<usize> {
        (0..regions.len())
            .filter(|&p| regions.contains(Region::Translucent, p))
            .filter(|&p| {
                let x = gbuffer.pixels[p]
                    .expect("translucent pixels have a hit")
                    .position
                    .x;
                let want = if x < 0.0 {
                    Region::Shadowed
                } else {
                    Region::Lit
                };
                x.abs() > 1e-3 && !regions.contains(want, p)
            })
            .collect()
    }

    /// `bumpy` at frame 15: the shadow edge crosses the object, so lit, penumbra and shadowed are
    /// all present; they partition the translucent pixels; and Lambert pixels are in no region.
    #[test]
    fn bumpy_regions_partition_the_object() {
        let scene = builtin("bumpy", 40, 30);
        let gbuffer = GBuffer::render(&scene, 15);
        let regions = Regions::classify(&scene, &gbuffer, 3);
        let counts = Region::VISIBILITY.map(|r| regions.count(r));
        assert!(counts.iter().all(|&c| c > 0), "{counts:?}");
        assert_eq!(counts[0], counts[1] + counts[2] + counts[3], "{counts:?}");
        for (p, g) in gbuffer.pixels.iter().enumerate() {
            let translucent = g.is_some_and(|g| {
                matches!(scene.material_of_object(g.object), Material::Translucent(_))
            });
            let members = Region::VISIBILITY
                .iter()
                .filter(|&&r| regions.contains(r, p))
                .count();
            assert_eq!(members, if translucent { 2 } else { 0 }, "pixel {p}");
            assert!(translucent || !regions.contains(Region::Disoccluded, p));
        }
    }

    /// The disoccluded pixels of `bumpy`'s frame 15 are the translucent pixels whose primary hit
    /// the previous frame's G-buffer does not show (the temporal pass's rule): some along the
    /// moving camera's path, not all. Controls: at frame 0 every translucent pixel is
    /// disoccluded; with the camera at rest and no jitter none is. Printed: the counts at rest
    /// and moving, with and without jitter, at 40×30 and 256×192 (the jitter alone moves a hit
    /// by up to a pixel, which on the bumps fails the depth or normal test: about half the
    /// pixels at 40×30, 3% at 256×192).
    #[test]
    fn disoccluded_pixels_are_those_temporal_reuse_cannot_reproject() {
        let scene = builtin("bumpy", 40, 30);
        let gbuffer = GBuffer::render(&scene, 15);
        let regions = Regions::classify(&scene, &gbuffer, 3);
        let previous = GBuffer::render(&scene, 14);
        let expected: Vec<usize> = (0..regions.len())
            .filter(|&p| regions.contains(Region::Translucent, p))
            .filter(|&p| {
                let g = gbuffer.pixels[p].as_ref().unwrap();
                previous.reproject(&scene.camera, g).is_none()
            })
            .collect();
        assert_eq!(regions.pixels(Region::Disoccluded), expected);
        let (disoccluded, translucent) = (expected.len(), regions.count(Region::Translucent));
        eprintln!("disoccluded: {disoccluded} of {translucent} translucent pixels");
        assert!(
            disoccluded > 0 && disoccluded < translucent,
            "{disoccluded} of {translucent}"
        );
        let first = Regions::classify(&scene, &GBuffer::render(&scene, 0), 3);
        assert_eq!(
            first.count(Region::Disoccluded),
            first.count(Region::Translucent)
        );
        for (w, h) in [(40, 30), (256, 192)] {
            for jitter in [true, false] {
                let s = Scene {
                    camera: scene
                        .camera
                        .at_rest()
                        .with_resolution(w, h)
                        .with_jitter(jitter),
                    ..scene.clone()
                };
                let r = Regions::classify(&s, &GBuffer::render(&s, 15), 3);
                let m = Scene {
                    camera: scene.camera.with_resolution(w, h).with_jitter(jitter),
                    ..scene.clone()
                };
                let mr = Regions::classify(&m, &GBuffer::render(&m, 15), 3);
                eprintln!(
                    "{w}x{h} jitter {jitter}: at rest {} of {}, moving {} of {}",
                    r.count(Region::Disoccluded),
                    r.count(Region::Translucent),
                    mr.count(Region::Disoccluded),
                    mr.count(Region::Translucent)
                );
            }
        }
        let rest = Scene {
            camera: scene.camera.at_rest().with_jitter(false),
            ..scene
        };
        let still = Regions::classify(&rest, &GBuffer::render(&rest, 15), 3);
        assert_eq!(
            still.count(Region::Disoccluded),
            0,
            "control: a camera at rest"
        );
    }
}
