//! Check 3 of `restir::check`, the finite-difference Jacobian, for delayed reconnection
//! [001 Eq. 11] on the bumpy scene (curved surface, quad light), spatial and temporal pairs, in
//! the coordinates of paper 001's extended path space `P × Γ` [001 App. A].
//!
//! `SssDomain`'s path coordinates cannot be turned back into a sample, so each test point gets
//! a chart: x2 in orthonormal coordinates of its triangle's plane (area measure); for an area
//! light, x3 as the direction ω at x2 in coordinates `(z, φ)` around a fixed axis
//! (`dω = dz dφ`); and γ, the number that picks the technique from its posterior at x1
//! [001 Alg. 4, line 1]. A chart point `(x2, ω, γ)` becomes a sample by probabilistic inversion at
//! the source x1 (technique by γ, `u_radius`, `u_angle`, index re-traced), the sample the
//! sequential scheme's delayed pass receives.
//!
//! Why γ. BSSRDF IS draws `u = (u_technique, u_radius, u_angle)` uniformly; writing
//! `u_technique` as the technique `t` and its relative position `v` in `t`'s interval, the map
//! `u ↦ (x2, γ)` with `γ = lo_t(x2) + v · post_t(x2)` (`[lo_t, lo_t + post_t)` = the γ's that pick
//! `t` given x2) sends the uniform measure to `p_disk(x2) dA dγ`: x2 from the nine-technique
//! mixture and γ uniform. Delayed reconnection keeps `u`, so it keeps `t` and `v`, and in
//! `(x2, ω, γ)` its Jacobian is `p_disk(x2|x1)/p_disk(y2|y1)` (times the light factor): the
//! block of x2 gives the stored technique's ratio `q_t(x2|x1)/q_t(y2|y1)`, the γ block
//! `post_t(y2|y1)/post_t(x2|x1)`, and `post_t = q_t / p_disk`. In these coordinates the map is
//! smooth (within one technique's γ interval), so central differences measure the mixture
//! ratio directly. The charts carry `v` beside the sample; templates keep γ inside its interval
//! (`V_MARGIN`, `MIN_POSTERIOR`), and stencil points where γ would pick another technique are
//! outside the chart (the kit skips them).
//!
//! Controls: `J = 1` (`DelayedWithoutJacobian`), and the stored technique's own density ratio
//! in place of the mixture's (`PerTechniqueRatio`), which the nine-technique selection detects
//! and a one-technique selection cannot (there the two ratios are equal).

mod common;

use common::{SEED, VISIBLE, fixture, refs};
use geometry::Frame;
use glam::{Vec2, Vec3};
use restir::check::{CheckReport, ShiftCase, finite_difference_jacobian, negative_control};
use restir::rng::{Stream, StreamKey};
use restir::shift::{CandidateSampler, Domain, Fail, LocalCoords, Shift, Shifted};
use shifts::broken::DelayedWithoutJacobian;
use shifts::{DelayedReconnection, SssDomain, SssSample};
use sss::bssrdf::{
    BssrdfSample, EntryPoint, Technique, TechniqueSelection, find_index, invert_random_numbers,
    technique_terms,
};
use sss::scene::Light;

/// Relative step of the kit: `h = 0.1 · 0.01` = 1e-3 scene units / radians / units of γ
/// (coordinates are centred on the test point, so `|x_k| < 0.01`). The map is f32 (`u_radius`
/// stored with 2⁻²⁴ resolution, y2 from an f32 ray hit), so the difference quotient carries
/// ~1e-7 / h of rounding: at h = 4e-4 the worst error was 2.2e-3, at 1e-3 it is below 1e-3.
const RELATIVE_STEP: f64 = 0.1;
/// DESIGN §3's relative tolerance of check 3.
const TOLERANCE: f64 = 1e-3;
/// Test points closer than this to an edge of their triangle (or whose image is) are left out:
/// the stencil (±h in x2 and in ω, moving y2 by similar amounts) would leave the chart. The bumpy
/// sphere's triangles have inradius ≈ 5e-3.
const MARGIN: f32 = 3e-3;
/// Test points closer than this to the `r_max,c` sphere of their technique's channel around x1
/// (or whose image is, around y1) are left out: the technique's support ends there, and the
/// stencil would leave it.
const BALL_MARGIN: f32 = 5e-3;
/// Templates keep γ at relative position `v ∈ [V_MARGIN, 1 − V_MARGIN]` of an interval of width
/// `post_t ≥ MIN_POSTERIOR`: at least 0.01 = 10 h from its ends.
const V_MARGIN: f64 = 0.2;
const MIN_POSTERIOR: f64 = 0.05;
const PAIRS: usize = 32;
const POINTS: usize = 48;

