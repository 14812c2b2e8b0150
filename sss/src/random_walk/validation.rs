//! Validation of the walk kernel against analytic results and conservation laws (module doc of
//! [`super`] states the analytic check). Replicas (independent batches of walks, each with its
//! own streams) are the statistical unit.

use geometry::Geometry;
use geometry::shapes::icosphere;
use glam::Vec3;
use restir::rng::{Stream, StreamKey};
use restir::stats::{Equivalence, Summary, Verdict, equivalence};

use crate::material::fresnel::fresnel_by_angles;

use super::boundary::{Boundary, HalfSpace, MeshBoundary, Sphere};
use super::interface::{fresnel_dielectric, refract};
use super::medium::{Interface, Medium};
use super::phase::{HenyeyGreenstein, ISOTROPIC, PhaseFunction, PhaseSample};
use super::walk::{WalkEnd, WalkSettings, walk};
use crate::sampling::sample_cosine_hemisphere;

/// Gauss–Legendre nodes and weights on [0, 1] (Newton iteration on `P_n`).
pub(crate) fn gauss_legendre_01(n: usize) -> Vec<(f64, f64)> {
    (1..=n)
        .map(|i| {
            let mut x = (std::f64::consts::PI * (i as f64 - 0.25) / (n as f64 + 0.5)).cos();
            let mut derivative = 1.0;
            for _ in 0..100 {
                let (mut p0, mut p1) = (1.0, x);
                for k in 2..=n {
                    (p0, p1) = (
                        p1,
                        ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64,
                    );
                }
                derivative = n as f64 * (x * p1 - p0) / (x * x - 1.0);
                let step = p1 / derivative;
                x -= step;
                if step.abs() < 1e-15 {
                    break;
                }
            }
            let weight = 2.0 / ((1.0 - x * x) * derivative * derivative);
            (0.5 * (1.0 + x), 0.5 * weight)
        })
        .collect()
}

/// The right-hand side `√(1 − α) + (α/2) Σ_j w_j μ_j H_j / (μ + μ_j)` of the H equation.
fn h_inverse(alpha: f64, nodes: &[(f64, f64)], h: &[f64], mu: f64) -> f64 {
    let integral: f64 = nodes
        .iter()
        .zip(h)
        .map(|(&(m, w), &hm)| w * m * hm / (mu + m))
        .sum();
    (1.0 - alpha).sqrt() + 0.5 * alpha * integral
}

/// Chandrasekhar's H-function for isotropic scattering with albedo `alpha`, by fixed-point
/// iteration of `1/H(μ) = √(1 − α) + (α/2) ∫₀¹ μ′H(μ′)/(μ + μ′) dμ′` on 64 Gauss–Legendre nodes.
fn chandrasekhar_h(alpha: f64) -> impl Fn(f64) -> f64 {
    let nodes = gauss_legendre_01(64);
    let mut h = vec![1.0; nodes.len()];
    for _ in 0..10_000 {
        let next: Vec<f64> = nodes
            .iter()
            .map(|&(mu, _)| 1.0 / h_inverse(alpha, &nodes, &h, mu))
            .collect();
        let change = next
            .iter()
            .zip(&h)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        h = next;
        if change < 1e-14 {
            break;
        }
    }
    move |mu| 1.0 / h_inverse(alpha, &nodes, &h, mu)
}

/// Diffuse reflectance `R(μ0) = 1 − H(μ0)√(1 − α)` (index-matched, semi-infinite, isotropic).
pub(crate) fn reflectance_exact(alpha: f64, mu0: f64) -> f64 {
    1.0 - chandrasekhar_h(alpha)(mu0) * (1.0 - alpha).sqrt()
}

/// Single-scattering part `R1(μ0) = (α/2)(1 − μ0 ln(1 + 1/μ0))`.
pub(crate) fn single_scattering_exact(alpha: f64, mu0: f64) -> f64 {
    0.5 * alpha * (1.0 - mu0 * (1.0 + 1.0 / mu0).ln())
}

