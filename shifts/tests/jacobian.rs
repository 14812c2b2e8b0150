//! Check 3 of `restir::check`, the finite-difference Jacobian, for delayed reconnection
//! [001 Eq. 11] on the bumpy scene (curved surface, quad light), spatial and temporal pairs.
//!
//! `SssDomain`'s path coordinates cannot be turned back into a sample, so each test point gets
//! a chart: x2 in orthonormal coordinates of its triangle's plane (area measure) and, for an
//! area light, x3 as the direction ω at x2 in coordinates `(z, φ)` around a fixed axis
//! (`dω = dz dφ`), so `p̂`'s measure (area at x2 × solid angle at x2) is Lebesgue in the chart.
//! Moving x2 within the chart re-inverts the stored technique at the source x1
//! (`invert_technique`), so the perturbed sample's random numbers regenerate it, as delayed
//! reconnection requires.
//!
//! The chart measures the map of one technique, whose Jacobian is `q_t(x2|x1)/q_t(y2|y1)` with
//! `q_t = P(t) p_{d_c}(r_a)|n2·axis_a|`; delayed reconnection uses the nine-technique `p_disk`
//! (DESIGN §5). The two agree when the selection has a single technique, so the test runs once
//! per axis with a one-technique selection.

mod common;

use common::{SEED, VISIBLE, fixture, refs};
use glam::{Vec2, Vec3};
use restir::check::{CheckReport, ShiftCase, finite_difference_jacobian, negative_control};
use restir::rng::{Stream, StreamKey};
use restir::shift::{CandidateSampler, Domain, Fail, LocalCoords, Shift, Shifted};
use shifts::broken::DelayedWithoutJacobian;
use shifts::{DelayedReconnection, SssDomain, SssSample};
use sss::bssrdf::{BssrdfSample, EntryPoint, TechniqueSelection, invert_technique};
use sss::geometry::Frame;
use sss::scene::Light;

/// Relative step of the kit: `h = 0.1 · 0.01` = 1e-3 scene units / radians (coordinates are
/// centred on the test point, so `|x_k| < 0.01`). The map is f32 (`u_radius` stored with 2⁻²⁴
/// resolution, y2 from an f32 ray hit), so the difference quotient carries ~1e-7 / h of
/// rounding: at h = 4e-4 the worst error was 2.2e-3, at 1e-3 it is below 1e-3.
const RELATIVE_STEP: f64 = 0.1;
/// DESIGN §3's relative tolerance of check 3.
const TOLERANCE: f64 = 1e-3;
/// Test points closer than this to an edge of their triangle (or whose image is) are left out:
/// the stencil (±h in x2 and in ω, moving y2 by similar amounts) would leave the chart. The bumpy
/// sphere's triangles have inradius ≈ 5e-3.
const MARGIN: f32 = 3e-3;
const PAIRS: usize = 24;
const POINTS: usize = 32;

/// One domain seen through the chart of one sample (see the module documentation).
struct Chart<'a, 's> {
    domain: &'a SssDomain<'s>,
    template: SssSample,
    origin: Vec3,
    plane: [Vec3; 2],
    /// `(axis, b, c)` of the direction coordinates; `None` for delta lights (x3 is no dimension).
    directions: Option<[Vec3; 3]>,
}

impl<'a, 's> Chart<'a, 's> {
    fn new(domain: &'a SssDomain<'s>, template: SssSample) -> Chart<'a, 's> {
        let geometry = &domain.scene().geometry;
        let origin = geometry.position(template.prim(), template.bary());
        let normal = geometry.geometric_normal(template.prim());
        let [v0, v1, _] = geometry.vertices(template.prim());
        let e1 = (v1 - v0).normalize();
        let plane = [e1, normal.cross(e1)];
        let directions = (!domain.scene().lights.get(template.light()).is_delta()).then(|| {
            let w = (template.x3() - origin).normalize();
            let f = Frame::from_normal(w);
            [f.t, w, f.b]
        });
        Chart {
            domain,
            template,
            origin,
            plane,
            directions,
        }
    }

    /// Barycentrics of the in-plane point `p` in the template's triangle; `None` outside it.
    fn bary(&self, p: Vec3) -> Option<Vec2> {
        let [v0, v1, v2] = self.domain.scene().geometry.vertices(self.template.prim());
        let (a, b, d) = (v1 - v0, v2 - v0, p - v0);
        let (aa, ab, bb, da, db) = (a.dot(a), a.dot(b), b.dot(b), d.dot(a), d.dot(b));
        let det = aa * bb - ab * ab;
        let (u, v) = ((bb * da - ab * db) / det, (aa * db - ab * da) / det);
        (u >= 0.0 && v >= 0.0 && u + v <= 1.0).then_some(Vec2::new(u, v))
    }