/// A sample of the extended space: the path sample and `v`, the relative position of γ in its
/// technique's posterior interval (equal to that of `u_technique` in its prior interval, which
/// the sample does not store and delayed reconnection keeps).
#[derive(Clone, Copy, Debug)]
struct Extended {
    x: SssSample,
    v: f64,
}

/// `[lo_t, lo_t + post_t)`, the γ's that pick technique `t` at `domain`'s x1 given x2
/// [001 Alg. 4, line 1] (f64 sums of the f32 terms); `None` where `t` cannot reach x2.
fn posterior_interval(domain: &SssDomain, x2: &EntryPoint, t: Technique) -> Option<(f64, f64)> {
    let terms = technique_terms(
        domain.x1(),
        domain.selection(),
        x2.position,
        x2.geometric_normal,
    );
    let sum: f64 = terms.iter().map(|&q| q as f64).sum();
    let lo: f64 = terms[..t.index()].iter().map(|&q| q as f64).sum();
    let q = terms[t.index()] as f64;
    (sum > 0.0 && q > 0.0).then(|| (lo / sum, q / sum))
}

/// The sample of `(x2, x3)` at `domain` for γ: probabilistic inversion at x1 with the index
/// re-traced; `None` if x2 is not found on the chord.
fn invert(
    domain: &SssDomain,
    x2: &EntryPoint,
    light: u32,
    x3: Vec3,
    gamma: f32,
) -> Option<Extended> {
    let (probe, p_disk) = invert_random_numbers(domain.x1(), domain.selection(), x2, gamma).ok()?;
    let (lo, post) = posterior_interval(domain, x2, probe.technique)?;
    let mut hits = Vec::new();
    let index = find_index(&domain.scene().geometry, domain.x1(), &probe, x2, &mut hits)?;
    let bssrdf = BssrdfSample::new(&probe, Some(index), x2, p_disk);
    Some(Extended {
        x: SssSample::new(&bssrdf, light, x3),
        v: (gamma as f64 - lo) / post,
    })
}

/// γ of `e` at `domain`: `lo_t + v · post_t` for its technique and x2.
fn gamma_of(domain: &SssDomain, e: &Extended) -> Option<f64> {
    let x2 = domain.entry_point(&e.x)?;
    let (lo, post) = posterior_interval(domain, &x2, e.x.technique()?)?;
    Some(lo + e.v * post)
}

/// One domain seen through the chart of one sample (see the module documentation).
struct Chart<'a, 's> {
    domain: &'a SssDomain<'s>,
    template: Extended,
    origin: Vec3,
    plane: [Vec3; 2],
    /// `(axis, b, c)` of the direction coordinates; `None` for delta lights (x3 is no dimension).
    directions: Option<[Vec3; 3]>,
    /// γ of the template.
    gamma: f64,
}

impl<'a, 's> Chart<'a, 's> {
    fn new(domain: &'a SssDomain<'s>, template: Extended) -> Option<Chart<'a, 's>> {
        let x = template.x;
        let geometry = &domain.scene().geometry;
        let origin = geometry.position(x.prim(), x.bary());
        let normal = geometry.geometric_normal(x.prim());
        let [v0, v1, _] = geometry.vertices(x.prim());
        let e1 = (v1 - v0).normalize();
        let plane = [e1, normal.cross(e1)];
        let directions = (!domain.scene().lights.get(x.light()).is_delta()).then(|| {
            let w = (x.x3() - origin).normalize();
            let f = Frame::from_normal(w);
            [f.t, w, f.b]
        });
        Some(Chart {
            domain,
            template,
            origin,
            plane,
            directions,
            gamma: gamma_of(domain, &template)?,
        })
    }

