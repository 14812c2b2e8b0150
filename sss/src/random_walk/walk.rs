//! The walk kernel: free flights, collisions, phase sampling and boundary events inside a
//! homogeneous medium, until the walk leaves through the boundary.
//!
//! **Chromatic extinction (hero channel, path-level spectral MIS).** One channel `h` is drawn
//! uniformly per walk and every free flight is sampled with `σt,h` [000 slide 54]; the path is
//! then weighted per channel `c` by `f_c(x̄) / ((1/3) Σ_k p_k(x̄))`, the one-sample MIS
//! (balance heuristic) over the three channel techniques [000 last slide, "hero tracking"]:
//! a collision at distance `t` has `f_c = σs,c e^{−σt,c t}` and `p_c = σt,c e^{−σt,c t}`, reaching
//! the boundary at distance `d` has `f_c = p_c = e^{−σt,c d}` [000 slide 66]. The kernel keeps
//! `β = f / p_h` and `r_c = p_c / p_h`, rescaled after every step so that `mean(r) = 1`; the
//! path weight is then `β` itself and stays bounded by `3 · max_c α_c^n`. For a gray medium
//! `r = 1` and this is plain analogue-distance tracking.
//!
//! **Termination.** The walk ends when it leaves the medium, by Russian roulette (survival
//! probability `q = min(1, max_c β_c)`, survivors divided by `q`: unbiased), when its weight is
//! zero, or at [`WalkSettings::max_bounces`] segments, which is reported as
//! [`WalkEnd::Truncated`] so callers can count the truncation.

use glam::Vec3;
use restir::rng::Stream;

use super::boundary::Boundary;
use super::interface::{fresnel_dielectric, reflect, refract};
use super::medium::{Interface, Medium};
use super::phase::PhaseFunction;

pub use crate::contract::random_walk::{CrossingKind, DEFAULT_MAX_BOUNCES, WalkEndKind};

/// Knobs of the walk kernel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WalkSettings {
    /// Maximum number of free-flight segments (collisions plus internal reflections plus the exit).
    pub max_bounces: u32,
    /// Throughput-based Russian roulette after every collision.
    pub roulette: bool,
}

impl Default for WalkSettings {
    fn default() -> Self {
        WalkSettings {
            max_bounces: DEFAULT_MAX_BOUNCES,
            roulette: true,
        }
    }
}

/// How the walk leaves the medium.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ExitDirection {
    /// A single outgoing direction (index-matched or refracted through a smooth dielectric).
    Specular(Vec3),
    /// Lambertian transmission: any outgoing direction, with `f = 1/π` (the caller integrates).
    Diffuse,
}

/// The exit event of a walk.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Exit {
    pub point: Vec3,
    /// Unit outward normal at `point`.
    pub normal: Vec3,
    pub direction: ExitDirection,
    /// The path weight per channel, `f(x̄) / mean_c p_c(x̄)` (see the module doc), times the
    /// Russian-roulette factors.
    pub weight: Vec3,
    /// Volume collisions before the exit (0 = unscattered).
    pub scatter_count: u32,
    /// Fresnel (including total) internal reflections before the exit.
    pub reflection_count: u32,
}

/// How a walk ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum WalkEnd {
    Exited(Exit),
    /// Killed by Russian roulette or with zero weight (contributes nothing, unbiasedly).
    Terminated,
    /// Cut off at `max_bounces` segments: a truncation bias the caller must count.
    Truncated,
}

impl WalkEnd {
    /// The end without its exit: the code a GPU walk returns.
    pub fn kind(&self) -> WalkEndKind {
        match self {
            WalkEnd::Exited(_) => WalkEndKind::Exited,
            WalkEnd::Terminated => WalkEndKind::Terminated,
            WalkEnd::Truncated => WalkEndKind::Truncated,
        }
    }
}

/// Where a path inside the medium meets the boundary.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Crossing {
    /// It leaves the medium.
    Leaves(ExitDirection),
    /// It is reflected back inside along this direction (Fresnel or total internal reflection).
    Reflected(Vec3),
}

impl Crossing {
    /// The crossing without its direction: the code a GPU crossing returns.
    pub fn kind(&self) -> CrossingKind {
        match self {
            Crossing::Leaves(ExitDirection::Specular(_)) => CrossingKind::LeavesSpecular,
            Crossing::Leaves(ExitDirection::Diffuse) => CrossingKind::LeavesDiffuse,
            Crossing::Reflected(_) => CrossingKind::Reflected,
        }
    }
}

