//! The random-walk method on a real scene, judged by the lab's regions: a plausible,
//! deterministic image.

use lab::regions::{Region, Regions};
use methods::random_walk::render;
use restir::stats::Summary;
use sss::color::luminance;
use sss::scene::{GBuffer, Scene};

fn bumpy(w: u32, h: u32) -> Scene {
    let scene = Scene::builtin("bumpy").expect("built-in");
    Scene {
        camera: scene.camera.with_resolution(w, h),
        ..scene
    }
}

/// On `bumpy` (24 × 18, 16 walks per pixel): every value is finite and non-negative, the
/// run is a function of its seed, and lit translucent pixels are brighter than shadowed ones
/// on average (the walk sees the light and the occluder).
#[test]
fn walks_render_a_plausible_deterministic_image() {
    let scene = bumpy(24, 18);
    let gbuffer = GBuffer::render(&scene, 15);
    let (a, nonfinite) = render(&scene, &gbuffer, 1, 16).unwrap();
    let (b, _) = render(&scene, &gbuffer, 1, 16).unwrap();
    assert_eq!(a, b);
    assert_eq!(nonfinite, 0);
    assert!(
        a.pixels
            .iter()
            .all(|p| p.is_finite() && p.min_element() >= 0.0)
    );
    let regions = Regions::classify(&scene, &gbuffer, 7);
    let mean = |r| {
        let values: Vec<f64> = regions
            .pixels(r)
            .iter()
            .map(|&p| luminance(a.pixels[p].as_dvec3()))
            .collect();
        Summary::from_samples(&values).mean
    };
    assert!(mean(Region::Lit) > 2.0 * mean(Region::Shadowed));
}