    /// Index of the γ coordinate.
    fn gamma_axis(&self) -> usize {
        if self.directions.is_some() { 4 } else { 2 }
    }

    /// Barycentrics of the in-plane point `p` in the template's triangle; `None` outside it.
    fn bary(&self, p: Vec3) -> Option<Vec2> {
        let [v0, v1, v2] = self
            .domain
            .scene()
            .geometry
            .vertices(self.template.x.prim());
        let (a, b, d) = (v1 - v0, v2 - v0, p - v0);
        let (aa, ab, bb, da, db) = (a.dot(a), a.dot(b), b.dot(b), d.dot(a), d.dot(b));
        let det = aa * bb - ab * ab;
        let (u, v) = ((bb * da - ab * db) / det, (aa * db - ab * da) / det);
        (u >= 0.0 && v >= 0.0 && u + v <= 1.0).then_some(Vec2::new(u, v))
    }

    /// Where the ray from `p` along `w` meets the plane of the template's light.
    fn light_point(&self, p: Vec3, w: Vec3) -> Option<Vec3> {
        let (anchor, normal) = match *self.domain.scene().lights.get(self.template.x.light()) {
            Light::Quad {
                corner,
                edge_u,
                edge_v,
                ..
            } => (corner, edge_u.cross(edge_v)),
            Light::Triangle {
                vertices: [v0, v1, v2],
                ..
            } => (v0, (v1 - v0).cross(v2 - v0)),
            ref other => panic!("the chart handles planar lights only, not {other:?}"),
        };
        let t = normal.dot(anchor - p) / normal.dot(w);
        (t > 0.0 && t.is_finite()).then(|| p + t * w)
    }
}

impl Domain for Chart<'_, '_> {
    type Sample = Extended;
    fn target(&self, e: &Extended) -> f32 {
        self.domain.target(&e.x)
    }
}

impl LocalCoords for Chart<'_, '_> {
    fn dim(&self) -> usize {
        self.gamma_axis() + 1
    }

    fn to_local(&self, e: &Extended, out: &mut [f64]) {
        let x = &e.x;
        let p = self.domain.scene().geometry.position(x.prim(), x.bary());
        out[0] = (p - self.origin).dot(self.plane[0]) as f64;
        out[1] = (p - self.origin).dot(self.plane[1]) as f64;
        if let Some([axis, b, c]) = self.directions {
            let w = (x.x3() - p).normalize();
            out[2] = w.dot(axis) as f64;
            out[3] = w.dot(c).atan2(w.dot(b)) as f64;
        }
        out[self.gamma_axis()] = gamma_of(self.domain, e).map_or(f64::NAN, |g| g - self.gamma);
    }

    /// `None` off the template's triangle, where γ picks another technique than the template's,
    /// or where x2 is not found on the chord.
    fn sample_at_local(&self, coords: &[f64]) -> Option<Extended> {
        let template = &self.template.x;
        let p = self.origin + coords[0] as f32 * self.plane[0] + coords[1] as f32 * self.plane[1];
        let x2 = EntryPoint::new(
            &self.domain.scene().geometry,
            template.prim(),
            self.bary(p)?,
        );
        let x3 = match self.directions {
            Some([axis, b, c]) => {
                let (z, phi) = (coords[2] as f32, coords[3] as f32);
                let w = z * axis + (1.0 - z * z).max(0.0).sqrt() * (phi.cos() * b + phi.sin() * c);
                self.light_point(x2.position, w)?
            }
            None => template.x3(),
        };
        let gamma = (self.gamma + coords[self.gamma_axis()]) as f32;
        let e = invert(self.domain, &x2, template.light(), x3, gamma)?;
        (e.x.technique() == template.technique()).then_some(e)
    }
}

/// A shift of `SssDomain`s applied to charts, keeping `v`; an image off the destination chart's
/// triangle (which the chart cannot represent) fails, so the kit skips that stencil.
struct OnChart<'t, T>(&'t T);