/// The boundary event of a path travelling along `dir` that meets the boundary where its unit
/// outward normal is `normal`: index-matched and diffuse interfaces always let it leave; a
/// dielectric (inside → outside: relative index `1/η`) reflects it with the Fresnel probability,
/// drawing one number from `stream` only when refraction is possible (total internal reflection
/// draws none). The probability choice leaves the weight unchanged (`F/F`, `(1 − F)/(1 − F)`).
pub fn cross(interface: Interface, dir: Vec3, normal: Vec3, stream: &mut Stream) -> Crossing {
    match interface {
        Interface::IndexMatched => Crossing::Leaves(ExitDirection::Specular(dir)),
        Interface::Diffuse => Crossing::Leaves(ExitDirection::Diffuse),
        Interface::Dielectric { eta } => {
            let fresnel = fresnel_dielectric(dir.dot(normal), 1.0 / eta);
            match refract(dir, -normal, 1.0 / eta) {
                Some(out) if stream.next_f32() >= fresnel => {
                    Crossing::Leaves(ExitDirection::Specular(out))
                }
                _ => Crossing::Reflected(reflect(dir, normal)),
            }
        }
    }
}

/// Survival under throughput-based Russian roulette: with `q = min(1, max_c β_c)`, the walk
/// survives iff `u < q`, and survivors carry `β / q` (so `E[β'] = β`). `None` = killed.
pub fn roulette(beta: Vec3, u: f32) -> Option<Vec3> {
    let q = beta.max_element().min(1.0);
    if q.is_nan() || u >= q {
        None
    } else {
        Some(beta / q)
    }
}

/// `e^{−(σt,c − σt,h) t}` per channel: the transmittance ratio `T_c(t) / T_h(t)`, without the
/// 0/0 of dividing two underflowed exponentials.
fn transmittance_ratio(sigma_t: Vec3, sigma_hero: f32, t: f32) -> Vec3 {
    (-(sigma_t - Vec3::splat(sigma_hero)) * t).exp()
}

/// Rescales `(β, r)` by `1 / mean(r)`, which leaves the path weight `β / mean(r)` unchanged.
fn rescale(beta: Vec3, r: Vec3) -> (Vec3, Vec3) {
    let mean = (r.x + r.y + r.z) / 3.0;
    (beta / mean, r / mean)
}