/// Per replica and channel: mean exit weight of all walks (`R`) and of those that left after
/// exactly one collision (`R1`), for a collimated beam at incidence cosine `mu0` on the
/// half-space `z < 0`.
fn reflectance_replicas<P: PhaseFunction>(
    medium: &Medium<P>,
    mu0: f32,
    replicas: u32,
    walks: u32,
    seed: u64,
) -> (Vec<[f64; 3]>, Vec<[f64; 3]>, u32) {
    let boundary = HalfSpace {
        point: Vec3::ZERO,
        normal: Vec3::Z,
    };
    let dir = Vec3::new((1.0 - mu0 * mu0).sqrt(), 0.0, -mu0);
    let settings = WalkSettings::default();
    let (mut r_all, mut r_single, mut truncated) = (Vec::new(), Vec::new(), 0);
    for replica in 0..replicas {
        let (mut sum, mut sum_single) = ([0.0f64; 3], [0.0f64; 3]);
        for i in 0..walks {
            let mut stream = StreamKey::new(i, replica, 0xC4A2, 1).stream(seed);
            match walk(&boundary, medium, Vec3::ZERO, dir, &settings, &mut stream) {
                WalkEnd::Exited(exit) => {
                    for c in 0..3 {
                        sum[c] += exit.weight[c] as f64;
                        if exit.scatter_count == 1 {
                            sum_single[c] += exit.weight[c] as f64;
                        }
                    }
                }
                WalkEnd::Truncated => truncated += 1,
                WalkEnd::Terminated => {}
            }
        }
        r_all.push(sum.map(|s| s / walks as f64));
        r_single.push(sum_single.map(|s| s / walks as f64));
    }
    (r_all, r_single, truncated)
}

fn channel_summary(replicas: &[[f64; 3]], c: usize) -> Summary {
    Summary::from_samples(&replicas.iter().map(|r| r[c]).collect::<Vec<_>>())
}

/// Albedos (0.3, 0.8, 0.99) with extinctions (1, 2, 4): one chromatic medium checks three
/// albedos and the hero-channel weights at once (R depends on α only: no length scale).
fn chromatic_medium() -> Medium {
    let sigma_t = Vec3::new(1.0, 2.0, 4.0);
    let albedo = Vec3::new(0.3, 0.8, 0.99);
    let sigma_s = albedo * sigma_t;
    let path = std::path::Path::new("<test>");
    Medium::new(
        sigma_s,
        sigma_t - sigma_s,
        0.0,
        Interface::IndexMatched,
        path,
        "medium",
    )
    .unwrap()
}

/// A deliberately wrong phase function: draws HG(g = 0.5) directions but reports the isotropic
/// value and pdf, i.e. its sampling pdf is wrong (the negative control of the analytic check).
struct WrongPdfPhase(HenyeyGreenstein);

impl PhaseFunction for WrongPdfPhase {
    fn eval(&self, _: Vec3, _: Vec3) -> f32 {
        ISOTROPIC
    }
    fn sample(&self, dir_in: Vec3, u: [f32; 2]) -> PhaseSample {
        PhaseSample {
            value: ISOTROPIC,
            pdf: ISOTROPIC,
            ..self.0.sample(dir_in, u)
        }
    }
    fn pdf(&self, _: Vec3, _: Vec3) -> f32 {
        ISOTROPIC
    }
}

// Analytic check: K = 24 replicas × 12 000 walks per incidence, μ0 ∈ {1, 0.5}; 12 comparisons
// (3 albedos × {R, R1} × 2 μ0), each an equivalence test with δ = 3% relative at confidence
// 1 − 0.01/12 (Bonferroni, family α = 0.01); every one must be `Unbiased`.
const REPLICAS: u32 = 24;
const WALKS: u32 = 12_000;
const DELTA: f64 = 0.03;
const CONFIDENCE: f64 = 1.0 - 0.01 / 12.0;

