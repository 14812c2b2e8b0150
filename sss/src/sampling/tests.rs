use super::*;
use restir::rng::{Stream, StreamKey};
use restir::stats::chi_square_gof;

/// Level of every goodness-of-fit test below.
const ALPHA: f64 = 1e-3;

fn stream(purpose: u32) -> Stream {
    StreamKey::new(0, 0, 0, purpose).stream(5)
}

/// Composite Simpson's rule of `f` over `[a, b]` with `2n` intervals.
fn simpson(f: impl Fn(f64) -> f64, a: f64, b: f64, n: usize) -> f64 {
    let h = (b - a) / (2 * n) as f64;
    let inner: f64 = (1..2 * n)
        .map(|i| f(a + i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 })
        .sum();
    (f(a) + f(b) + inner) * h / 3.0
}

// Round-trip tolerances: the random numbers are ≤ 1 and each warp and inverse is a handful of
// f32 operations (a few ulps, ~1e-7), so 1e-5 leaves two orders of margin; an angle read back
// with atan2 loses precision as the point nears the pole or centre (1e-4, and not checked
// below u₀ = 1e-6 where it is undefined). The cosine round trip keeps the 1e-3 it was written
// with: the direction is normalised and reprojected on a basis, which costs more.

/// The angle of `u` and of `back` agree modulo 1 (or the radius is too small to carry one).
fn same_angle(u: f32, back: f32, tolerance: f32) -> bool {
    let d = (u - back).abs();
    d.min(1.0 - d) < tolerance
}

/// Chi-square p-value of `n` draws from stream `purpose`, each binned by `cell`, against the
/// cell probabilities `expected` (which must sum to 1: each test derives them from its pdf).
fn chi_square_p(
    purpose: u32,
    n: usize,
    expected: &[f64],
    cell: impl Fn(&mut Stream) -> usize,
) -> f64 {
    assert!(
        (expected.iter().sum::<f64>() - 1.0).abs() < 1e-4,
        "probabilities sum to 1"
    );
    let mut s = stream(purpose);
    let mut observed = vec![0.0; expected.len()];
    for _ in 0..n {
        observed[cell(&mut s)] += 1.0;
    }
    chi_square_gof(&observed, expected, 5.0).p_value
}

#[test]
fn disk_sampling_inverts() {
    let mut s = stream(0xD15);
    for _ in 0..10_000 {
        let u = [s.next_f32(), s.next_f32()];
        let p = sample_uniform_disk(2.5, u[0], u[1]);
        assert!(p.length() <= 2.5 * (1.0 + f32::EPSILON));
        let back = invert_uniform_disk(2.5, p);
        assert!((back[0] - u[0]).abs() < 1e-5, "{u:?} → {back:?}");
        assert!(
            same_angle(u[1], back[1], 1e-4) || u[0] < 1e-6,
            "{u:?} → {back:?}"
        );
    }
}

/// Disk points binned in `r²/R²` (10 bins) × angle (8 sectors) against the probability of each
/// cell from [`uniform_disk_pdf`] times its area; N = 80 000. Negative control: `r = R·u`.
#[test]
fn disk_sampling_matches_its_pdf() {
    const N: usize = 80_000;
    const RINGS: usize = 10;
    const SECTORS: usize = 8;
    let radius = 2.5f32;
    let cell = |p: Vec2| {
        let ring =
            ((p.length_squared() / (radius * radius) * RINGS as f32) as usize).min(RINGS - 1);
        let sector =
            ((invert_uniform_disk(radius, p)[1] * SECTORS as f32) as usize).min(SECTORS - 1);
        ring * SECTORS + sector
    };
    let expected: Vec<f64> = (0..RINGS * SECTORS)
        .map(|k| {
            let r2 = |i: usize| (radius * radius) as f64 * i as f64 / RINGS as f64;
            let ring = k / SECTORS;
            let area = std::f64::consts::PI * (r2(ring + 1) - r2(ring)) / SECTORS as f64;
            uniform_disk_pdf(radius) as f64 * area
        })
        .collect();
    let p_value = |sample: &dyn Fn(f32, f32) -> Vec2| {
        chi_square_p(0xD16, N, &expected, |s| {
            cell(sample(s.next_f32(), s.next_f32()))
        })
    };
    let p = p_value(&|u, v| sample_uniform_disk(radius, u, v));
    assert!(
        p > ALPHA,
        "disk sampling: chi-square p = {p:.2e} ≤ α = {ALPHA}"
    );
    let linear = |u: f32, v: f32| sample_uniform_disk(radius, u * u, v);
    let p = p_value(&linear);
    assert!(
        p < ALPHA,
        "negative control (r = R·u) not detected: p = {p:.2e}"
    );
}

