//! The skip policy of the Vulkan tests, in one place: where Vulkan is unavailable (no loader, no
//! device, a build without `glslc`) a test says why and passes, unless [`REQUIRE_ENV`]` = 1`
//! (set in CI, where lavapipe is installed), which makes it fail instead.

use std::sync::OnceLock;

use glam::Vec3;

use sss::scene::{GBuffer, Scene};

use super::{
    Buffer, Checks, Context, FrameInput, FrameParams, GpuPixel, GpuScene, Kernel, REQUIRE_ENV,
    Renderer, Shader, VulkanError,
};
use crate::{Backend, Run};

/// `Some(value)`, or `None` after printing why `test` is skipped; panics instead when
/// [`REQUIRE_ENV`] is `1`.
fn or_skip<T>(test: &str, opened: Result<T, String>) -> Option<T> {
    match opened {
        Ok(value) => Some(value),
        Err(e) if std::env::var(REQUIRE_ENV).as_deref() == Ok("1") => {
            panic!("{test}: {REQUIRE_ENV}=1 but the Vulkan backend is unavailable: {e}")
        }
        Err(e) => {
            eprintln!("{test}: skipped, Vulkan backend unavailable: {e}");
            None
        }
    }
}

/// A device and the kernel of `shader` for `test`, or `None` when Vulkan is unavailable.
pub fn kernel_or_skip(test: &str, shader: Shader) -> Option<(Context, Kernel)> {
    let opened = Context::new().and_then(|context| {
        let kernel = Kernel::for_shader(&context, shader)?;
        Ok::<_, VulkanError>((context, kernel))
    });
    let (context, kernel) = or_skip(test, opened.map_err(|e| e.to_string()))?;
    eprintln!("{test}: on {:?}", context.device());
    Some((context, kernel))
}

/// A renderer of its own whose context runs the validation layer's `checks`, or `None` when
/// Vulkan or the layer (`vulkan-validationlayers`) is unavailable.
pub fn validated_or_skip(test: &str, checks: Checks) -> Option<Renderer> {
    let opened = Context::with_validation(None, checks).map_err(|e| e.to_string());
    let context = or_skip(test, opened)?;
    eprintln!(
        "{test}: on {:?} with validation {checks:?}",
        context.device()
    );
    Some(Renderer::new(context))
}

/// `result`'s value; under validation an error names the call `what` it came from.
pub fn validated<T, E: std::fmt::Display>(what: &str, result: Result<T, E>) -> T {
    result.unwrap_or_else(|e| panic!("{what}: {e}"))
}

/// Fails with the layer's messages when validation reported an error that no call returned;
/// warnings (e.g. performance hints) are listed, not failed.
pub fn assert_no_unreported_errors(renderer: &Renderer) {
    let messages = renderer.context().validation_messages();
    let errors: Vec<_> = messages
        .iter()
        .filter(|m| m.severity == super::Severity::Error)
        .collect();
    assert!(errors.is_empty(), "unreported errors: {errors:#?}");
    for m in &messages {
        eprintln!("validation: warning {}: {}", m.id, m.text);
    }
}

/// The Vulkan backend shared by every test of one test binary (pipelines are created once per
/// renderer; on lavapipe that compiles LLVM code), or `None` when Vulkan is unavailable.
pub fn backend_or_skip(test: &str) -> Option<Backend> {
    static SHARED: OnceLock<Result<Backend, String>> = OnceLock::new();
    let opened = SHARED.get_or_init(|| Backend::vulkan(None, false).map_err(|e| e.to_string()));
    let backend = or_skip(test, opened.clone())?;
    eprintln!("{test}: on {backend}");
    Some(backend)
}

/// Mean over frames and pixels of `Σ_c (a − b)² / (b² + ε)` over RGB, ε = 1e-2 (a relative MSE
/// that does not explode on black pixels), accumulated in f64: the yardstick of whole-run
/// parity, compared with the same figure between two CPU seeds.
pub fn rel_mse(a: &Run, b: &Run) -> f64 {
    const EPSILON: f64 = 1e-2;
    let (mut sum, mut n) = (0.0, 0usize);
    for (fa, fb) in a.frames.iter().zip(&b.frames) {
        for (pa, pb) in fa.pixels.iter().zip(&fb.pixels) {
            for c in 0..3 {
                let (x, y) = (pa[c] as f64, pb[c] as f64);
                sum += (x - y) * (x - y) / (y * y + EPSILON);
                n += 1;
            }
        }
    }
    sum / n.max(1) as f64
}