fn check(what: &str, estimate: &Summary, exact: f64) -> Equivalence {
    let e = equivalence(estimate, &Summary::exact(exact), DELTA, CONFIDENCE);
    eprintln!(
        "{what}: walk {:.5} ± {:.5}, exact {exact:.5}, rel. bias {:+.4} CI [{:+.4}, {:+.4}], p {:.3}, {:?}",
        estimate.mean,
        estimate.std_err,
        e.relative_bias,
        e.ci_low,
        e.ci_high,
        e.p_zero_bias,
        e.verdict
    );
    e
}

#[test]
fn chandrasekhar_reference_is_self_consistent() {
    for alpha in [0.3, 0.8, 0.99] {
        let h = chandrasekhar_h(alpha);
        // The classical form H(μ) = 1 + (α/2) μ H(μ) ∫₀¹ H(μ′)/(μ + μ′) dμ′ holds for the solution
        // of the form we iterate, and so does the zeroth moment (α/2) ∫₀¹ H = 1 − √(1 − α).
        let nodes = gauss_legendre_01(64);
        for mu in [0.5, 1.0] {
            let integral: f64 = nodes.iter().map(|&(m, w)| w * h(m) / (mu + m)).sum();
            let classical = 1.0 + 0.5 * alpha * mu * h(mu) * integral;
            assert!(
                (classical - h(mu)).abs() < 1e-6,
                "α={alpha} μ={mu}: {classical} vs {}",
                h(mu)
            );
        }
        let moment: f64 = 0.5 * alpha * nodes.iter().map(|&(m, w)| w * h(m)).sum::<f64>();
        assert!(
            (moment - (1.0 - (1.0 - alpha).sqrt())).abs() < 1e-6,
            "α={alpha}: moment {moment}"
        );
    }
    // Conservative limit R = 1, and R → R1 as α → 0 (single scattering dominates).
    assert!((reflectance_exact(1.0, 0.7) - 1.0).abs() < 1e-12);
    for mu0 in [0.5, 1.0] {
        let (r, r1) = (
            reflectance_exact(1e-3, mu0),
            single_scattering_exact(1e-3, mu0),
        );
        assert!((r / r1 - 1.0).abs() < 1e-3, "μ0={mu0}: R {r} vs R1 {r1}");
    }
}

/// The walk's diffuse reflectance and single-scattering reflectance against Chandrasekhar.
/// Negative control: the same test on a walk whose phase sampling pdf is wrong must be `Biased`.
#[test]
fn walk_matches_chandrasekhar_reflectance() {
    let medium = chromatic_medium();
    let albedo = medium.albedo();
    for (k, mu0) in [1.0f32, 0.5].into_iter().enumerate() {
        let (r_all, r_single, truncated) =
            reflectance_replicas(&medium, mu0, REPLICAS, WALKS, 7 + k as u64);
        assert_eq!(
            truncated,
            0,
            "walks hit the cap of {}",
            WalkSettings::default().max_bounces
        );
        for c in 0..3 {
            let alpha = albedo[c] as f64;
            for (what, replicas, exact) in [
                ("R", &r_all, reflectance_exact(alpha, mu0 as f64)),
                ("R1", &r_single, single_scattering_exact(alpha, mu0 as f64)),
            ] {
                let label = format!("{what}(μ0={mu0}) α={alpha:.2}");
                let e = check(&label, &channel_summary(replicas, c), exact);
                assert_eq!(
                    e.verdict,
                    Verdict::Equivalent,
                    "{label}: {e:?} (δ = {DELTA}, confidence {CONFIDENCE}, K = {REPLICAS} × {WALKS} walks)"
                );
            }
        }
    }
    let wrong = medium.with_phase(WrongPdfPhase(HenyeyGreenstein::new(0.5).unwrap()));
    let (r_all, _, _) = reflectance_replicas(&wrong, 1.0, REPLICAS, WALKS, 7);
    for c in 0..3 {
        let alpha = albedo[c] as f64;
        let label = format!("negative control R(μ0=1) α={alpha:.2}");
        let e = check(
            &label,
            &channel_summary(&r_all, c),
            reflectance_exact(alpha, 1.0),
        );
        assert_eq!(
            e.verdict,
            Verdict::Biased,
            "{label} not detected: {e:?} (δ = {DELTA}, K = {REPLICAS} × {WALKS} walks)"
        );
    }
}

