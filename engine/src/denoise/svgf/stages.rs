//! The per-pixel stages of the spatiotemporal variance-guided filter (`[SVGF]`), each a function of
//! one pixel and read-only buffers, so that every pixel is independent of the others and of the
//! thread that computes it. `engine/glsl/denoise_svgf.glsl` is their GLSL twin, one function
//! per function here, with the same operation order (no fused multiply-add); only `exp` (the
//! edge-stopping weight) is not bit-identical on a device.

use glam::{Vec2, Vec3};
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
        self.at(x, y)
    }

    /// The pixel `(x, y)`, if inside the image.
    pub fn at(self, x: i64, y: i64) -> Option<usize> {
        let inside =
            (0..i64::from(self.width)).contains(&x) && (0..i64::from(self.height)).contains(&y);
        inside.then(|| (y * i64::from(self.width) + x) as usize)
    }
}

/// Temporal accumulation of pixel `p` with demodulated colour `c` [SVGF §4.1]: an exponential
/// moving average with the previous frame's history read at the pixel's reprojection
/// ([`reprojected`]), colour with `α = max(1/(n + 1), α_c)` for a history of `n` frames, the
/// luminance moments with `α_m` [SVGF §4.1]; a pixel without history (no hit, or no tap of its
/// footprint kept) starts over.
pub fn temporal(
    size: Size,
    pixel: &SvgfPixel,
    c: Vec3,
    history: &[SvgfHistory],
    params: &Params,
) -> SvgfHistory {
    let l = luminance(c);
    let previous = if pixel.object == NONE {
        None
    } else {
        reprojected(size, pixel, history)
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

/// The previous frame's `history` at `pixel`'s reprojection, read through the 2×2 bilinear
/// footprint of Schied et al. 2017 [SVGF §4.1]: tap `t`, pixel
/// `floor(previous) + (t & 1, t >> 1)`, has the bilinear weight of `previous`'s fraction and is
/// kept where the guide found that it shows the same surface (bit `t` of `taps`) and it has a
/// history; the colour, the moments and the frames accumulated are the kept taps' means with the
/// weights renormalised over them (the frames rounded to the nearest integer). `None` where no
/// tap is kept (their weights sum to 0).
pub fn reprojected(size: Size, pixel: &SvgfPixel, history: &[SvgfHistory]) -> Option<SvgfHistory> {
    if pixel.taps == 0 {
        return None;
    }
    let position = Vec2::from_array(pixel.previous);
    let corner = position.floor();
    let (fx, fy) = (position.x - corner.x, position.y - corner.y);
    let weights = [
        (1.0 - fx) * (1.0 - fy),
        fx * (1.0 - fy),
        (1.0 - fx) * fy,
        fx * fy,
    ];
    let (mut colour, mut m1, mut m2, mut frames, mut sum) =
        (Vec3::ZERO, 0.0f32, 0.0f32, 0.0f32, 0.0f32);
    for (t, w) in weights.into_iter().enumerate() {
        let x = corner.x as i64 + (t & 1) as i64;
        let y = corner.y as i64 + (t >> 1) as i64;
        let kept = (pixel.taps >> t) & 1 == 1;
        let Some(h) = size
            .at(x, y)
            .filter(|_| kept)
            .and_then(|q| history.get(q))
            .filter(|h| h.frames > 0)
        else {
            continue;
        };
        colour += Vec3::from_array(h.colour) * w;
        m1 += h.moments[0] * w;
        m2 += h.moments[1] * w;
        frames += h.frames as f32 * w;
        sum += w;
    }
    (sum > 0.0).then(|| SvgfHistory {
        colour: (colour / sum).to_array(),
        moments: [m1 / sum, m2 / sum],
        frames: (frames / sum + 0.5).floor() as u32,
    })
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

#[cfg(test)]
mod tests {
    use super::*;

    const SIZE: Size = Size {
        width: 2,
        height: 2,
    };

    /// Histories of a 2×2 image: pixel `p` has colour `(p, 2p, 4p)`, moments `(p, p²)` and
    /// `p + 1` frames (values whose weighted sums below are exact in `f32`).
    fn history() -> Vec<SvgfHistory> {
        (0..4)
            .map(|p| {
                let v = p as f32;
                SvgfHistory {
                    colour: [v, 2.0 * v, 4.0 * v],
                    moments: [v, v * v],
                    frames: p + 1,
                }
            })
            .collect()
    }

    fn pixel(x: f32, y: f32, taps: u32) -> SvgfPixel {
        SvgfPixel {
            previous: [x, y],
            taps,
            ..SvgfPixel::default()
        }
    }

    /// At `(0.25, 0.5)` the taps' bilinear weights are `(3, 1, 3, 1)/8`: with every tap kept the
    /// read is the weighted mean (frames 2.25, rounded to 2); with taps 0 and 2 kept their
    /// weights are renormalised to ½ each [SVGF §4.1].
    #[test]
    fn the_footprint_blends_its_kept_taps_renormalised() {
        let h = history();
        let all = reprojected(SIZE, &pixel(0.25, 0.5, 0b1111), &h).unwrap();
        let mean = (0.0 * 3.0 + 1.0 + 2.0 * 3.0 + 3.0) / 8.0;
        assert_eq!(all.colour, [mean, 2.0 * mean, 4.0 * mean]);
        assert_eq!(all.moments, [mean, (0.0 + 1.0 + 4.0 * 3.0 + 9.0) / 8.0]);
        assert_eq!(all.frames, 2);
        let left = reprojected(SIZE, &pixel(0.25, 0.5, 0b0101), &h).unwrap();
        assert_eq!(left.colour, [1.0, 2.0, 4.0]);
        assert_eq!(left.moments, [1.0, 2.0]);
        assert_eq!(left.frames, 2);
    }

    /// The history is rejected only when no tap with a weight is kept: no tap, only taps of
    /// weight 0, or only taps without a history. Taps outside the image are never read.
    #[test]
    fn the_footprint_rejects_only_when_no_tap_is_kept() {
        let mut h = history();
        assert_eq!(reprojected(SIZE, &pixel(0.25, 0.5, 0), &h), None);
        assert_eq!(reprojected(SIZE, &pixel(0.0, 0.5, 0b1010), &h), None);
        let edge = reprojected(SIZE, &pixel(1.0, 0.0, 0b1111), &h).unwrap();
        assert_eq!(edge.colour, [1.0, 2.0, 4.0]);
        h[1].frames = 0;
        assert_eq!(reprojected(SIZE, &pixel(1.0, 0.0, 0b1111), &h), None);
        assert_eq!(
            reprojected(SIZE, &pixel(-0.5, -0.5, 0b1111), &h)
                .unwrap()
                .colour,
            [0.0; 3]
        );
    }
}