impl<'a, 's, T: Shift<SssDomain<'s>>> Shift<Chart<'a, 's>> for OnChart<'_, T> {
    fn shift(
        &self,
        e: &Extended,
        src: &Chart<'a, 's>,
        dst: &Chart<'a, 's>,
    ) -> Result<Shifted<Extended>, Fail> {
        let shifted = self.0.shift(&e.x, src.domain, dst.domain)?;
        if shifted.y.prim() != dst.template.x.prim() {
            return Err(Fail::OutOfSupport);
        }
        Ok(Shifted {
            y: Extended {
                x: shifted.y,
                v: e.v,
            },
            jacobian: shifted.jacobian,
        })
    }
}

/// Each chart's own template is its one test point.
struct Templates;

impl<'a, 's> CandidateSampler<Chart<'a, 's>> for Templates {
    fn sample(&self, chart: &Chart<'a, 's>, _: &mut Stream) -> Option<(Extended, f32)> {
        Some((chart.template, 1.0))
    }
    fn pdf(&self, _: &Chart<'a, 's>, _: &Extended) -> f32 {
        1.0
    }
}

/// Negative control: delayed reconnection with the stored technique's own density ratio
/// `q_t(x2|x1) / q_t(y2|y1)` (`q_t` = its term of `technique_terms`) in place of the mixture's
/// `p_disk(x2|x1) / p_disk(y2|y1)`, the light factor kept.
struct PerTechniqueRatio;

impl Shift<SssDomain<'_>> for PerTechniqueRatio {
    fn shift(
        &self,
        x: &SssSample,
        src: &SssDomain,
        dst: &SssDomain,
    ) -> Result<Shifted<SssSample>, Fail> {
        let shifted = DelayedReconnection.shift(x, src, dst)?;
        let t = x.technique().ok_or(Fail::Degenerate)?;
        let (x2, y2) = (
            src.entry_point(x).ok_or(Fail::Rejected)?,
            dst.entry_point(&shifted.y).ok_or(Fail::Rejected)?,
        );
        let q = |d: &SssDomain, e: &EntryPoint| {
            technique_terms(d.x1(), d.selection(), e.position, e.geometric_normal)[t.index()]
        };
        let mixture = x.p_disk() / shifted.y.p_disk();
        Ok(Shifted {
            y: shifted.y,
            jacobian: shifted.jacobian / mixture * (q(src, &x2) / q(dst, &y2)),
        })
    }
}

/// Distance from x2 of `x` to the nearest edge of its triangle (scene units).
fn edge_margin(domain: &SssDomain, x: &SssSample) -> f32 {
    let [v0, v1, v2] = domain.scene().geometry.vertices(x.prim());
    let twice_area = (v1 - v0).cross(v2 - v0).length();
    let b = x.bary();
    let bary = [1.0 - b.x - b.y, b.x, b.y];
    let opposite = [v2 - v1, v0 - v2, v1 - v0];
    (0..3)
        .map(|i| bary[i] * twice_area / opposite[i].length())
        .fold(f32::INFINITY, f32::min)
}

/// Whether `e` lies inside its chart at `domain` by the margins of the templates: x2 away from
/// its triangle's edges and from the `r_max,c` sphere, γ away from its interval's ends.
fn well_inside(domain: &SssDomain, e: &Extended) -> bool {
    let (Some(x2), Some(t)) = (domain.entry_point(&e.x), e.x.technique()) else {
        return false;
    };
    let r = (x2.position - domain.x1().position).length();
    edge_margin(domain, &e.x) > MARGIN
        && r < domain.x1().r_max[t.channel] - BALL_MARGIN
        && posterior_interval(domain, &x2, t).is_some_and(|(_, post)| post >= MIN_POSTERIOR)
        && (V_MARGIN..=1.0 - V_MARGIN).contains(&e.v)
}

