//! Candidate generation [001 §3.1, Eq. 10]: M BSSRDF samples per pixel, every hit of each probe a
//! candidate with density `p_disk · p_light`, then the selected (canonical) sample shadow-tested.

use geometry::Hit;
use restir::reservoir::{InvalidCandidate, Reservoir, Ris};
use restir::rng::StreamKey;
use restir::shift::Domain;
use shifts::{SssDomain, SssSample};
use sss::bssrdf::{BssrdfSample, EntryPoint, Probe};

use crate::purpose;

/// What one pixel's candidate generation saw (for the intersections-per-probe diagnostic).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ProbeCounts {
    pub probes: u32,
    pub hits: u32,
}

/// The canonical reservoir of `domain` from `bssrdf_samples` (M ≥ 1) BSSRDF samples.
///
/// Each hit `x2` of a probe, with a light sample `x3` at x2, streams with resampling weight
/// `p̂(x) / (M · p_disk(x2 | x1) · p_light(x3 | x2))` [001 Eq. 10]; the confidence grows by 1 per
/// BSSRDF sample, not per hit, so `c = M`. With `shared_light` one triple of light numbers serves
/// all hits of a probe (each hit still gets its own density `p_light(x3 | x2)`, so every
/// candidate keeps its exact pdf) [001 §5.2]. The target is unshadowed: the pipeline applies
/// [`shadow_test`] to the result. `hits` is scratch space.
pub fn generate(
    domain: &SssDomain,
    bssrdf_samples: u32,
    shared_light: bool,
    seed: u64,
    hits: &mut Vec<Hit>,
) -> Result<(Reservoir<SssSample>, ProbeCounts), InvalidCandidate> {
    let key = |purpose| StreamKey::new(domain.pixel(), domain.frame(), domain.pass(), purpose);
    let mut probe_rng = key(purpose::PROBE).stream(seed);
    let mut light_rng = key(purpose::LIGHT).stream(seed);
    let mut select_rng = key(purpose::SELECT).stream(seed);
    let scene = domain.scene();
    let inv_m = 1.0 / bssrdf_samples.max(1) as f32;
    let mut ris = Ris::new();
    let mut counts = ProbeCounts::default();
    for _ in 0..bssrdf_samples {
        ris.skip(1.0)?;
        let probe = Probe::sample(
            domain.selection(),
            probe_rng.next_f32(),
            probe_rng.next_f32(),
            probe_rng.next_f32(),
        );
        probe.trace(&scene.geometry, domain.x1(), hits);
        counts.probes += 1;
        counts.hits += hits.len() as u32;
        let mut light_numbers = || {
            [
                light_rng.next_f32(),
                light_rng.next_f32(),
                light_rng.next_f32(),
            ]
        };
        let shared = shared_light.then(&mut light_numbers);
        for (rank, hit) in hits.iter().enumerate() {
            let u_light = shared.unwrap_or_else(&mut light_numbers);
            let u_select = select_rng.next_f32();
            let x2 = EntryPoint::from_hit(&scene.geometry, hit);
            let p_disk = domain.p_disk(&x2);
            let Some(light) = scene.lights.sample(x2.position, u_light) else {
                continue;
            };
            let density = p_disk * light.pdf;
            if !(density > 0.0 && density.is_finite()) {
                continue;
            }
            let bssrdf = BssrdfSample::new(&probe, Some(rank as u32), &x2, p_disk);
            let x = SssSample::new(&bssrdf, light.light, light.point);
            let target = domain.target(&x);
            // w = p̂(x) / (M p_disk p_light)   [001 Eq. 10]
            let weight = inv_m * target / density;
            if weight.is_finite() {
                ris.update(x, target, weight, 0.0, u_select)?;
            }
        }
    }
    Ok((ris.finish(), counts))
}

