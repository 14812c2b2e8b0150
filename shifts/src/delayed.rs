//! Delayed reconnection [001 §3.2.2]: random replay of the stored BSSRDF IS draw at the new x1,
//! then reconnection to the kept light vertex x3 (DESIGN §5, §9).

use glam::Vec3;
use restir::shift::{Fail, Shift, Shifted};
use sss::bssrdf::{BssrdfSample, EntryPoint, pick_hit};
use sss::scene::{Light, Lights};

use crate::contract::{DELAYED_CHECK_JACOBIAN, DELAYED_CHECK_VISIBILITY, DELAYED_CHECKS_ALL};
use crate::domain::{PURPOSE_PICK, SssDomain};
use crate::numbers::{DeclaresNumbers, Numbers};
use crate::sample::SssSample;

/// Delayed reconnection: replays (technique, `u_radius`, `u_angle`, intersection index) at y1 →
/// y2, keeps x3, tests y2–x3 visibility (`Occluded`) and caches `p_disk(y2 | y1)`.
///
/// `J = p_disk(x2 | x1) / p_disk(y2 | y1) · |cos θ_y / cos θ_x| · ‖x3 − x2‖² / ‖x3 − y2‖²`
/// [001 Eq. 11] for area-type lights (quad, triangle, sphere: x3 is fixed, its solid angle at x2
/// changes). For delta lights x3 is not a dimension of the path (a point light has one point, a
/// directional light one direction, kept as such), so `J = p_disk(x2 | x1) / p_disk(y2 | y1)`.
/// The full nine-technique `p_disk` replaces the stored technique's own density; this is
/// unbiased because candidates and probabilistic inversion both draw the technique from its
/// posterior given x2 (DESIGN §5).
///
/// The sample's random numbers must regenerate x2 at the *source* x1 (true after candidate
/// generation, delayed reconnection and [`crate::InvertingReconnection`], not after plain
/// [`crate::Reconnection`]): otherwise the shift is not invertible.
///
/// Unknown index (deferred policy): a hit is picked uniformly with a number from the receiver's
/// stream (purpose `PURPOSE_PICK`, see [`SssDomain`]); the result stores the picked rank. The
/// `1/hits` pick probability is not in `J` and the back shift replays the picked rank, not the
/// original hit, so such a shift is not invertible: paper 001's documented small bias.
#[derive(Clone, Copy, Debug, Default)]
pub struct DelayedReconnection;

impl DeclaresNumbers for DelayedReconnection {
    const NUMBERS: Numbers = Numbers::REPLAYED;
}

impl Shift<SssDomain<'_>> for DelayedReconnection {
    fn shift(
        &self,
        x: &SssSample,
        src: &SssDomain,
        dst: &SssDomain,
    ) -> Result<Shifted<SssSample>, Fail> {
        replay(x, src, dst, Checks::ALL)?.finish(dst, false, Wanted::Every)
    }

    /// Whether light reaches y2 at all ([`SssDomain::visible_if_lit`]) before the shadow ray.
    fn shift_supported(
        &self,
        x: &SssSample,
        src: &SssDomain,
        dst: &SssDomain,
    ) -> Result<Shifted<SssSample>, Fail> {
        replay(x, src, dst, Checks::ALL)?.finish(dst, false, Wanted::Supported)
    }
}

/// Which parts of delayed reconnection run: a set of the contract's `DELAYED_CHECK_*` bits, as
/// the GPU twin passes them; only the negative controls in [`crate::broken`] switch one off.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Checks(u32);

impl Checks {
    pub const ALL: Checks = Checks(DELAYED_CHECKS_ALL);

    /// These checks without the one of bit `check`.
    pub const fn without(self, check: u32) -> Checks {
        Checks(self.0 & !check)
    }

    fn has(self, check: u32) -> bool {
        self.0 & check != 0
    }
}

/// Which shifted samples the caller of a shift uses: every one ([`Shift::shift`], whose failure
/// kinds the diagnostics count), or only those with `p̂_dst > 0` ([`Shift::shift_supported`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Wanted {
    Every,
    Supported,
}

