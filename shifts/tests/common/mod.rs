//! Test support: real SSS domains from built-in scenes, pairs of pixels (spatial neighbours
//! within the spatial radius, temporal pairs across frames), and a BSSRDF IS sampler of test
//! points.
#![allow(dead_code)] // each test binary uses a different part of this module

use std::sync::OnceLock;

use glam::Vec3;
use restir::rng::{Stream, StreamKey};
use restir::shift::{CandidateSampler, Domain};
use shifts::{SssDomain, SssSample, Target};
use sss::bssrdf::{BssrdfSample, EntryPoint, Probe, pick_hit};
use sss::material::{Material, Translucent};
use sss::scene::{Camera, GBuffer, Scene};

/// Run seed of every test stream.
pub const SEED: u64 = 0x5_1F75;

/// A built-in scene with the G-buffers of frames 0 and 1, and the target function `p̂` of its
/// domains.
pub struct Fixture {
    /// The scene as loaded (its objects posed at frame 0).
    pub scene: Scene,
    /// The scene posed at frames 0 and 1 (`Scene::at_frame`): the domains of frame `f` see
    /// `posed[f]`, so a temporal pair of a moving object spans two poses.
    pub posed: [Scene; 2],
    pub frames: [GBuffer; 2],
    pub target: Target,
}

/// The fixture of built-in scene `name` ("bumpy", "half-shadow", "far-knot" or "passing"),
/// built once per test binary.
pub fn fixture(name: &str) -> &'static Fixture {
    static BUMPY: OnceLock<Fixture> = OnceLock::new();
    static HALF_SHADOW: OnceLock<Fixture> = OnceLock::new();
    static FAR_KNOT: OnceLock<Fixture> = OnceLock::new();
    static PASSING: OnceLock<Fixture> = OnceLock::new();
    let cell = match name {
        "bumpy" => &BUMPY,
        "half-shadow" => &HALF_SHADOW,
        "far-knot" => &FAR_KNOT,
        "passing" => &PASSING,
        _ => panic!("no test fixture for scene {name}"),
    };
    cell.get_or_init(|| Fixture::new(name))
}

/// The scenes every conformance test runs on.
pub const SCENES: [&str; 2] = ["bumpy", "half-shadow"];

impl Fixture {
    pub fn new(name: &str) -> Fixture {
        Fixture::with_target(name, Target::Luminance)
    }

    /// The fixture of built-in scene `name` whose domains have the target `target`.
    pub fn with_target(name: &str, target: Target) -> Fixture {
        let mut scene = Scene::builtin(name).unwrap_or_else(|| panic!("no built-in scene {name}"));
        // The framing the conformance checks were designed and measured on (`bumpy` was 160 ×
        // 120 in its file then; its pixel pairs and charts are these).
        if name == "bumpy" {
            scene.camera = scene.camera.with_resolution(160, 120);
        }
        // The moving wax sphere of `passing` fills the view: its temporal pairs span its poses
        // of frames 0 and 1.
        if name == "passing" {
            let (eye, target) = (Vec3::new(0.0, 1.1, 3.0), Vec3::new(-0.17, 0.6, 0.95));
            scene.camera = Camera::new([64, 64], 12.0, [eye; 2], [target; 2], Vec3::Y, true);
        }
        let posed = [0, 1].map(|f| scene.at_frame(f).into_owned());
        let frames = [GBuffer::render(&scene, 0), GBuffer::render(&scene, 1)];
        Fixture {
            scene,
            posed,
            frames,
            target,
        }
    }