/// The shadow test of the canonical sample: `W = 0` if x2–x3 is occluded, the sample is kept
/// (DESIGN §9 "Visibility").
pub fn shadow_test(domain: &SssDomain, canonical: &mut Reservoir<SssSample>) {
    if let Some(y) = &canonical.y
        && !domain.visible(y)
    {
        canonical.ucw = 0.0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;
    use sss::color::luminance;
    use sss::integrator::pt::{PtSettings, Shading, estimate, sample_stream};
    use sss::scene::{GBuffer, Scene};

    fn scene(name: &str, size: u32) -> Scene {
        let mut scene = Scene::builtin(name).unwrap();
        scene.camera = scene.camera.with_resolution(size, size);
        scene
    }

    /// Confidence is M (per BSSRDF sample, not per hit), probes are counted, and occluded
    /// canonical samples keep their sample with W = 0: on `half-shadow` every x2 with x < 0 is in
    /// shadow.
    #[test]
    fn confidence_counts_bssrdf_samples_and_shadowed_samples_get_zero_weight() {
        let scene = scene("half-shadow", 16);
        let gbuffer = GBuffer::render(&scene, 0);
        let mut hits = Vec::new();
        let (mut shadowed, mut lit) = (0, 0);
        for (pixel, g) in gbuffer.pixels.iter().enumerate() {
            let Some(g) = g else { continue };
            let domain = SssDomain::new(&scene, g, pixel as u32, 0, 0, 9).unwrap();
            for m in [1, 3] {
                let (mut r, counts) = generate(&domain, m, true, 9, &mut hits).unwrap();
                assert_eq!(r.confidence, m as f32);
                assert_eq!(counts.probes, m);
                // A flat plane crosses each probe chord at most once.
                assert!(counts.hits <= m);
                shadow_test(&domain, &mut r);
                let Some(y) = r.y else { continue };
                let x2 = domain.entry_point(&y).unwrap();
                // The occluder's edge is x = 0 (half-shadow.toml); keep clear of it by 1e-3.
                if x2.position.x < -1e-3 {
                    assert_eq!(r.ucw, 0.0, "shadowed x2 {:?}", x2.position);
                    shadowed += 1;
                } else if x2.position.x > 1e-3 {
                    assert!(r.ucw > 0.0 && domain.contribution(&y) != Vec3::ZERO);
                    lit += 1;
                }
            }
        }
        assert!(shadowed > 20 && lit > 20, "shadowed {shadowed}, lit {lit}");
    }

    /// E[f(Y)·W] of one pixel equals the path tracer's all-hits estimate (unbiased,
    /// `sss::integrator::pt`), each averaged over N = 4000 seeds at the `bumpy` pixel (24×24)
    /// whose canonical samples are most evenly split between lit and occluded, with M = 2 and a
    /// shared light sample. Welch z, two-sided, α = 1e-3. Negative control: the same estimate
    /// without the shadow test is rejected by the same test.
    #[test]
    fn canonical_estimate_matches_the_path_tracer() {
        let scene = scene("bumpy", 24);
        let gbuffer = GBuffer::render(&scene, 0);
        let mut hits = Vec::new();
        let domains: Vec<(u32, sss::scene::GPixel)> = gbuffer
            .pixels
            .iter()
            .enumerate()
            .filter_map(|(i, g)| g.map(|g| (i as u32, g)))
            .filter(|(i, g)| SssDomain::new(&scene, g, *i, 0, 0, 0).is_some())
            .collect();
        let occluded_share = |(pixel, g): &(u32, sss::scene::GPixel)| {
            let (mut occluded, mut total) = (0.0f64, 0.0f64);
            for seed in 0..32 {
                let domain = SssDomain::new(&scene, g, *pixel, 0, 0, 1000 + seed).unwrap();
                let (r, _) = generate(&domain, 1, true, 1000 + seed, &mut Vec::new()).unwrap();
                if let Some(y) = r.y {
                    total += 1.0;
                    occluded += !domain.visible(&y) as u32 as f64;
                }
            }
            (occluded / total.max(1.0) - 0.5).abs()
        };
        let (pixel, g) = *domains
            .iter()
            .min_by(|a, b| occluded_share(a).total_cmp(&occluded_share(b)))
            .unwrap();
        let n = 4000u64;
        let (mut restir, mut unshadowed, mut pt) = (Vec::new(), Vec::new(), Vec::new());
        for seed in 0..n {
            let domain = SssDomain::new(&scene, &g, pixel, 0, 0, seed).unwrap();
            let (mut r, _) = generate(&domain, 2, true, seed, &mut hits).unwrap();
            let value = |r: &Reservoir<SssSample>| {
                r.y.map_or(0.0, |y| {
                    luminance(domain.contribution(&y)) as f64 * r.ucw as f64
                })
            };
            unshadowed.push(value(&r));
            shadow_test(&domain, &mut r);
            restir.push(value(&r));
            let mut rng = sample_stream(pixel, 0, 0, seed);
            pt.push(luminance(estimate(
                &scene,
                &Shading::new(&scene, &g),
                &PtSettings::default(),
                &mut rng,
                &mut hits,
            )) as f64);
        }
        let mean_var = |v: &[f64]| {
            let m = v.iter().sum::<f64>() / v.len() as f64;
            let var = v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() - 1) as f64;
            (m, var / v.len() as f64)
        };
        let z = |a: &[f64], b: &[f64]| {
            let ((ma, va), (mb, vb)) = (mean_var(a), mean_var(b));
            (ma - mb) / (va + vb).sqrt()
        };
        // Two-sided standard normal critical value at α = 1e-3.
        let z_crit = 3.2905;
        let good = z(&restir, &pt);
        let bad = z(&unshadowed, &pt);
        println!("pixel {pixel}, N = {n}: z = {good:.3}, control (no shadow test) z = {bad:.3}");
        assert!(
            good.abs() < z_crit,
            "pixel {pixel}, α = 1e-3, N = {n}: z = {good}"
        );
        let bad = z(&unshadowed, &pt);
        assert!(
            bad.abs() > z_crit,
            "negative control undetected, α = 1e-3, N = {n}: z = {bad}"
        );
    }
}