/// Delayed reconnection up to its last test, the y2–x3 shadow ray ([`Replayed::finish`]).
pub(crate) struct Replayed {
    pub shifted: Shifted<SssSample>,
    /// y2, which the hybrid tests.
    pub y2: EntryPoint,
    checks: Checks,
}

impl Replayed {
    /// The shifted sample, or `Rejected` if the caller's own criterion `rejected` holds,
    /// `Occluded` if y2–x3 is occluded (with [`Checks`]' visibility bit). For
    /// [`Wanted::Supported`] the criterion comes first, and a y2 that light does not reach
    /// ([`SssDomain::visible_if_lit`]: `p̂_dst = 0`) fails `OutOfSupport` without the shadow
    /// ray; for [`Wanted::Every`] the criterion comes after the ray, so a sample that fails both
    /// reads `Occluded`, as on the GPU.
    pub(crate) fn finish(
        self,
        dst: &SssDomain,
        rejected: bool,
        wanted: Wanted,
    ) -> Result<Shifted<SssSample>, Fail> {
        let y = &self.shifted.y;
        if wanted == Wanted::Supported && rejected {
            return Err(Fail::Rejected);
        }
        if self.checks.has(DELAYED_CHECK_VISIBILITY) {
            let visible = match wanted {
                Wanted::Every => dst.visible(y),
                Wanted::Supported => dst.visible_if_lit(y).ok_or(Fail::OutOfSupport)?,
            };
            if !visible {
                return Err(Fail::Occluded);
            }
        }
        if rejected {
            return Err(Fail::Rejected);
        }
        Ok(self.shifted)
    }
}

/// Delayed reconnection of `x` from `src` into `dst` before its visibility test.
pub(crate) fn replay(
    x: &SssSample,
    src: &SssDomain,
    dst: &SssDomain,
    checks: Checks,
) -> Result<Replayed, Fail> {
    // Replay traces on y1's object; a neighbour on another object is rejected both ways.
    if src.x1().object != dst.x1().object {
        return Err(Fail::Rejected);
    }
    let stored = x.bssrdf().ok_or(Fail::Degenerate)?;
    let x2 = src.entry_point(x).ok_or(Fail::Rejected)?;
    let probe = stored.probe();
    let mut hits = Vec::new();
    probe.trace(&dst.scene().geometry, dst.x1(), &mut hits);
    let u_pick = match stored.index {
        Some(_) => 0.0,
        None => dst.shift_stream(PURPOSE_PICK, src).next_f32(),
    };
    let (rank, hit) = pick_hit(&hits, stored.index, u_pick).ok_or(Fail::OutOfSupport)?;
    let y2 = EntryPoint::from_hit(&dst.scene().geometry, &hit);
    let p_disk_y = dst.p_disk(&y2);
    if !(p_disk_y > 0.0 && p_disk_y.is_finite()) {
        return Err(Fail::Degenerate);
    }
    let y = x.with_bssrdf(&BssrdfSample::new(&probe, Some(rank), &y2, p_disk_y));
    let jacobian = if checks.has(DELAYED_CHECK_JACOBIAN) {
        // [001 Eq. 11]
        let light = light_jacobian(
            &dst.scene().lights,
            y.light(),
            y.x3(),
            x2.position,
            y2.position,
        );
        stored.p_disk / p_disk_y * light
    } else {
        1.0
    };
    if !(jacobian > 0.0 && jacobian.is_finite()) {
        return Err(Fail::Degenerate);
    }
    Ok(Replayed {
        shifted: Shifted { y, jacobian },
        y2,
        checks,
    })
}

