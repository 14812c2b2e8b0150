//! Sampling x2 by BSSRDF IS, replay of stored random numbers, and the stored sample record.

use geometry::{Geometry, Hit, Ray};
use glam::Vec2;

use super::probe::{EntryPoint, ExitPoint, probe_ray_with, trace_probe};
use super::technique::{RadiusSampling, Technique, TechniqueSelection};

/// One BSSRDF IS draw before tracing: the technique and its two random numbers. Replaying it at
/// another x1 is delayed reconnection's random replay [001 §3.2.2].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Probe {
    pub technique: Technique,
    pub u_radius: f32,
    pub u_angle: f32,
}

impl Probe {
    /// The technique from `u_technique` (cumulative over [`Technique::ALL`]), then the random
    /// numbers of the radius and the angle as given.
    pub fn sample(
        selection: &TechniqueSelection,
        u_technique: f32,
        u_radius: f32,
        u_angle: f32,
    ) -> Probe {
        Probe {
            technique: selection.sample(u_technique),
            u_radius,
            u_angle,
        }
    }

    /// The chord to trace; `None` when the sampled radius reaches `r_max,c` (no hit possible).
    pub fn ray(&self, x1: &ExitPoint) -> Option<Ray> {
        self.ray_with(x1, RadiusSampling::Exact)
    }

    /// [`Probe::ray`] with the radius drawn by `radius`.
    pub fn ray_with(&self, x1: &ExitPoint, radius: RadiusSampling) -> Option<Ray> {
        probe_ray_with(x1, self.technique, radius, self.u_radius, self.u_angle)
    }

    /// Fills `hits` with the chord's hits on x1's object, sorted by `t` (empty for an empty chord).
    pub fn trace(&self, geometry: &Geometry, x1: &ExitPoint, hits: &mut Vec<Hit>) {
        self.trace_with(geometry, x1, RadiusSampling::Exact, hits)
    }

    /// [`Probe::trace`] with the radius drawn by `radius`.
    pub fn trace_with(
        &self,
        geometry: &Geometry,
        x1: &ExitPoint,
        radius: RadiusSampling,
        hits: &mut Vec<Hit>,
    ) {
        match self.ray_with(x1, radius) {
            Some(ray) => trace_probe(geometry, x1, &ray, hits),
            None => hits.clear(),
        }
    }
}

/// The hit a probe selects: rank `index`, or, when the index is unknown, one picked uniformly with
/// `u_pick` (probability `1/hits.len()`). Returns the rank and the hit; `None` if there is no such
/// hit.
pub fn pick_hit(hits: &[Hit], index: Option<u32>, u_pick: f32) -> Option<(u32, Hit)> {
    let rank = match index {
        Some(i) => i as usize,
        None if hits.is_empty() => return None,
        None => ((u_pick * hits.len() as f32) as usize).min(hits.len() - 1),
    };
    hits.get(rank).map(|h| (rank as u32, *h))
}

/// The part of a reservoir sample that BSSRDF IS owns [001 Alg. 3]: x2 and the random numbers
/// that regenerate it from the x1 they belong to. The light vertex x3 is stored by the caller.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BssrdfSample {
    pub object: u32,
    pub prim: u32,
    pub bary: Vec2,
    pub technique: Technique,
    pub u_radius: f32,
    pub u_angle: f32,
    /// Rank of x2 among the probe's hits sorted by `t`; `None` = unknown (deferred inversion:
    /// replay then picks a hit uniformly, paper 001's small bias).
    pub index: Option<u32>,
    /// `p_disk(x2 | x1)` for the x1 whose random numbers are stored (the cached Jacobian part
    /// [001 Eq. 11]); update it whenever the random numbers change.
    pub p_disk: f32,
}

impl BssrdfSample {
    pub fn new(probe: &Probe, index: Option<u32>, x2: &EntryPoint, p_disk: f32) -> BssrdfSample {
        BssrdfSample {
            object: x2.object,
            prim: x2.prim,
            bary: x2.bary,
            technique: probe.technique,
            u_radius: probe.u_radius,
            u_angle: probe.u_angle,
            index,
            p_disk,
        }
    }

    pub fn probe(&self) -> Probe {
        Probe {
            technique: self.technique,
            u_radius: self.u_radius,
            u_angle: self.u_angle,
        }
    }
}
