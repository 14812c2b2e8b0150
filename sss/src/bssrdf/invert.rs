//! Probabilistic inversion of BSSRDF IS [001 Alg. 4]: random numbers that regenerate a given x2
//! from a new x1, with the technique drawn from its posterior so the UCW needs no change.

use std::f32::consts::TAU;

use geometry::{Geometry, Hit};
use glam::Vec3;

use super::pdf::technique_terms;
use super::probe::{EntryPoint, ExitPoint, trace_probe};
use super::sample::{BssrdfSample, Probe};
use super::technique::{Technique, TechniqueSelection};

pub use crate::contract::bssrdf::InvertFail;

/// The random numbers with which technique `t` at x1 produces a disk point under `x2`
/// [001 Alg. 4, lines 2–9]: `u_radius = CDF_{d_c}(r_a)`, `u_angle = atan2(l_y, l_x) / 2π` wrapped
/// to [0, 1). Inverse of [`super::probe::probe_ray`] up to rounding.
pub fn invert_technique(x1: &ExitPoint, t: Technique, x2: Vec3) -> Probe {
    let disk = x1.disk_coordinates(t.axis, x2);
    let u_radius = x1.profiles[t.channel].cdf(disk.length());
    let u = disk.y.atan2(disk.x) / TAU;
    let u = if u < 0.0 { u + 1.0 } else { u };
    let u_angle = if u < 1.0 { u } else { 0.0 };
    Probe {
        technique: t,
        u_radius,
        u_angle,
    }
}

/// Draws the technique with probability `P(a)P(c) p_{d_c}(r_a)|n2·axis_a| 1[…] / p_disk(x2 | x1)`
/// using `gamma ∈ [0, 1)` [001 Alg. 4, line 1] and inverts it; also returns `p_disk(x2 | x1)`.
/// Traces no ray (the deferred index policy stops here).
pub fn invert_random_numbers(
    x1: &ExitPoint,
    selection: &TechniqueSelection,
    x2: &EntryPoint,
    gamma: f32,
) -> Result<(Probe, f32), InvertFail> {
    let terms = technique_terms(x1, selection, x2.position, x2.geometric_normal);
    let p_disk: f32 = terms.iter().sum();
    if !(p_disk > 0.0 && p_disk.is_finite()) {
        return Err(InvertFail::OutOfSupport);
    }
    let threshold = gamma * p_disk;
    let mut cumulative = 0.0;
    let mut chosen = None;
    for (t, &term) in Technique::ALL.iter().zip(&terms) {
        if term <= 0.0 {
            continue;
        }
        cumulative += term;
        chosen = Some(*t);
        if threshold < cumulative {
            break;
        }
    }
    let t = chosen.ok_or(InvertFail::OutOfSupport)?;
    Ok((invert_technique(x1, t, x2.position), p_disk))
}

/// Exact index policy: re-traces the chord of `probe` at x1 and returns the rank of the hit on
/// x2's triangle whose `t` matches x2 (within `1e-3 · r_max,c`); `None` if there is none.
pub fn find_index(
    geometry: &Geometry,
    x1: &ExitPoint,
    probe: &Probe,
    x2: &EntryPoint,
    hits: &mut Vec<Hit>,
) -> Option<u32> {
    let ray = probe.ray(x1)?;
    trace_probe(geometry, x1, &ray, hits);
    let t_x2 = (x2.position - Vec3::from(ray.origin)).dot(Vec3::from(ray.dir));
    let tolerance = 1e-3 * x1.r_max[probe.technique.channel];
    hits.iter()
        .position(|h| h.prim == x2.prim && (h.t - t_x2).abs() <= tolerance)
        .map(|i| i as u32)
}

/// Probabilistic inversion with the exact index policy: the new sample record for x2 relative to
/// x1, with fresh random numbers, the re-found intersection index and the new cached `p_disk`.
pub fn invert(
    geometry: &Geometry,
    x1: &ExitPoint,
    selection: &TechniqueSelection,
    x2: &EntryPoint,
    gamma: f32,
    hits: &mut Vec<Hit>,
) -> Result<BssrdfSample, InvertFail> {
    let (probe, p_disk) = invert_random_numbers(x1, selection, x2, gamma)?;
    let index = find_index(geometry, x1, &probe, x2, hits).ok_or(InvertFail::IndexNotFound)?;
    Ok(BssrdfSample::new(&probe, Some(index), x2, p_disk))
}