/// Walks from `start` (on or inside the boundary) along the unit direction `dir` (into the
/// medium) until the walk exits, is terminated or is truncated. The starting weight is 1; the
/// caller applies the entry weight.
pub fn walk<B: Boundary + ?Sized, P: PhaseFunction>(
    boundary: &B,
    medium: &Medium<P>,
    start: Vec3,
    dir: Vec3,
    settings: &WalkSettings,
    stream: &mut Stream,
) -> WalkEnd {
    let sigma_t = medium.sigma_t();
    let sigma_s = medium.sigma_s();
    let hero = ((3.0 * stream.next_f32()) as usize).min(2);
    let sigma_hero = sigma_t[hero];
    let (mut beta, mut r) = (Vec3::ONE, Vec3::ONE);
    let (mut pos, mut dir) = (start, dir);
    let (mut scatter_count, mut reflection_count) = (0, 0);
    for _ in 0..settings.max_bounces {
        // Free flight with pdf σt,h e^{−σt,h t} [000 slide 54].
        let t_collision = -(1.0 - stream.next_f32()).ln() / sigma_hero;
        if let Some(hit) = boundary.intersect(pos, dir, t_collision) {
            // Boundary first: f_c = p_c = e^{−σt,c d} [000 slide 66].
            let ratio = transmittance_ratio(sigma_t, sigma_hero, hit.t);
            (beta, r) = rescale(beta * ratio, r * ratio);
            pos += hit.t * dir;
            let exit = |direction| {
                let (weight, normal) = (beta, hit.normal);
                WalkEnd::Exited(Exit {
                    point: pos,
                    normal,
                    direction,
                    weight,
                    scatter_count,
                    reflection_count,
                })
            };
            match cross(medium.interface(), dir, hit.normal, stream) {
                Crossing::Leaves(direction) => return exit(direction),
                Crossing::Reflected(reflected) => {
                    dir = reflected;
                    reflection_count += 1;
                }
            }
        } else {
            // Collision: f_c = σs,c e^{−σt,c t}, p_c = σt,c e^{−σt,c t} [000 slide 66].
            pos += t_collision * dir;
            let ratio = transmittance_ratio(sigma_t, sigma_hero, t_collision) / sigma_hero;
            (beta, r) = rescale(beta * sigma_s * ratio, r * sigma_t * ratio);
            scatter_count += 1;
            let scattered = medium
                .phase()
                .sample(dir, [stream.next_f32(), stream.next_f32()]);
            if scattered.pdf.is_nan() || scattered.pdf <= 0.0 {
                return WalkEnd::Terminated;
            }
            beta *= scattered.value / scattered.pdf;
            dir = scattered.dir;
            let survivor = if settings.roulette {
                roulette(beta, stream.next_f32())
            } else {
                (beta.max_element() > 0.0).then_some(beta)
            };
            match survivor {
                Some(b) => beta = b,
                None => return WalkEnd::Terminated,
            }
        }
    }
    WalkEnd::Truncated
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::*;
    use crate::random_walk::boundary::Sphere;
    use restir::rng::StreamKey;

    /// Gray albedo-1 sphere (σt = 10, radius 1) entered at its pole, roulette off: only the exit
    /// or the cap can end a walk. With a cap of 3 segments most walks are reported truncated,
    /// none vanish, and walks that exit in time used at most 2 collisions.
    #[test]
    fn the_bounce_cap_is_reported() {
        let path = Path::new("<test>");
        let medium = Medium::new(
            Vec3::splat(10.0),
            Vec3::ZERO,
            0.0,
            Interface::IndexMatched,
            path,
            "m",
        )
        .unwrap();
        let sphere = Sphere {
            center: Vec3::ZERO,
            radius: 1.0,
        };
        let settings = WalkSettings {
            max_bounces: 3,
            roulette: false,
        };
        let (mut exited, mut truncated) = (0, 0);
        for i in 0..1_000 {
            let mut stream = StreamKey::new(i, 0, 0, 0x7A).stream(1);
            let end = walk(&sphere, &medium, Vec3::Z, -Vec3::Z, &settings, &mut stream);
            assert_ne!(end.kind(), WalkEndKind::Terminated);
            match end {
                WalkEnd::Exited(exit) => {
                    exited += 1;
                    assert!(exit.scatter_count <= 2, "{exit:?}");
                }
                WalkEnd::Truncated => truncated += 1,
                WalkEnd::Terminated => panic!("walk {i} terminated with weight 1 and no roulette"),
            }
        }
        assert!(
            truncated > 500 && exited > 0,
            "{exited} exited, {truncated} truncated of 1 000"
        );
    }

    /// The codes a GPU crossing returns: index-matched leaves specularly, diffuse diffusely, and
    /// a dielectric (η = 1.5) reflects a path at sin θ = 0.99, beyond the critical 1/1.5.
    #[test]
    fn crossings_have_their_kinds() {
        let mut stream = StreamKey::new(0, 0, 0, 0x7A).stream(1);
        let dir = Vec3::new(0.0, 0.6, 0.8);
        let kind =
            |interface, dir, stream: &mut Stream| cross(interface, dir, Vec3::Z, stream).kind();
        assert_eq!(
            kind(Interface::IndexMatched, dir, &mut stream),
            CrossingKind::LeavesSpecular
        );
        assert_eq!(
            kind(Interface::Diffuse, dir, &mut stream),
            CrossingKind::LeavesDiffuse
        );
        let grazing = Vec3::new(0.99, 0.0, (1.0f32 - 0.99 * 0.99).sqrt());
        assert_eq!(
            kind(Interface::Dielectric { eta: 1.5 }, grazing, &mut stream),
            CrossingKind::Reflected
        );
    }

    #[test]
    fn roulette_keeps_the_expectation() {
        let beta = Vec3::new(0.2, 0.5, 0.1);
        // q = 0.5: survivors below u = 0.5 carry β/q, the expectation q·β/q = β.
        assert_eq!(roulette(beta, 0.49), Some(beta / 0.5));
        assert_eq!(roulette(beta, 0.5), None);
        assert_eq!(
            roulette(Vec3::new(2.0, 0.1, 0.1), 0.999),
            Some(Vec3::new(2.0, 0.1, 0.1))
        );
        assert_eq!(roulette(Vec3::ZERO, 0.0), None);
    }

    #[test]
    fn rescaling_keeps_the_path_weight() {
        let (beta, r) = (Vec3::new(0.3, 2.0, 0.7), Vec3::new(0.5, 4.0, 1.5));
        let (b2, r2) = rescale(beta, r);
        let w = beta / ((r.x + r.y + r.z) / 3.0);
        assert!((b2 - w).abs().max_element() < 1e-6);
        assert!(((r2.x + r2.y + r2.z) / 3.0 - 1.0).abs() < 1e-6);
    }
}