#[test]
fn cosine_sampling_inverts() {
    let mut s = stream(0xC05);
    let axis = Vec3::new(0.0, -0.6, 0.8);
    for _ in 0..10_000 {
        let u = [s.next_f32(), s.next_f32()];
        let back = invert_cosine_hemisphere(axis, sample_cosine_hemisphere(axis, u));
        assert!((back[0] - u[0]).abs() < 1e-3, "{u:?} → {back:?}");
        assert!(
            same_angle(u[1], back[1], 1e-3) || u[0] < 1e-4,
            "{u:?} → {back:?}"
        );
    }
}

/// Chi-square p-value of `n` directions from `sample` binned in `cos θ` (20 equal bins)
/// against the probabilities of [`cosine_hemisphere_pdf`], integrated numerically (Simpson,
/// 2π ∫ pdf dμ).
fn cosine_chi_square_p(sample: impl Fn(Vec3, [f32; 2]) -> Vec3, n: usize) -> f64 {
    const BINS: usize = 20;
    let axis = Vec3::new(0.0, -0.6, 0.8);
    let (t, _) = axis.any_orthonormal_pair();
    let density = |mu: f64| {
        let dir = (mu as f32) * axis + (1.0 - mu * mu).max(0.0).sqrt() as f32 * t;
        std::f64::consts::TAU * cosine_hemisphere_pdf(axis, dir) as f64
    };
    let expected: Vec<f64> = (0..BINS)
        .map(|k| {
            let a = k as f64 / BINS as f64;
            simpson(density, a, a + 1.0 / BINS as f64, 50)
        })
        .collect();
    chi_square_p(0xC06, n, &expected, |s| {
        let mu = axis.dot(sample(axis, [s.next_f32(), s.next_f32()]));
        ((mu.clamp(0.0, 1.0) * BINS as f32) as usize).min(BINS - 1)
    })
}

/// Cosine sampling against its pdf: chi-square in cos θ, 20 bins, N = 100 000, α = 1e-3.
/// Negative control: uniform-hemisphere directions (cos θ = 1 − u) against the same pdf.
#[test]
fn cosine_sampling_matches_its_pdf() {
    const N: usize = 100_000;
    let p = cosine_chi_square_p(sample_cosine_hemisphere, N);
    assert!(
        p > ALPHA,
        "cosine sampling: chi-square p = {p:.2e} ≤ α = {ALPHA} (N = {N}, 20 bins)"
    );
    let uniform = |axis: Vec3, u: [f32; 2]| {
        let (t, b) = axis.any_orthonormal_pair();
        let z = 1.0 - u[0];
        let r = (1.0 - z * z).max(0.0).sqrt();
        let (sin_phi, cos_phi) = (TAU * u[1]).sin_cos();
        r * cos_phi * t + r * sin_phi * b + z * axis
    };
    let p = cosine_chi_square_p(uniform, N);
    assert!(
        p < ALPHA,
        "negative control (uniform hemisphere) not detected: p = {p:.2e}, α = {ALPHA}"
    );
}

#[test]
fn triangle_sampling_inverts() {
    let mut s = stream(0x7A1);
    for _ in 0..10_000 {
        let u = [s.next_f32(), s.next_f32()];
        let b = sample_uniform_triangle(u);
        assert!(b.iter().all(|&x| (0.0..=1.0).contains(&x)));
        assert!((b.iter().sum::<f32>() - 1.0).abs() < 1e-6);
        let back = invert_uniform_triangle(b);
        assert!((back[0] - u[0]).abs() < 1e-5, "{u:?} → {back:?}");
        assert!(
            (back[1] - u[1]).abs() < 1e-4 || u[0] < 1e-6,
            "{u:?} → {back:?}"
        );
    }
}