/// Exit statistics of walks entering a closed object at `x1` (outward normal `n1`) with
/// cosine-distributed inward directions (entry weight 1).
struct EnergyTally {
    /// Per replica and channel: mean exiting weight per entering unit weight.
    replicas: Vec<[f64; 3]>,
    /// Walks that did not exit, or whose exit weight differs from 1 by more than 1e-5 in a channel.
    not_unit: u32,
    truncated: u32,
    reflected_walks: u32,
}

fn energy_tally<B: Boundary + ?Sized>(
    boundary: &B,
    medium: &Medium,
    x1: Vec3,
    n1: Vec3,
    replicas: u32,
    walks: u32,
    seed: u64,
) -> EnergyTally {
    let settings = WalkSettings::default();
    let mut tally = EnergyTally {
        replicas: Vec::new(),
        not_unit: 0,
        truncated: 0,
        reflected_walks: 0,
    };
    for replica in 0..replicas {
        let mut sum = [0.0f64; 3];
        for i in 0..walks {
            let mut stream = StreamKey::new(i, replica, 0xE4E2, 2).stream(seed);
            let dir = sample_cosine_hemisphere(-n1, [stream.next_f32(), stream.next_f32()]);
            let end = walk(boundary, medium, x1, dir, &settings, &mut stream);
            let weight = match end {
                WalkEnd::Exited(exit) => {
                    tally.reflected_walks += (exit.reflection_count > 0) as u32;
                    exit.weight
                }
                WalkEnd::Truncated => {
                    tally.truncated += 1;
                    Vec3::ZERO
                }
                WalkEnd::Terminated => Vec3::ZERO,
            };
            tally.not_unit += ((weight - Vec3::ONE).abs().max_element() > 1e-5) as u32;
            for c in 0..3 {
                sum[c] += weight[c] as f64;
            }
        }
        tally.replicas.push(sum.map(|s| s / walks as f64));
    }
    tally
}

fn medium(sigma_s: Vec3, sigma_a: Vec3, g: f32, interface: Interface) -> Medium {
    Medium::new(
        sigma_s,
        sigma_a,
        g,
        interface,
        std::path::Path::new("<test>"),
        "medium",
    )
    .unwrap()
}

/// Verdicts of "mean exit weight = 1" per channel: equivalence, δ = 1% relative, confidence
/// 1 − 0.01/3 per channel (Bonferroni over 3 channels).
fn energy_verdicts(tally: &EnergyTally, what: &str) -> [Verdict; 3] {
    [0, 1, 2].map(|c| {
        let e = equivalence(
            &channel_summary(&tally.replicas, c),
            &Summary::exact(1.0),
            0.01,
            1.0 - 0.01 / 3.0,
        );
        eprintln!(
            "{what} channel {c}: exit/entry {:.5}, CI [{:+.4}, {:+.4}], {:?}",
            1.0 + e.relative_bias,
            e.ci_low,
            e.ci_high,
            e.verdict
        );
        e.verdict
    })
}