/// `|cos θ_y / cos θ_x| · ‖x3 − x2‖² / ‖x3 − y2‖²`, θ at x3 between the light's normal and the
/// direction to x2 (resp. y2): the change of x3's solid angle when x2 moves to y2 [001 Eq. 11].
/// 1 for delta lights (x3 is not a dimension of the path); 0 for an unknown light (the caller
/// fails with `Degenerate`).
pub(crate) fn light_jacobian(lights: &Lights, light: u32, x3: Vec3, x2: Vec3, y2: Vec3) -> f32 {
    if light as usize >= lights.len() {
        return 0.0;
    }
    let normal = match *lights.get(light) {
        Light::Quad { edge_u, edge_v, .. } => edge_u.cross(edge_v).normalize_or_zero(),
        Light::Triangle {
            vertices: [v0, v1, v2],
            ..
        } => (v1 - v0).cross(v2 - v0).normalize_or_zero(),
        Light::Sphere { center, .. } => (x3 - center).normalize_or_zero(),
        Light::Point { .. } | Light::Directional { .. } => return 1.0,
    };
    let (to_x, to_y) = (x2 - x3, y2 - x3);
    let (dx2, dy2) = (to_x.length_squared(), to_y.length_squared());
    // |cos θ_y| / ‖x3 − y2‖² over |cos θ_x| / ‖x3 − x2‖², with cos θ = n·d / ‖d‖.
    let num = normal.dot(to_y).abs() * dx2 * dx2.sqrt();
    let den = normal.dot(to_x).abs() * dy2 * dy2.sqrt();
    if den > 0.0 { num / den } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::vec3;
    use restir::rng::StreamKey;

    /// For planar area lights (sampled uniformly by area) the factor is the ratio of the light's
    /// solid-angle densities at x2 and y2, `sss`'s own area → solid-angle conversion
    /// (`Lights::pdf`); for a sphere it is reciprocal under swapping x2 and y2; for delta lights
    /// it is 1.
    #[test]
    fn light_factor_is_the_solid_angle_density_ratio() {
        let lights = Lights::new(
            vec![
                Light::Quad {
                    corner: vec3(-1.0, 3.0, -0.5),
                    edge_u: vec3(2.0, 0.0, 0.0),
                    edge_v: vec3(0.0, 0.2, 2.0),
                    radiance: Vec3::ONE,
                },
                Light::Triangle {
                    vertices: [
                        vec3(-1.0, 2.0, 1.0),
                        vec3(0.0, 2.2, -1.0),
                        vec3(1.0, 2.5, 1.0),
                    ],
                    radiance: Vec3::ONE,
                    two_sided: false,
                },
                Light::Sphere {
                    center: vec3(0.5, 3.0, 0.2),
                    radius: 0.3,
                    radiance: Vec3::ONE,
                },
                Light::Point {
                    position: vec3(0.0, 2.0, 0.0),
                    intensity: Vec3::ONE,
                },
                Light::Directional {
                    direction: vec3(0.0, -1.0, 0.0),
                    irradiance: Vec3::ONE,
                },
            ],
            5.0,
        )
        .unwrap();
        let mut rng = StreamKey::new(0, 0, 0, 0xDE1A).stream(1);
        let mut tested = 0;
        for light in 0..lights.len() as u32 {
            // u[0] in the middle of `light`'s selection interval.
            let below: f32 = (0..light).map(|j| lights.selection_pmf(j)).sum();
            let u_select = below + 0.5 * lights.selection_pmf(light);
            for _ in 0..100 {
                let mut point = || {
                    0.5 * vec3(
                        rng.next_f32() - 0.5,
                        rng.next_f32() - 0.5,
                        rng.next_f32() - 0.5,
                    )
                };
                let (x2, y2) = (point(), point());
                let s = lights
                    .sample(x2, [u_select, rng.next_f32(), rng.next_f32()])
                    .unwrap();
                assert_eq!(s.light, light);
                let factor = light_jacobian(&lights, light, s.point, x2, y2);
                match lights.get(light) {
                    Light::Point { .. } | Light::Directional { .. } => assert_eq!(factor, 1.0),
                    Light::Sphere { .. } => {
                        let back = light_jacobian(&lights, light, s.point, y2, x2);
                        assert!(
                            (factor * back - 1.0).abs() < 1e-5,
                            "sphere: {factor} · {back}"
                        );
                    }
                    Light::Quad { .. } | Light::Triangle { .. } => {
                        let expected =
                            lights.pdf(x2, light, s.point) / lights.pdf(y2, light, s.point);
                        assert!(
                            (factor / expected - 1.0).abs() < 1e-5,
                            "light {light}: {factor} vs {expected}"
                        );
                    }
                }
                tested += 1;
            }
        }
        assert_eq!(tested, 500);
    }
}
