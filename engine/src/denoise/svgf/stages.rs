//! The per-pixel stages of the spatiotemporal variance-guided filter (`[SVGF]`), each a function of
//! one pixel and read-only buffers, so that every pixel is independent of the others and of the
//! thread that computes it. `engine/glsl/denoise_svgf.glsl` is their GLSL twin, one function
//! per function here, with the same operation order (no fused multiply-add); only `exp` (the
//! edge-stopping weight) is not bit-identical on a device.

use glam::Vec3;
use sss::color::luminance;

use super::Params;
use crate::contract::{SvgfHistory, SvgfPixel};
use crate::denoise::guide::NONE;

/// One pixel of the à-trous input/output: demodulated colour and its luminance variance.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Filtered {
    pub colour: Vec3,
    pub variance: f32,
}

/// The size of the image the stages run over.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Size {
    pub width: u32,
    pub height: u32,
}

impl Size {
    /// The pixel `(x + dx, y + dy)` of pixel `p`, if inside the image.
    pub fn offset(self, p: usize, dx: i32, dy: i32) -> Option<usize> {
        let x = (p % self.width as usize) as i64 + i64::from(dx);
        let y = (p / self.width as usize) as i64 + i64::from(dy);
        let inside =
            (0..i64::from(self.width)).contains(&x) && (0..i64::from(self.height)).contains(&y);
        inside.then(|| (y * i64::from(self.width) + x) as usize)
    }
}

/// Temporal accumulation of pixel `p` with demodulated colour `c` [SVGF §4.1]: an exponential
/// moving average through the reprojected pixel of `history` (the previous frame's), colour with
/// `α = max(1/(n + 1), α_c)` for a history of `n` frames, the luminance moments with `α_m`
/// [SVGF §4.1]; a pixel without history (no previous pixel, [`NONE`] included, or one that had
/// none) starts over.
pub fn temporal(
    pixel: &SvgfPixel,
    c: Vec3,
    history: &[SvgfHistory],
    params: &Params,
) -> SvgfHistory {
    let l = luminance(c);
    let previous = if pixel.object == NONE || pixel.previous as usize >= history.len() {
        None
    } else {
        Some(history[pixel.previous as usize]).filter(|h| h.frames > 0)
    };
    let Some(h) = previous else {
        return SvgfHistory {
            colour: c.to_array(),
            moments: [l, l * l],
            frames: u32::from(pixel.object != NONE),
        };
    };
    let frames = h.frames.saturating_add(1);
    let alpha = (1.0 / frames as f32).max(params.alpha_colour);
    let colour = c * alpha + Vec3::from_array(h.colour) * (1.0 - alpha);
    let a = params.alpha_moments;
    let m1 = l * a + h.moments[0] * (1.0 - a);
    let m2 = (l * l) * a + h.moments[1] * (1.0 - a);
    SvgfHistory {
        colour: colour.to_array(),
        moments: [m1, m2],
        frames,
    }
}

/// `x^n` by binary exponentiation: exact multiplies in a fixed order, so the device gets the
/// same bits (`pow` would not).
pub fn powi(x: f32, n: u32) -> f32 {
    let (mut result, mut base, mut e) = (1.0f32, x, n);
    while e > 0 {
        if e & 1 == 1 {
            result *= base;
        }
        base *= base;
        e >>= 1;
    }
    result
}

/// The normal weight `max(0, n(p)·n(q))^σ_n` [SVGF Eq. 4].
pub fn normal_weight(p: &SvgfPixel, q: &SvgfPixel, params: &Params) -> f32 {
    let d = Vec3::from_array(p.normal).dot(Vec3::from_array(q.normal));
    powi(d.max(0.0), params.sigma_normal)
}

/// The depth term of the exponent, `|z(p) − z(q)| / (σ_z |∇z(p)·(p − q)| + ε_z)` [SVGF Eq. 3],
/// for the offset `(dx, dy)` in pixels.
pub fn depth_term(p: &SvgfPixel, q: &SvgfPixel, dx: f32, dy: f32, params: &Params) -> f32 {
    let along = (p.gradient[0] * dx + p.gradient[1] * dy).abs();
    (p.depth - q.depth).abs() / (params.sigma_depth * along + params.epsilon_depth)
}