/// Runs `check(name, boundary, x1, n1)` on the two closed objects of the energy tests: the unit
/// sphere (analytic) and an icosphere mesh (BVH), each with an entry point on its surface.
fn for_each_closed_boundary(mut check: impl FnMut(&str, &dyn Boundary, Vec3, Vec3)) {
    let sphere = Sphere {
        center: Vec3::ZERO,
        radius: 1.0,
    };
    check("sphere", &sphere, Vec3::Z, Vec3::Z);
    let geometry = Geometry::new(&[icosphere(1.0, 2)]);
    let mesh = MeshBoundary {
        geometry: &geometry,
        object: 0,
        inward_winding: false,
    };
    let [v0, v1, v2] = geometry.vertices(0);
    let centroid = (v0 + v1 + v2) / 3.0;
    check(
        "icosphere mesh",
        &mesh,
        centroid,
        geometry.geometric_normal(0),
    );
}

/// Energy conservation at albedo 1 with an index-matched boundary, sphere (analytic) and closed
/// mesh (BVH): gray medium, 8 × 2 500 walks, every walk exits with weight 1 (to 1e-5) and none
/// reaches the cap (`DEFAULT_MAX_BOUNCES`); chromatic medium (σt = (6, 8, 10), hero weights),
/// 16 × 5 000 walks: mean exit weight equivalent to 1 per channel (δ = 1%). Negative control:
/// σa = 2% of σt loses energy, and both checks flag it.
#[test]
fn albedo_one_conserves_energy_index_matched() {
    let gray = medium(Vec3::splat(10.0), Vec3::ZERO, 0.7, Interface::IndexMatched);
    let chromatic = medium(
        Vec3::new(6.0, 8.0, 10.0),
        Vec3::ZERO,
        0.3,
        Interface::IndexMatched,
    );
    let lossy = medium(
        Vec3::splat(9.8),
        Vec3::splat(0.2),
        0.7,
        Interface::IndexMatched,
    );
    for_each_closed_boundary(|name, boundary, x1, n1| {
        let tally = energy_tally(boundary, &gray, x1, n1, 8, 2_500, 1);
        assert_eq!(
            (tally.not_unit, tally.truncated),
            (0, 0),
            "{name}, gray: walks without unit exit weight / truncated"
        );
        let tally = energy_tally(boundary, &chromatic, x1, n1, 16, 5_000, 2);
        assert_eq!(tally.truncated, 0, "{name}, chromatic: truncated walks");
        assert_eq!(
            energy_verdicts(&tally, name),
            [Verdict::Equivalent; 3],
            "{name}, chromatic: mean exit weight not shown within δ = 1% of 1 (confidence 1 − 0.01/3, 16 × 5 000 walks)"
        );
        let lossy = energy_tally(boundary, &lossy, x1, n1, 8, 2_500, 3);
        assert!(
            lossy.not_unit > 0,
            "{name}: negative control (σa > 0) kept every walk's weight"
        );
        let verdicts = energy_verdicts(&lossy, &format!("{name}, negative control σa > 0"));
        assert_eq!(
            verdicts,
            [Verdict::Biased; 3],
            "{name}: negative control not flagged (δ = 1%, confidence 1 − 0.01/3, 8 × 2 500 walks)"
        );
    });
}

/// Albedo 1 with `interface` on the sphere and the closed mesh, gray medium, 8 × 2 500 walks:
/// every walk exits with weight 1 and none hits the cap, and at least `min_reflected` walks
/// were reflected internally (so the check exercises reflection where there is any).
/// Negative control: σa = 2% of σt loses energy, and both checks flag it.
fn check_albedo_one_conserves_energy(interface: Interface, min_reflected: u32, seed: u64) {
    let gray = medium(Vec3::splat(10.0), Vec3::ZERO, 0.7, interface);
    let lossy = medium(Vec3::splat(9.8), Vec3::splat(0.2), 0.7, interface);
    for_each_closed_boundary(|name, boundary, x1, n1| {
        let tally = energy_tally(boundary, &gray, x1, n1, 8, 2_500, seed);
        assert_eq!(
            (tally.not_unit, tally.truncated),
            (0, 0),
            "{name}, {interface:?}: walks without unit exit weight / truncated"
        );
        eprintln!(
            "{name}, {interface:?}: {} of 20 000 walks reflected internally",
            tally.reflected_walks
        );
        assert!(
            tally.reflected_walks >= min_reflected,
            "{name}, {interface:?}: only {} reflected walks",
            tally.reflected_walks
        );
        let lossy = energy_tally(boundary, &lossy, x1, n1, 8, 2_500, seed + 1);
        assert!(
            lossy.not_unit > 0,
            "{name}, {interface:?}: negative control (σa > 0) kept every walk's weight"
        );
        let verdicts = energy_verdicts(
            &lossy,
            &format!("{name} {interface:?}, negative control σa > 0"),
        );
        assert_eq!(
            verdicts,
            [Verdict::Biased; 3],
            "{name}, {interface:?}: negative control not flagged (δ = 1%, confidence 1 − 0.01/3, 8 × 2 500 walks)"
        );
    });
}

