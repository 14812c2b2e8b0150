//! The two hit policies of the baseline estimate the same pixel value (both unbiased, see
//! `sss::integrator::pt`): on the curved `bumpy` object, per pixel, Welch tests between
//! `HitPolicy::All` and `HitPolicy::UniformOne` (independent streams), Holm over the pixels,
//! family α = 1e-3, N = 60 000 samples per policy and pixel. Negative control: the uniform pick
//! without its `n_hits` factor (i.e. taking `p_disk` as the density of the kept hit and forgetting
//! the `1/n` pick) is rejected by the same test.

use geometry::Hit;
use glam::Vec3;
use restir::stats::{Welford, holm, welch};
use sss::color::luminance;
use sss::integrator::pt::{estimate, sample_stream};
use sss::integrator::{HitPolicy, PtSettings, Shading};
use sss::scene::{GBuffer, GPixel, Scene};

const N: u32 = 60_000;
const ALPHA: f64 = 1e-3;

/// The uniform-pick estimator with the `n_hits` factor dropped (deliberately biased): the
/// correct `HitPolicy::UniformOne` estimate divided by the number of hits its probe found.
fn uniform_without_hit_count(
    scene: &Scene,
    shading: &Shading,
    settings: &PtSettings,
    rng: &mut restir::rng::Stream,
    hits: &mut Vec<Hit>,
) -> Vec3 {
    let value = estimate(scene, shading, settings, rng, hits);
    if hits.is_empty() {
        Vec3::ZERO
    } else {
        value / hits.len() as f32
    }
}

#[test]
fn uniform_pick_and_all_hits_agree_on_a_curved_object() {
    let mut scene = Scene::builtin("bumpy").expect("built-in scene");
    scene.camera = scene.camera.with_resolution(64, 48);
    let gbuffer = GBuffer::render(&scene, 0);
    let translucent = |p: &GPixel| {
        matches!(
            scene.material_of_object(p.object),
            sss::material::Material::Translucent(_)
        )
    };
    // Six pixels on the translucent object, spread over its rows (lit, penumbra and shadow).
    let candidates: Vec<(u32, GPixel)> = gbuffer
        .pixels
        .iter()
        .enumerate()
        .filter_map(|(i, p)| p.filter(translucent).map(|p| (i as u32, p)))
        .collect();
    assert!(candidates.len() >= 6, "too few translucent pixels");
    let pixels: Vec<(u32, GPixel)> = (0..6)
        .map(|k| candidates[(2 * k + 1) * candidates.len() / 12])
        .collect();

    let mut hits = Vec::new();
    let (mut p_right, mut p_control) = (Vec::new(), Vec::new());
    for (pixel, x1) in &pixels {
        let shading = Shading::new(&scene, x1);
        let mut summaries = [Welford::new(), Welford::new(), Welford::new()];
        for sample in 0..N {
            let all = PtSettings {
                hits: HitPolicy::All,
                ..PtSettings::default()
            };
            let uniform = PtSettings {
                hits: HitPolicy::UniformOne,
                ..PtSettings::default()
            };
            let values = [
                estimate(
                    &scene,
                    &shading,
                    &all,
                    &mut sample_stream(*pixel, 0, sample, 1),
                    &mut hits,
                ),
                estimate(
                    &scene,
                    &shading,
                    &uniform,
                    &mut sample_stream(*pixel, 0, sample, 2),
                    &mut hits,
                ),
                uniform_without_hit_count(
                    &scene,
                    &shading,
                    &uniform,
                    &mut sample_stream(*pixel, 0, sample, 2),
                    &mut hits,
                ),
            ];
            for (summary, value) in summaries.iter_mut().zip(values) {
                summary.push(luminance(value) as f64);
            }
        }
        let [all, uniform, control] = summaries.map(|s| s.summary());
        let (right, wrong) = (welch(&uniform, &all), welch(&control, &all));
        eprintln!(
            "pixel {pixel}: all {:.5} ± {:.5}, uniform {:.5} ± {:.5} (p = {:.3}); control {:.5} (p = {:.1e})",
            all.mean,
            all.std_err,
            uniform.mean,
            uniform.std_err,
            right.p_value,
            control.mean,
            wrong.p_value
        );
        p_right.push(right.p_value);
        p_control.push(wrong.p_value);
    }
    assert!(
        holm(&p_right, ALPHA).iter().all(|&rejected| !rejected),
        "the hit policies disagree (Holm, α = {ALPHA}, N = {N}): p = {p_right:?}"
    );
    assert!(
        holm(&p_control, ALPHA).iter().any(|&rejected| rejected),
        "negative control (no n_hits factor) not detected: p = {p_control:?}"
    );
}