/// `Σ ‖a − b‖² / Σ ‖b‖²` over `pixels`, accumulated in f64 (the bare sum where `b` is black
/// there): the image yardstick of the per-pixel method parity tests, compared with the same
/// figure between two CPU seeds.
pub fn rel_mse_pixels(a: &[Vec3], b: &[Vec3], pixels: impl IntoIterator<Item = usize>) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for p in pixels {
        let (x, y) = (a[p].as_dvec3(), b[p].as_dvec3());
        num += (x - y).length_squared();
        den += y.length_squared();
    }
    if den > 0.0 { num / den } else { num }
}

/// The largest difference of a channel of `got` from `want`, over `want`'s largest channel (so
/// that a dark channel is not over-weighted); 0 for equal pixels, ∞ where `want` is black and
/// `got` is not.
pub fn pixel_error(got: Vec3, want: Vec3) -> f64 {
    let scale = want.max_element() as f64;
    if got == want {
        0.0
    } else if scale > 0.0 {
        (got - want).abs().max_element() as f64 / scale
    } else {
        f64::INFINITY
    }
}

/// Relative error of `got` against `want`; equal values (0 included) give 0, a 0 or
/// non-finite value on one side only gives ∞.
pub fn rel_error(got: f32, want: f32) -> f64 {
    if got == want {
        0.0
    } else if want == 0.0 || !want.is_finite() || !got.is_finite() {
        f64::INFINITY
    } else {
        ((got as f64 - want as f64) / want as f64).abs()
    }
}

/// Largest absolute difference of the components over `scale` (a length of the problem, so
/// components near 0 are not over-weighted).
pub fn scaled_error(got: &[f32], want: &[f32], scale: f32) -> f64 {
    got.iter()
        .zip(want)
        .map(|(&g, &w)| (g as f64 - w as f64).abs() / scale as f64)
        .fold(0.0, f64::max)
}

/// The tally of one parity comparison: integer mismatches, float errors beyond their stated
/// bounds, and the worst error per named float field.
#[derive(Debug)]
pub struct Tally {
    pub bounds: &'static [(&'static str, f64)],
    pub compared: usize,
    /// Comparisons with an integer field (or a fail code, or a diag counter) different.
    pub mismatched: usize,
    /// Comparisons whose integers agree but a float exceeds its bound.
    pub beyond_bounds: usize,
    /// Worst float error per named field, over the comparisons whose integers agree.
    pub worst: Vec<(&'static str, f64)>,
}

impl Tally {
    /// An empty tally; every float field compared later needs a bound in `bounds`.
    pub fn new(bounds: &'static [(&'static str, f64)]) -> Tally {
        Tally {
            bounds,
            compared: 0,
            mismatched: 0,
            beyond_bounds: 0,
            worst: Vec::new(),
        }
    }

    /// Records `error` of field `name`; true if it exceeds the field's bound.
    pub fn float(&mut self, name: &'static str, error: f64) -> bool {
        match self.worst.iter_mut().find(|(n, _)| *n == name) {
            Some((_, e)) => *e = e.max(error),
            None => self.worst.push((name, error)),
        }
        let bound = self.bounds.iter().find(|(n, _)| *n == name);
        error > bound.expect("every compared field has a bound").1
    }

    pub fn mismatch_fraction(&self) -> f64 {
        self.mismatched as f64 / self.compared.max(1) as f64
    }

    /// Fraction rejected for any reason (the negative controls' statistic).
    pub fn rejected_fraction(&self) -> f64 {
        (self.mismatched + self.beyond_bounds) as f64 / self.compared.max(1) as f64
    }
}

/// A scene uploaded with one frame's `FrameParams` and the CPU's G-buffer of that frame: the
/// inputs of a per-pixel kernel under test.
pub struct UploadedFrame {
    pub scene: GpuScene,
    pub params: Buffer,
    pub gbuffer: Buffer,
    pub width: u32,
    pub height: u32,
}

impl UploadedFrame {
    pub fn new(
        context: &Context,
        scene: &Scene,
        gbuffer: &GBuffer,
        seed: u64,
    ) -> Result<UploadedFrame, VulkanError> {
        let pixels: Vec<GpuPixel> = gbuffer
            .pixels
            .iter()
            .map(|p| GpuPixel::from_cpu(p.as_ref()))
            .collect();
        Ok(UploadedFrame {
            scene: GpuScene::upload(context, scene)?,
            params: FrameParams::new(scene, gbuffer.frame, None, seed).buffer(context)?,
            gbuffer: Buffer::from_slice(context, &pixels)?,
            width: gbuffer.width,
            height: gbuffer.height,
        })
    }

    pub fn input(&self) -> FrameInput<'_> {
        FrameInput {
            scene: &self.scene,
            params: &self.params,
            gbuffer: &self.gbuffer,
            width: self.width,
            height: self.height,
        }
    }
}