/// Triangle points binned by `b0` (10 bins) and by `b2 / (b1 + b2)` (5 bins) against
/// [`uniform_triangle_pdf`] times each cell's area: `{b0 ≥ a}` is the triangle scaled by
/// `1 − a` about the opposite edge, area `A (1 − a)²`, split evenly along that edge.
/// N = 50 000. Negative control: `b0 = 1 − u₀` (too much mass near `v0`).
#[test]
fn triangle_sampling_matches_its_pdf() {
    const N: usize = 50_000;
    const ROWS: usize = 10;
    const COLUMNS: usize = 5;
    let vertices = [
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(2.0, 0.0, 0.0),
        Vec3::new(0.5, 1.5, 0.0),
    ];
    let area = 0.5 * 2.0 * 1.5;
    assert!((uniform_triangle_pdf(vertices) as f64 - 1.0 / area).abs() < 1e-6);
    let cell = |b: [f32; 3]| {
        let row = ((b[0] * ROWS as f32) as usize).min(ROWS - 1);
        let column = ((invert_uniform_triangle(b)[1] * COLUMNS as f32) as usize).min(COLUMNS - 1);
        row * COLUMNS + column
    };
    let expected: Vec<f64> = (0..ROWS * COLUMNS)
        .map(|k| {
            let above = |a: f64| area * (1.0 - a) * (1.0 - a);
            let row = (k / COLUMNS) as f64 / ROWS as f64;
            let row_area = above(row) - above(row + 1.0 / ROWS as f64);
            uniform_triangle_pdf(vertices) as f64 * row_area / COLUMNS as f64
        })
        .collect();
    let p_value = |sample: &dyn Fn([f32; 2]) -> [f32; 3]| {
        chi_square_p(0x7A2, N, &expected, |s| {
            cell(sample([s.next_f32(), s.next_f32()]))
        })
    };
    let p = p_value(&sample_uniform_triangle);
    assert!(
        p > ALPHA,
        "triangle sampling: chi-square p = {p:.2e} ≤ α = {ALPHA}"
    );
    let linear = |u: [f32; 2]| [1.0 - u[0], u[0] * (1.0 - u[1]), u[0] * u[1]];
    let p = p_value(&linear);
    assert!(
        p < ALPHA,
        "negative control (b0 = 1 − u) not detected: p = {p:.2e}"
    );
}

#[test]
fn truncated_exponential_inverts_and_stays_in_range() {
    let mut s = stream(0xE1);
    for (sigma_t, d) in [(2.0f32, 0.7f32), (0.3, 5.0), (4.0, f32::INFINITY)] {
        for _ in 0..10_000 {
            let u = s.next_f32();
            let t = sample_truncated_exponential(sigma_t, d, u);
            assert!((0.0..=d).contains(&t), "σt {sigma_t}, d {d}: t = {t}");
            let back = invert_truncated_exponential(sigma_t, d, t);
            assert!((back - u).abs() < 1e-5, "σt {sigma_t}, d {d}: {u} → {back}");
        }
    }
}

/// The truncated exponential's density integrates to 1 over `(0, d)` (Simpson, error far
/// below 1e-6 for this smooth integrand), and its samples binned in `t` (20 bins,
/// N = 100 000) match it; negative control: the untruncated density's inverse CDF clamped to
/// `d` piles mass at the end.
#[test]
fn truncated_exponential_matches_its_pdf() {
    const N: usize = 100_000;
    const BINS: usize = 20;
    let (sigma_t, d) = (2.0f32, 0.7f32);
    let pdf = |t: f64| truncated_exponential_pdf(sigma_t, d, t as f32) as f64;
    assert!((simpson(pdf, 0.0, d as f64, 500) - 1.0).abs() < 1e-6);
    let expected: Vec<f64> = (0..BINS)
        .map(|k| {
            let h = d as f64 / BINS as f64;
            simpson(pdf, k as f64 * h, (k + 1) as f64 * h, 20)
        })
        .collect();
    let p_value = |sample: &dyn Fn(f32) -> f32| {
        chi_square_p(0xE2, N, &expected, |s| {
            ((sample(s.next_f32()) / d * BINS as f32) as usize).min(BINS - 1)
        })
    };
    let p = p_value(&|u| sample_truncated_exponential(sigma_t, d, u));
    assert!(
        p > ALPHA,
        "truncated exponential: chi-square p = {p:.2e} ≤ α = {ALPHA}"
    );
    let clamped = |u: f32| sample_truncated_exponential(sigma_t, f32::INFINITY, u).min(d);
    let p = p_value(&clamped);
    assert!(
        p < ALPHA,
        "negative control (clamped exponential) not detected: p = {p:.2e}"
    );
}