/// Smooth dielectric (η = 1.4) at albedo 1: Fresnel and total internal reflection only delay
/// the exit; at least a fifth of the walks are reflected internally.
#[test]
fn albedo_one_conserves_energy_dielectric() {
    check_albedo_one_conserves_energy(Interface::Dielectric { eta: 1.4 }, 4_000, 4);
}

/// Lambertian (diffuse) boundary at albedo 1: every walk leaves at its first boundary hit.
#[test]
fn albedo_one_conserves_energy_diffuse() {
    check_albedo_one_conserves_energy(Interface::Diffuse, 0, 6);
}

/// Diffuse reflectance of a semi-infinite, isotropically scattering medium (σt = 1, albedo
/// `alpha`) under a smooth dielectric boundary of index `eta`, lit by a collimated beam at
/// external incidence cosine `mu0`: one replica of `n` photons of an analogue plane-parallel
/// Monte Carlo in f64 that tracks only depth and direction cosine — a separate simulation from
/// the 3D walk kernel (Fresnel from the angle form, refraction by Snell's law on cosines,
/// absorption by survival, f64 throughout). The
/// specular reflection `F(μ0)` is not counted (it is not subsurface light).
fn plane_parallel_reflectance(alpha: f64, eta: f64, mu0: f64, n: u32, stream: &mut Stream) -> f64 {
    let transmitted = 1.0 - fresnel_by_angles(mu0, eta);
    let mu_refracted = (1.0 - (1.0 - mu0 * mu0) / (eta * eta)).sqrt();
    let mut escaped = 0u32;
    for _ in 0..n {
        // z: depth below the surface; mu: direction cosine with the inward normal.
        let (mut z, mut mu) = (0.0f64, mu_refracted);
        loop {
            let step = -(1.0 - stream.next_f64()).ln();
            let next = z + mu * step;
            if next > 0.0 {
                z = next;
                if stream.next_f64() >= alpha {
                    break; // absorbed
                }
                mu = 2.0 * stream.next_f64() - 1.0;
            } else if stream.next_f64() < fresnel_by_angles(-mu, 1.0 / eta) {
                (z, mu) = (0.0, -mu); // internal (or total) reflection at the surface
            } else {
                escaped += 1;
                break;
            }
        }
    }
    transmitted * escaped as f64 / n as f64
}