/// The selections tested: paper 001's nine techniques, then the single-technique selections
/// normal axis / red, tangent / green, bitangent / blue.
fn selections() -> Vec<(String, TechniqueSelection)> {
    let single = (0..3).map(|i| {
        let mut one = [0.0; 3];
        one[i] = 1.0;
        let selection = TechniqueSelection {
            axis: one,
            channel: one,
        };
        (
            format!("technique {}", Technique::ALL[4 * i].index()),
            selection,
        )
    });
    std::iter::once(("nine techniques".to_string(), TechniqueSelection::default()))
        .chain(single)
        .collect()
}

/// Check 3 of `shift` on charts around delayed-reconnection test points of the bumpy scene,
/// one report per selection of [`selections`].
fn fd_reports<T>(shift: &T) -> Vec<(String, CheckReport)>
where
    T: for<'s> Shift<SssDomain<'s>>,
{
    let fx = fixture("bumpy");
    let mut reports = Vec::new();
    for (s, (name, selection)) in selections().into_iter().enumerate() {
        let pairs: Vec<_> = fx
            .spatial_pairs(PAIRS, 10 + s as u32)
            .into_iter()
            .chain(fx.temporal_pairs(PAIRS, 20 + s as u32))
            .map(|(a, b)| (a.with_selection(selection), b.with_selection(selection)))
            .collect();
        let mut charts = Vec::new();
        for (index, (src, dst)) in refs(&pairs).into_iter().enumerate() {
            let mut rng = StreamKey::new(index as u32, 0, 0, 30 + s as u32).stream(SEED);
            for _ in 0..POINTS {
                let Some((x, _)) = VISIBLE.sample(src, &mut rng) else {
                    continue;
                };
                let gamma = rng.next_f32();
                let Some(e) = src
                    .entry_point(&x)
                    .and_then(|x2| invert(src, &x2, x.light(), x.x3(), gamma))
                else {
                    continue;
                };
                let Ok(fwd) = DelayedReconnection.shift(&e.x, src, dst) else {
                    continue;
                };
                let image = Extended { x: fwd.y, v: e.v };
                if well_inside(src, &e)
                    && well_inside(dst, &image)
                    && let (Some(a), Some(b)) = (Chart::new(src, e), Chart::new(dst, image))
                {
                    charts.push((a, b));
                }
            }
        }
        let case = ShiftCase {
            pairs: charts.iter().map(|(a, b)| (a, b)).collect(),
            sampler: &Templates,
            samples_per_pair: 1,
            seed: SEED,
        };
        let label = format!("{name}, {} spatial + temporal charts", charts.len());
        reports.push((
            label,
            finite_difference_jacobian(&OnChart(shift), &case, RELATIVE_STEP, TOLERANCE),
        ));
    }
    reports
}

#[test]
fn delayed_reconnection_jacobian_matches_finite_differences() {
    let reports = fd_reports(&DelayedReconnection);
    for (label, report) in &reports {
        println!("delayed reconnection, {label}: {report}");
    }
    for (label, report) in reports {
        assert!(report.passed, "{label}: {report}");
        assert!(
            report.figure("tested").unwrap_or(0.0) >= 20.0,
            "{label}: too few points: {report}"
        );
    }
}

/// Negative control: `J = 1` is caught by the same check (on every selection and pair kind).
#[test]
fn missing_jacobian_is_caught_by_finite_differences() {
    for (label, report) in fd_reports(&DelayedWithoutJacobian) {
        println!("delayed without Jacobian, {label}: {report}");
        let control = negative_control("delayed reconnection without Jacobian", &[report]);
        assert!(control.passed, "{label}: {control}");
    }
}

/// Negative control: the per-technique ratio is caught with the nine techniques, and equals the
/// mixture ratio (passes) with one technique, where a test without γ could not tell them apart.
#[test]
fn per_technique_ratio_is_caught_under_the_nine_technique_selection() {
    let reports = fd_reports(&PerTechniqueRatio);
    for (label, report) in &reports {
        println!("per-technique ratio, {label}: {report}");
    }
    let (label, nine) = &reports[0];
    let control = negative_control(
        "delayed reconnection with the per-technique ratio",
        std::slice::from_ref(nine),
    );
    assert!(control.passed, "{label}: {control}");
    for (label, report) in &reports[1..] {
        assert!(report.passed, "{label}: {report}");
    }
}