    /// The domain of pixel `(px, py)` of `frame` (0 or 1), receiving in `pass`, with the
    /// fixture's target; `None` off the translucent object.
    pub fn domain(&self, frame: u32, px: i64, py: i64, pass: u32) -> Option<SssDomain<'_>> {
        self.domain_with_seed(frame, px, py, pass, SEED)
    }

    /// `domain` under the run seed `seed` (the key of the shifts' own random numbers, such as
    /// probabilistic inversion's γ).
    pub fn domain_with_seed(
        &self,
        frame: u32,
        px: i64,
        py: i64,
        pass: u32,
        seed: u64,
    ) -> Option<SssDomain<'_>> {
        let g = &self.frames[frame as usize];
        if px < 0 || py < 0 || px >= g.width as i64 || py >= g.height as i64 {
            return None;
        }
        let (px, py) = (px as u32, py as u32);
        SssDomain::new(
            &self.posed[frame as usize],
            g.get(px, py)?,
            py * g.width + px,
            frame,
            pass,
            seed,
        )
        .map(|d| d.with_target(self.target))
    }

    /// The scene's (first) translucent material.
    pub fn domain_material(&self) -> &Translucent {
        self.scene
            .materials
            .iter()
            .find_map(|m| match m {
                Material::Translucent(t) => Some(t),
                Material::Lambert(_) => None,
            })
            .expect("a translucent material")
    }

    /// The spatial radius (pixels) at a domain: 2·max d projected, clamped to [5, 30] (DESIGN §9).
    pub fn spatial_radius(&self, d: &SssDomain) -> f32 {
        let max_d = d.material().d().max_element();
        self.scene
            .camera
            .spatial_radius_px(d.frame(), d.x1().position, 2.0 * max_d)
            .clamp(5.0, 30.0)
    }

    /// `count` receivers on the translucent object of frame `frame`, drawn uniformly.
    fn receivers(&self, frame: u32, count: usize, rng: &mut Stream) -> Vec<(i64, i64)> {
        let g = &self.frames[frame as usize];
        let mut out = Vec::new();
        while out.len() < count {
            let px = (rng.next_f32() * g.width as f32) as i64;
            let py = (rng.next_f32() * g.height as f32) as i64;
            if self.domain(frame, px, py, 0).is_some() {
                out.push((px, py));
            }
        }
        out
    }

    /// `count` (neighbour, receiver) pairs of frame 1: the neighbour uniform in the disk of the
    /// spatial radius around the receiver, both on the translucent object.
    pub fn spatial_pairs(&self, count: usize, purpose: u32) -> Vec<(SssDomain<'_>, SssDomain<'_>)> {
        let mut rng = StreamKey::new(0, 1, 0, purpose).stream(SEED);
        let mut pairs = Vec::new();
        while pairs.len() < count {
            let (px, py) = self.receivers(1, 1, &mut rng)[0];
            let receiver = self.domain(1, px, py, 1).expect("receiver on the object");
            let radius = self.spatial_radius(&receiver);
            let (r, phi) = (
                radius * rng.next_f32().sqrt(),
                std::f32::consts::TAU * rng.next_f32(),
            );
            let (nx, ny) = (
                px + (r * phi.cos()).round() as i64,
                py + (r * phi.sin()).round() as i64,
            );
            if (nx, ny) == (px, py) {
                continue;
            }
            if let Some(neighbour) = self.domain(1, nx, ny, 1) {
                pairs.push((neighbour, receiver));
            }
        }
        pairs
    }

    /// A receiver of frame 1 and `k` distinct neighbours in its spatial-radius disk, all on the
    /// translucent object (one spatial pass with `k` neighbours).
    pub fn neighbourhood(&self, k: usize, purpose: u32) -> (SssDomain<'_>, Vec<SssDomain<'_>>) {
        let mut rng = StreamKey::new(0, 1, 0, purpose).stream(SEED);
        let (px, py) = self.receivers(1, 1, &mut rng)[0];
        let receiver = self.domain(1, px, py, 1).expect("receiver on the object");
        let radius = self.spatial_radius(&receiver);
        let mut taken = vec![(px, py)];
        let mut neighbours = Vec::new();
        for _ in 0..1000 {
            if neighbours.len() == k {
                break;
            }
            let (r, phi) = (
                radius * rng.next_f32().sqrt(),
                std::f32::consts::TAU * rng.next_f32(),
            );
            let (nx, ny) = (
                px + (r * phi.cos()).round() as i64,
                py + (r * phi.sin()).round() as i64,
            );
            if taken.contains(&(nx, ny)) {
                continue;
            }
            if let Some(n) = self.domain(1, nx, ny, 1) {
                taken.push((nx, ny));
                neighbours.push(n);
            }
        }
        assert_eq!(neighbours.len(), k, "too few neighbours on the object");
        (receiver, neighbours)
    }

    /// `count` (previous frame, current frame) pairs: the same pixel of frames 0 and 1 (the
    /// camera moves between them), both on the translucent object.
    pub fn temporal_pairs(
        &self,
        count: usize,
        purpose: u32,
    ) -> Vec<(SssDomain<'_>, SssDomain<'_>)> {
        let mut rng = StreamKey::new(0, 0, 0, purpose).stream(SEED);
        let mut pairs = Vec::new();
        for (px, py) in self.receivers(1, 4 * count, &mut rng) {
            if let Some(previous) = self.domain(0, px, py, 1) {
                pairs.push((
                    previous,
                    self.domain(1, px, py, 1).expect("receiver on the object"),
                ));
            }
            if pairs.len() == count {
                break;
            }
        }
        assert_eq!(pairs.len(), count, "too few temporal pairs on the object");
        pairs
    }
}