/// Per replica and channel, the 3D walk's diffuse reflectance of the same configuration: walks
/// start at the surface of the half-space `z < 0` along the refracted beam, weighted by the
/// entry transmittance `1 − F(μ0)` (as `estimate_exitant` does), and every exit weight counts.
fn walk_dielectric_reflectance(
    medium: &Medium,
    eta: f32,
    mu0: f32,
    entry_fresnel: bool,
    replicas: u32,
    walks: u32,
) -> Vec<[f64; 3]> {
    let boundary = HalfSpace {
        point: Vec3::ZERO,
        normal: Vec3::Z,
    };
    let beam = Vec3::new((1.0 - mu0 * mu0).sqrt(), 0.0, -mu0);
    let dir = refract(beam, Vec3::Z, eta).expect("a beam from outside refracts");
    let entry = if entry_fresnel {
        1.0 - fresnel_dielectric(mu0, eta)
    } else {
        1.0
    };
    let settings = WalkSettings::default();
    (0..replicas)
        .map(|replica| {
            let mut sum = [0.0f64; 3];
            for i in 0..walks {
                let mut stream = StreamKey::new(i, replica, 0xD1E1, 3).stream(17);
                if let WalkEnd::Exited(exit) =
                    walk(&boundary, medium, Vec3::ZERO, dir, &settings, &mut stream)
                {
                    for (s, w) in sum.iter_mut().zip(exit.weight.to_array()) {
                        *s += (entry * w) as f64;
                    }
                }
            }
            sum.map(|s| s / walks as f64)
        })
        .collect()
}

/// The walk through a smooth dielectric (η = 1.4) against the independent plane-parallel Monte
/// Carlo, normal incidence, albedos 0.8, 0.95, 0.99 (one gray-extinction medium, σt = 1).
///
/// Power: per photon the reflectance tally has relative standard deviation ≤ √((1 − R)/R) ≈ 2.4
/// for the smallest R ≈ 0.15 (α = 0.8); 16 × 40 000 walks give a relative standard error of
/// ≤ 0.3%, and the reference (16 × 160 000 photons) ≤ 0.15%, so the 99.67% interval is at most
/// about ±1.0% and a true bias of 0 passes δ = 1.5% (measured: R = 0.1533, 0.3588, 0.6034). Equivalence per albedo at confidence
/// 1 − 0.01/3 (Bonferroni). Negative control at 1.9 δ: the walk without the entry transmittance
/// `1 − F(1) = 1 − 0.0278` (+2.9% bias) must be flagged `Biased` for every albedo.
#[test]
fn walk_through_a_dielectric_half_space_matches_a_plane_parallel_simulation() {
    const ETA: f32 = 1.4;
    const MU0: f32 = 1.0;
    const REPLICAS: u32 = 16;
    const WALKS: u32 = 40_000;
    const PHOTONS: u32 = 160_000;
    const DELTA: f64 = 0.015;
    const CONFIDENCE: f64 = 1.0 - 0.01 / 3.0;
    let albedo = Vec3::new(0.8, 0.95, 0.99);
    let walk_medium = medium(
        albedo,
        Vec3::ONE - albedo,
        0.0,
        Interface::Dielectric { eta: ETA },
    );
    let walks = walk_dielectric_reflectance(&walk_medium, ETA, MU0, true, REPLICAS, WALKS);
    let control = walk_dielectric_reflectance(&walk_medium, ETA, MU0, false, REPLICAS, WALKS);
    for c in 0..3 {
        let alpha = albedo[c] as f64;
        let reference: Vec<f64> = (0..REPLICAS)
            .map(|replica| {
                let mut stream = StreamKey::new(replica, c as u32, 0xD1E2, 4).stream(23);
                plane_parallel_reflectance(alpha, ETA as f64, MU0 as f64, PHOTONS, &mut stream)
            })
            .collect();
        let reference = Summary::from_samples(&reference);
        for (what, replicas, want) in [
            ("walk", &walks, Verdict::Equivalent),
            (
                "negative control (no entry Fresnel)",
                &control,
                Verdict::Biased,
            ),
        ] {
            let estimate = channel_summary(replicas, c);
            let e = equivalence(&estimate, &reference, DELTA, CONFIDENCE);
            eprintln!(
                "dielectric half-space α = {alpha}: {what} {:.5} ± {:.5}, plane-parallel {:.5} ± {:.5}: {e}",
                estimate.mean, estimate.std_err, reference.mean, reference.std_err
            );
            assert_eq!(
                e.verdict, want,
                "α = {alpha}, {what}: {e} (δ = {DELTA}, confidence {CONFIDENCE})"
            );
        }
    }
}