/// The variance estimate of pixel `p` from its accumulated `history` [SVGF §4.2]: the temporal
/// `m₂ − m₁²` once `variance_history` frames are accumulated, before that the same from moments
/// averaged over a `(2r + 1)²` window with depth and normal weights (same object only).
pub fn variance(
    size: Size,
    p: usize,
    pixels: &[SvgfPixel],
    history: &[SvgfHistory],
    params: &Params,
) -> f32 {
    let centre = &pixels[p];
    let h = &history[p];
    if centre.object == NONE {
        return 0.0;
    }
    if h.frames >= params.variance_history {
        return (h.moments[1] - h.moments[0] * h.moments[0]).max(0.0);
    }
    let r = params.variance_radius as i32;
    let (mut m1, mut m2, mut sum) = (0.0f32, 0.0f32, 0.0f32);
    for dy in -r..=r {
        for dx in -r..=r {
            let Some(q) = size.offset(p, dx, dy) else {
                continue;
            };
            let other = &pixels[q];
            if other.object != centre.object {
                continue;
            }
            let w = if q == p {
                1.0
            } else {
                let e = depth_term(centre, other, dx as f32, dy as f32, params);
                normal_weight(centre, other, params) * (-e).exp()
            };
            m1 += history[q].moments[0] * w;
            m2 += history[q].moments[1] * w;
            sum += w;
        }
    }
    let (m1, m2) = (m1 / sum, m2 / sum);
    (m2 - m1 * m1).max(0.0)
}

/// The variance at `p` blurred by the 3×3 Gaussian `[¼ ½ ¼]²` over the pixels inside the image
/// (renormalised at the border): the luminance weight's prefilter [SVGF Eq. 5].
pub fn prefiltered_variance(size: Size, p: usize, input: &[Filtered]) -> f32 {
    const G: [f32; 3] = [0.25, 0.5, 0.25];
    let (mut sum, mut weight) = (0.0f32, 0.0f32);
    for dy in -1i32..=1 {
        for dx in -1i32..=1 {
            let Some(q) = size.offset(p, dx, dy) else {
                continue;
            };
            let k = G[(dx + 1) as usize] * G[(dy + 1) as usize];
            sum += input[q].variance * k;
            weight += k;
        }
    }
    sum / weight
}

/// One edge-avoiding à-trous iteration at pixel `p` with holes of `step` pixels [SVGF §4.3]: the
/// 5×5 B3-spline kernel `h` times the edge-stopping weight `w = w_z·w_n·w_l` of same-object
/// pixels inside the image (`w = 1` at the centre) [SVGF Eq. 1], the colour filtered with
/// `h·w`, the variance with `(h·w)²` [SVGF §4.3]. A pixel without a hit passes through.
pub fn atrous(
    size: Size,
    p: usize,
    step: u32,
    pixels: &[SvgfPixel],
    input: &[Filtered],
    params: &Params,
) -> Filtered {
    const H: [f32; 5] = [1.0 / 16.0, 0.25, 0.375, 0.25, 1.0 / 16.0];
    let centre = &pixels[p];
    if centre.object == NONE {
        return Filtered {
            colour: input[p].colour,
            variance: 0.0,
        };
    }
    let l = luminance(input[p].colour);
    let phi = params.sigma_luminance * prefiltered_variance(size, p, input).sqrt()
        + params.epsilon_luminance;
    let (mut colour, mut variance, mut sum) = (Vec3::ZERO, 0.0f32, 0.0f32);
    for j in -2i32..=2 {
        for i in -2i32..=2 {
            let (dx, dy) = (i * step as i32, j * step as i32);
            let Some(q) = size.offset(p, dx, dy) else {
                continue;
            };
            let other = &pixels[q];
            if other.object != centre.object {
                continue;
            }
            let w = if q == p {
                1.0
            } else {
                let e = depth_term(centre, other, dx as f32, dy as f32, params)
                    + (l - luminance(input[q].colour)).abs() / phi;
                normal_weight(centre, other, params) * (-e).exp()
            };
            let k = H[(i + 2) as usize] * H[(j + 2) as usize] * w;
            colour += input[q].colour * k;
            variance += input[q].variance * (k * k);
            sum += k;
        }
    }
    Filtered {
        colour: colour / sum,
        variance: variance / (sum * sum),
    }
}