/// References to the domains of `pairs`, as `restir::check::ShiftCase` wants them.
pub fn refs<'a, 's>(
    pairs: &'a [(SssDomain<'s>, SssDomain<'s>)],
) -> Vec<(&'a SssDomain<'s>, &'a SssDomain<'s>)> {
    pairs.iter().map(|(a, b)| (a, b)).collect()
}

/// BSSRDF IS at x1 (technique, radius and angle from the stream), one hit of the probe picked
/// uniformly (its rank stored as the intersection index), a light sample at x2; samples with
/// `p̂ = 0` are dropped (`None`), and with `shadow_test` also samples whose x2–x3 segment is
/// occluded, like canonical samples after the shadow test. The sample's random numbers
/// regenerate x2 at this x1.
///
/// The returned density is `p_disk · p_light`, the density of the candidate *set* of a probe
/// [001 Eq. 10], not of the single picked hit: the kit's checks 1–4 use only the points.
pub struct ProbeSampler {
    pub shadow_test: bool,
}

/// Test points of shifts: visible paths, the domain on which shifts that test visibility are
/// bijections.
pub const VISIBLE: ProbeSampler = ProbeSampler { shadow_test: true };
/// Test points of MIS weights: every path with `p̂ > 0` (a canonical sample is kept when occluded).
pub const UNSHADOWED: ProbeSampler = ProbeSampler { shadow_test: false };

impl ProbeSampler {
    /// The sample and `(p_disk, p_light)`, before the support and visibility filter.
    pub fn draw(domain: &SssDomain, rng: &mut Stream) -> Option<(SssSample, f32, f32)> {
        let geometry = &domain.scene().geometry;
        let probe = Probe::sample(
            domain.selection(),
            rng.next_f32(),
            rng.next_f32(),
            rng.next_f32(),
        );
        let mut hits = Vec::new();
        probe.trace(geometry, domain.x1(), &mut hits);
        let (rank, hit) = pick_hit(&hits, None, rng.next_f32())?;
        let x2 = EntryPoint::from_hit(geometry, &hit);
        let p_disk = domain.p_disk(&x2);
        let light = domain.scene().lights.sample(
            x2.position,
            [rng.next_f32(), rng.next_f32(), rng.next_f32()],
        )?;
        let bssrdf = BssrdfSample::new(&probe, Some(rank), &x2, p_disk);
        Some((
            SssSample::new(&bssrdf, light.light, light.point),
            p_disk,
            light.pdf,
        ))
    }
}

impl CandidateSampler<SssDomain<'_>> for ProbeSampler {
    fn sample(&self, domain: &SssDomain, rng: &mut Stream) -> Option<(SssSample, f32)> {
        let (y, p_disk, p_light) = Self::draw(domain, rng)?;
        (domain.target(&y) > 0.0 && (!self.shadow_test || domain.visible(&y)))
            .then_some((y, p_disk * p_light))
    }

    fn pdf(&self, domain: &SssDomain, x: &SssSample) -> f32 {
        let Some(x2) = domain.entry_point(x) else {
            return 0.0;
        };
        let lights = &domain.scene().lights;
        let p_light = if lights.get(x.light()).is_delta() {
            lights.selection_pmf(x.light())
        } else {
            lights.pdf(x2.position, x.light(), x.x3())
        };
        domain.p_disk(&x2) * p_light
    }
}