    /// Where the ray from `p` along `w` meets the plane of the template's light.
    fn light_point(&self, p: Vec3, w: Vec3) -> Option<Vec3> {
        let (anchor, normal) = match *self.domain.scene().lights.get(self.template.light()) {
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
    type Sample = SssSample;
    fn target(&self, x: &SssSample) -> f32 {
        self.domain.target(x)
    }
}

impl LocalCoords for Chart<'_, '_> {
    fn dim(&self) -> usize {
        if self.directions.is_some() { 4 } else { 2 }
    }

    fn to_local(&self, x: &SssSample, out: &mut [f64]) {
        let p = self.domain.scene().geometry.position(x.prim(), x.bary());
        out[0] = (p - self.origin).dot(self.plane[0]) as f64;
        out[1] = (p - self.origin).dot(self.plane[1]) as f64;
        if let Some([axis, b, c]) = self.directions {
            let w = (x.x3() - p).normalize();
            out[2] = w.dot(axis) as f64;
            out[3] = w.dot(c).atan2(w.dot(b)) as f64;
        }
    }

    fn sample_at_local(&self, coords: &[f64]) -> Option<SssSample> {
        let p = self.origin + coords[0] as f32 * self.plane[0] + coords[1] as f32 * self.plane[1];
        let x2 = EntryPoint::new(
            &self.domain.scene().geometry,
            self.template.prim(),
            self.bary(p)?,
        );
        let x3 = match self.directions {
            Some([axis, b, c]) => {
                let (z, phi) = (coords[2] as f32, coords[3] as f32);
                let w = z * axis + (1.0 - z * z).max(0.0).sqrt() * (phi.cos() * b + phi.sin() * c);
                self.light_point(x2.position, w)?
            }
            None => self.template.x3(),
        };
        let probe = invert_technique(self.domain.x1(), self.template.technique()?, x2.position);
        let bssrdf = BssrdfSample::new(&probe, self.template.index(), &x2, self.domain.p_disk(&x2));
        Some(SssSample::new(&bssrdf, self.template.light(), x3))
    }
}

/// A shift of `SssDomain`s applied to charts; an image off the destination chart's triangle
/// (which the chart cannot represent) fails, so the kit skips that stencil.
struct OnChart<'t, T>(&'t T);

impl<'a, 's, T: Shift<SssDomain<'s>>> Shift<Chart<'a, 's>> for OnChart<'_, T> {
    fn shift(
        &self,
        x: &SssSample,
        src: &Chart<'a, 's>,
        dst: &Chart<'a, 's>,
    ) -> Result<Shifted<SssSample>, Fail> {
        let shifted = self.0.shift(x, src.domain, dst.domain)?;
        if shifted.y.prim() != dst.template.prim() {
            return Err(Fail::OutOfSupport);
        }
        Ok(shifted)
    }
}

/// Each chart's own template is its one test point.
struct Templates;

impl<'a, 's> CandidateSampler<Chart<'a, 's>> for Templates {
    fn sample(&self, chart: &Chart<'a, 's>, _: &mut Stream) -> Option<(SssSample, f32)> {
        Some((chart.template, 1.0))
    }
    fn pdf(&self, _: &Chart<'a, 's>, _: &SssSample) -> f32 {
        1.0
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

/// The single-technique selections: normal axis / red, tangent / green, bitangent / blue.
fn single_techniques() -> [TechniqueSelection; 3] {
    std::array::from_fn(|i| {
        let mut one = [0.0; 3];
        one[i] = 1.0;
        TechniqueSelection {
            axis: one,
            channel: one,
        }
    })
}

/// Check 3 of `shift` on charts around delayed-reconnection test points of the bumpy scene.
fn fd_reports<T>(shift: &T) -> Vec<(String, CheckReport)>
where
    T: for<'s> Shift<SssDomain<'s>>,
{
    let fx = fixture("bumpy");
    let mut reports = Vec::new();
    for (s, selection) in single_techniques().into_iter().enumerate() {
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
                if let Ok(fwd) = DelayedReconnection.shift(&x, src, dst)
                    && edge_margin(src, &x) > MARGIN
                    && edge_margin(dst, &fwd.y) > MARGIN
                {
                    charts.push((Chart::new(src, x), Chart::new(dst, fwd.y)));
                }
            }
        }
        let case = ShiftCase {
            pairs: charts.iter().map(|(a, b)| (a, b)).collect(),
            sampler: &Templates,
            samples_per_pair: 1,
            seed: SEED,
        };
        let label = format!("technique {s}, {} spatial + temporal charts", charts.len());
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
