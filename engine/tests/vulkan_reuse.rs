//! Parity of the reuse GLSL (reservoirs, MIS, shifts, temporal and spatial passes) with
//! `restir` / `shifts` / `engine::reuse`, through the Vulkan backend on whatever device it
//! chooses (Mesa lavapipe in CI).
//!
//! Without Vulkan each test prints why it is skipped and passes, unless
//! `RESHIFT_REQUIRE_VULKAN=1`, which makes it fail.

use bytemuck::{Pod, Zeroable};
use engine::PixelReservoir;
use engine::candidates;
use engine::contract::ExchangeStatus;
use engine::reciprocal::{self, Exchanged};
use engine::reuse::{self, PassInput, Previous, Reused};
use engine::vulkan::testing::{Tally, kernel_or_skip, rel_error, scaled_error};
use engine::vulkan::{
    Buffer, Context, FrameParams, GpuPixel, GpuScene, Kernel, PassParams, SPATIAL, Shader,
    TEMPORAL, groups_for,
};
use restir::mis::{MAX_DOMAINS, MisKind};
use restir::resample::ResampleCode;
use restir::reservoir::{InvalidCandidate, Ris};
use restir::rng::StreamKey;
use restir::shift::Domain;
use shifts::ShiftKind;
use shifts::SssSample;
use shifts::Target;
use shifts::preset::{PassSpec, Preset, RadiusRule, Shade, TEMPORAL_CAP};
use sss::scene::{GBuffer, Scene};

/// `parity_reuse.glsl`: bindings 0–10 scene and pass inputs of the shift modes, 11 cases,
/// 12 results. Push constants: [`ReuseParams`].
const PARITY_REUSE: Shader = Shader::new("parity_reuse", 13, 16);

/// Push constants of [`PARITY_REUSE`].
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
struct ReuseParams {
    mode: u32,
    count: u32,
    pad: [u32; 2],
}

/// Mode 0 of `parity_reuse.glsl`: one MIS weight.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct MisCase {
    targets: [f32; MAX_DOMAINS],
    confidences: [f32; MAX_DOMAINS],
    n: u32,
    kind: u32,
    i: u32,
    pad: u32,
}

/// Mode 1 of `parity_reuse.glsl`: up to 8 candidates streamed through `Ris`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
struct RisCase {
    target: [f32; 8],
    weight: [f32; 8],
    confidence: [f32; 8],
    u: [f32; 8],
    count: u32,
    skip: u32,
    pad: [u32; 2],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct RisResult {
    reservoir: PixelReservoir,
    error: u32,
    selected: u32,
    pad: [u32; 2],
}

const MIS_KINDS: [MisKind; 4] = [
    MisKind::Gbh,
    MisKind::Pairwise,
    MisKind::DefensivePairwise,
    MisKind::ConfidenceOnly,
];

/// Runs `parity_reuse.glsl` in `mode` over `cases`, with the scene and pass buffers 0–10 given
/// (placeholders for the modes that do not read them), and returns the results.
fn run_parity<C: Pod, R: Pod + Zeroable>(
    context: &mut Context,
    kernel: &Kernel,
    inputs: &[&Buffer],
    mode: u32,
    cases: &[C],
) -> Vec<R> {
    let case_buffer = Buffer::from_slice(context, cases).unwrap();
    let results = Buffer::zeroed(context, cases.len() * size_of::<R>()).unwrap();
    let mut buffers: Vec<&Buffer> = inputs.to_vec();
    buffers.push(&case_buffer);
    buffers.push(&results);
    let params = ReuseParams {
        mode,
        count: cases.len() as u32,
        pad: [0; 2],
    };
    context
        .dispatch(
            kernel,
            &buffers,
            bytemuck::bytes_of(&params),
            [groups_for(params.count, PARITY_REUSE.local_size), 1, 1],
        )
        .unwrap();
    results.read::<R>().unwrap()
}

/// Eleven 4-byte placeholder buffers for bindings 0–10.
fn placeholders(context: &Context) -> Vec<Buffer> {
    (0..11)
        .map(|_| Buffer::zeroed(context, 16).unwrap())
        .collect()
}

/// Random MIS inputs as in `restir::mis`'s tests: 1–16 domains, 30% zero targets, some zero
/// confidences.
fn mis_cases() -> Vec<MisCase> {
    let mut rng = StreamKey::new(0, 0, 0, 0x315).stream(17);
    let mut cases = Vec::new();
    for trial in 0..600 {
        let n = 1 + trial % MAX_DOMAINS;
        let mut targets = [0.0f32; MAX_DOMAINS];
        let mut confidences = [0.0f32; MAX_DOMAINS];
        targets[0] = if trial % 37 == 0 {
            0.0
        } else {
            0.01 + rng.next_f32()
        };
        confidences[0] = 0.5 + 4.0 * rng.next_f32();
        for j in 1..n {
            targets[j] = if rng.next_f32() < 0.3 {
                0.0
            } else {
                5.0 * rng.next_f32()
            };
            confidences[j] = if rng.next_f32() < 0.1 {
                0.0
            } else {
                40.0 * rng.next_f32()
            };
        }
        for (kind, _) in MIS_KINDS.iter().enumerate() {
            for i in 0..n {
                cases.push(MisCase {
                    targets,
                    confidences,
                    n: n as u32,
                    kind: kind as u32,
                    i: i as u32,
                    pad: 0,
                });
            }
        }
    }
    cases
}

fn cpu_mis(case: &MisCase) -> (f32, bool) {
    let scheme = MIS_KINDS[case.kind as usize].scheme();
    let n = case.n as usize;
    let i = case.i as usize;
    (
        scheme.weight(i, &case.targets[..n], &case.confidences[..n]),
        scheme.needs_all_targets(i),
    )
}

/// Every MIS weight of the four schemes on 600 random steps (1–16 domains, every index) is
/// bit-identical on the GPU: the formulas use only + − × ÷, which lavapipe rounds like the CPU,
/// and the twin keeps the CPU's operation order (`precise`, no fused multiply-add). Negative
/// control: the same GPU weights compared with the CPU's under the next scheme's index (a wrong
/// `mis` push constant) differ in most cases.
#[test]
fn mis_weights_are_bit_identical() {
    let Some((mut context, kernel)) = kernel_or_skip("mis parity", PARITY_REUSE) else {
        return;
    };
    let inputs = placeholders(&context);
    let inputs: Vec<&Buffer> = inputs.iter().collect();
    let cases = mis_cases();
    let gpu: Vec<[f32; 2]> = run_parity(&mut context, &kernel, &inputs, 0, &cases);
    let mut wrong_kind_equal = 0usize;
    for (case, got) in cases.iter().zip(&gpu) {
        let (weight, needs_all) = cpu_mis(case);
        assert_eq!(
            (got[0].to_bits(), got[1] == 1.0),
            (weight.to_bits(), needs_all),
            "{:?} m_{} with {} domains: GPU {} vs CPU {weight}",
            MIS_KINDS[case.kind as usize],
            case.i,
            case.n,
            got[0]
        );
        let wrong = MisCase {
            kind: (case.kind + 1) % MIS_KINDS.len() as u32,
            ..*case
        };
        wrong_kind_equal += usize::from(cpu_mis(&wrong).0.to_bits() == got[0].to_bits());
    }
    let n = cases.len();
    eprintln!(
        "mis parity: {n} weights bit-identical; control: {wrong_kind_equal} of {n} equal under the wrong scheme"
    );
    assert!(
        wrong_kind_equal * 2 < n,
        "negative control: {wrong_kind_equal} of {n} weights also match the wrong scheme"
    );
}

/// Random candidate streams with valid and invalid inputs (NaN, ∞, negative weights, targets
/// and confidences, skipped candidates, overflowing `w_sum`).
fn ris_cases() -> Vec<RisCase> {
    let mut rng = StreamKey::new(0, 0, 0, 0x415).stream(23);
    let specials = [f32::NAN, f32::INFINITY, -1.0, 0.0, 3.0e38];
    (0..4000)
        .map(|trial| {
            let mut case = RisCase {
                count: 1 + (rng.next_u32() % 8),
                ..RisCase::default()
            };
            for j in 0..8 {
                let mut value = |scale: f32| {
                    if trial % 4 == 0 && rng.next_f32() < 0.08 {
                        specials[(rng.next_u32() % 5) as usize]
                    } else {
                        scale * rng.next_f32()
                    }
                };
                case.target[j] = value(2.0);
                case.weight[j] = value(5.0);
                case.confidence[j] = value(3.0);
                case.u[j] = rng.next_f32();
                if rng.next_f32() < 0.15 {
                    case.skip |= 1 << j;
                }
            }
            case
        })
        .collect()
}

/// The code `reservoir.glsl` writes for an `InvalidCandidate`.
fn invalid_code(error: InvalidCandidate) -> u32 {
    match error {
        InvalidCandidate::Weight(_) => ResampleCode::InvalidWeight,
        InvalidCandidate::Target(_) => ResampleCode::InvalidTarget,
        InvalidCandidate::Confidence(_) => ResampleCode::InvalidConfidence,
        InvalidCandidate::Ucw(_) => ResampleCode::InvalidUcw,
    }
    .code()
}

/// The CPU's reservoir and error code for `case` (the driver stops at the first error).
fn cpu_ris(case: &RisCase) -> (PixelReservoir, u32) {
    let mut ris = Ris::new();
    for j in 0..case.count as usize {
        let mut y = SssSample::zeroed();
        bytemuck::cast_slice_mut::<SssSample, u32>(std::slice::from_mut(&mut y))[7] = j as u32;
        let result = if case.skip & (1 << j) != 0 {
            ris.skip(case.confidence[j])
        } else {
            ris.update(
                y,
                case.target[j],
                case.weight[j],
                case.confidence[j],
                case.u[j],
            )
        };
        if let Err(e) = result {
            return (PixelReservoir::from(&ris.finish()), invalid_code(e));
        }
    }
    (PixelReservoir::from(&ris.finish()), 0)
}

/// Reservoir streaming of 4000 random candidate lists (a quarter with invalid inputs) gives the
/// CPU's reservoir byte for byte (selected candidate, `W`, `c`) and the same error code: the
/// update uses + × ÷ and comparisons only. Negative control: the same results compared with
/// the CPU run on selection numbers `u` shifted by one case differ in most selections.
#[test]
fn reservoir_streaming_is_bit_identical() {
    let Some((mut context, kernel)) = kernel_or_skip("reservoir parity", PARITY_REUSE) else {
        return;
    };
    let inputs = placeholders(&context);
    let inputs: Vec<&Buffer> = inputs.iter().collect();
    let cases = ris_cases();
    let gpu: Vec<RisResult> = run_parity(&mut context, &kernel, &inputs, 1, &cases);
    let (mut errors, mut control_equal, mut multi) = (0usize, 0usize, 0usize);
    for (k, (case, got)) in cases.iter().zip(&gpu).enumerate() {
        let (want, code) = cpu_ris(case);
        assert_eq!(
            (bytemuck::bytes_of(&got.reservoir), got.error, got.selected),
            (bytemuck::bytes_of(&want), code, want.y.prim()),
            "case {k}: {case:?}"
        );
        errors += usize::from(code != 0);
        if code == 0 && case.count > 2 {
            multi += 1;
            let shifted = RisCase {
                u: cases[(k + 1) % cases.len()].u,
                ..*case
            };
            control_equal += usize::from(cpu_ris(&shifted).0.y == got.reservoir.y);
        }
    }
    eprintln!(
        "reservoir parity: {} streams identical ({errors} with an error code); control: {control_equal} of {multi} equal with other u",
        cases.len()
    );
    assert!(errors > 100, "only {errors} cases exercised an error");
    assert!(
        control_equal * 10 < multi * 9,
        "negative control: {control_equal} of {multi} selections unchanged by other u"
    );
}

// ------------------------------------------------------------------------- shifts and passes

const SEED: u64 = 0x5EED_0000_0000_0005;
const SIZE: u32 = 32;
const SCENES: [&str; 2] = ["bumpy", "half-shadow"];

fn scene(name: &str) -> Scene {
    let mut scene = Scene::builtin(name).unwrap();
    scene.camera = scene.camera.with_resolution(SIZE, SIZE);
    scene
}

/// The CPU candidates pass (pass 0, M = 1, shared light, shadow-tested) of every pixel: the
/// reservoirs the reuse passes read.
fn canonical(scene: &Scene, gbuffer: &GBuffer, seed: u64) -> Vec<PixelReservoir> {
    let input = pass_input(scene, gbuffer, &[], 0, seed);
    let mut hits = Vec::new();
    (0..gbuffer.pixels.len() as u32)
        .map(|pixel| {
            let Some((domain, _)) = input.domain(pixel) else {
                return PixelReservoir::empty();
            };
            let (mut r, _) = candidates::generate(&domain, 1, true, seed, &mut hits).unwrap();
            candidates::shadow_test(&domain, &mut r);
            PixelReservoir::from(&r)
        })
        .collect()
}

fn pass_input<'a>(
    scene: &'a Scene,
    gbuffer: &'a GBuffer,
    reservoirs: &'a [PixelReservoir],
    pass: u32,
    seed: u64,
) -> PassInput<'a> {
    PassInput {
        scene,
        gbuffer,
        reservoirs,
        pass,
        seed,
        collect_diagnostics: true,
        target: Target::Luminance,
    }
}

fn gpu_pixels(gbuffer: &GBuffer) -> Vec<GpuPixel> {
    gbuffer
        .pixels
        .iter()
        .map(|g| GpuPixel::from_cpu(g.as_ref()))
        .collect()
}

/// The integer fields of a stored sample that must match exactly.
fn sample_key(s: &SssSample) -> (u32, u32, Option<usize>, Option<u32>, u32) {
    (
        s.object(),
        s.prim(),
        s.technique().map(|t| t.index()),
        s.index(),
        s.light(),
    )
}

/// Compares the float fields of two samples with equal integer fields; true if one exceeds
/// its bound.
fn compare_sample_floats(tally: &mut Tally, got: &SssSample, want: &SssSample) -> bool {
    let mut beyond = tally.float(
        "u_radius, u_angle",
        rel_error(got.u_radius(), want.u_radius()).max(rel_error(got.u_angle(), want.u_angle())),
    );
    beyond |= tally.float("p_disk", rel_error(got.p_disk(), want.p_disk()));
    beyond |= tally.float(
        "bary",
        scaled_error(&got.bary().to_array(), &want.bary().to_array(), 1.0),
    );
    let scale = want.x3().abs().max_element().max(1.0);
    beyond |= tally.float(
        "x3",
        scaled_error(&got.x3().to_array(), &want.x3().to_array(), scale),
    );
    beyond
}

/// `parity_reuse.glsl`'s `ShiftCase`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
struct ShiftCase {
    src: u32,
    dst: u32,
    kind: u32,
    pass: u32,
}

/// `parity_reuse.glsl`'s `ShiftResult` (80 bytes). `Shift::target_from` is the forward shift's
/// target times its Jacobian; the pass test covers its GLSL use.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct ShiftResult {
    y: SssSample,
    jacobian: f32,
    fail: u32,
    target: f32,
    pad: u32,
}

/// Pairs (src, dst) of translucent pixels, src holding a sample, dst within ±6 px (drawn from a
/// fixed stream), for every shift kind.
fn shift_cases(input: &PassInput, count: usize) -> Vec<ShiftCase> {
    let width = input.gbuffer.width as i32;
    let height = input.gbuffer.height as i32;
    let mut rng = StreamKey::new(0, 0, 0, 0x5417).stream(29);
    let mut cases = Vec::new();
    let mut pairs = 0;
    for _ in 0..count * 40 {
        if pairs == count {
            break;
        }
        let src = rng.next_u32() % (width * height) as u32;
        let dx = (rng.next_u32() % 13) as i32 - 6;
        let dy = (rng.next_u32() % 13) as i32 - 6;
        let (qx, qy) = ((src as i32 % width) + dx, (src as i32 / width) + dy);
        if qx < 0 || qy < 0 || qx >= width || qy >= height {
            continue;
        }
        let dst = (qy * width + qx) as u32;
        if input.reservoirs[src as usize].has_sample == 0
            || input.domain(src).is_none()
            || input.domain(dst).is_none()
        {
            continue;
        }
        pairs += 1;
        for kind in 0..ShiftKind::ALL.len() as u32 {
            cases.push(ShiftCase {
                src,
                dst,
                kind,
                pass: input.pass,
            });
        }
    }
    cases
}

/// The CPU's shift of `case` (with the shift built for dst's material, as the passes build it).
fn cpu_shift(input: &PassInput, case: &ShiftCase) -> ShiftResult {
    let (src, _) = input.domain(case.src).unwrap();
    let (dst, _) = input.domain(case.dst).unwrap();
    let x = input.reservoirs[case.src as usize].y;
    ShiftKind::ALL[case.kind as usize].with_shift(dst.material(), |shift| {
        match shift.shift(&x, &src, &dst) {
            Ok(s) => ShiftResult {
                y: s.y,
                jacobian: s.jacobian,
                fail: 0,
                target: dst.target(&s.y),
                pad: 0,
            },
            Err(f) => ShiftResult {
                y: SssSample::zeroed(),
                jacobian: 0.0,
                fail: f.code(),
                target: 0.0,
                pad: 0,
            },
        }
    })
}

/// Bounds of the shift comparison. The GPU's cos/sin (probe ray, replay), exp (Burley profile
/// in p_disk, the target and inversion's CDF) and atan (inversion's u_angle) differ from the
/// CPU's by a few ulp, which moves a replayed y2 along its triangle and changes densities by
/// ~1e-6 relative; the Jacobian and the targets are ratios and products of a handful of these.
/// x3 is never recomputed by a shift: exact. Seen (bumpy, half-shadow): Jacobian 5.2e-6, target
/// 4.9e-6 (against the floor of [`target_error`]), u 2.1e-5, p_disk 5.2e-6, bary 6.0e-6; bound
/// 1e-4 for each.
const SHIFT_BOUNDS: [(&str, f64); 6] = [
    ("jacobian", 1e-4),
    ("target", 1e-4),
    ("u_radius, u_angle", 1e-4),
    ("p_disk", 1e-4),
    ("bary", 1e-4),
    ("x3", 0.0),
];

/// At most this fraction of shifts may differ in the fail code or an integer field of y: a
/// replayed chord whose hit count, or a technique pick by γ, sits within an ulp of a decision
/// boundary (t of a hit at the chord's end, `threshold < cumulative`).
const SHIFT_MISMATCH_FRACTION: f64 = 1e-2;

/// The target's error against `max(|want|, floor)`: `p̂` carries `max(0, n2·ωi)` with the
/// shading normal n2 of the GPU's renormalised corner normals (`GpuScene`), an ulp off the
/// CPU's, so near grazing its *relative* error grows without bound; `floor` is 1% of the run's
/// mean non-zero target.
fn target_error(got: f32, want: f32, floor: f32) -> f64 {
    (got as f64 - want as f64).abs() / (want.abs().max(floor) as f64)
}

/// 1% of the mean of the non-zero CPU targets.
fn target_floor(cpu: &[ShiftResult]) -> f32 {
    let nonzero: Vec<f64> = cpu
        .iter()
        .filter(|r| r.target > 0.0)
        .map(|r| r.target as f64)
        .collect();
    (0.01 * nonzero.iter().sum::<f64>() / nonzero.len().max(1) as f64) as f32
}

fn compare_shifts(cpu: &[ShiftResult], gpu: &[ShiftResult], tally: &mut Tally) {
    let floor = target_floor(cpu);
    for (want, got) in cpu.iter().zip(gpu) {
        tally.compared += 1;
        let key = |r: &ShiftResult| (r.fail, (r.fail == 0).then(|| sample_key(&r.y)));
        if key(want) != key(got) {
            tally.mismatched += 1;
            continue;
        }
        let mut beyond = false;
        if want.fail == 0 {
            beyond |= tally.float("jacobian", rel_error(got.jacobian, want.jacobian));
            beyond |= tally.float("target", target_error(got.target, want.target, floor));
            beyond |= compare_sample_floats(tally, &got.y, &want.y);
        }
        tally.beyond_bounds += usize::from(beyond);
    }
}

/// Function-level parity of every shift kind (negative controls included) on 150 pixel pairs
/// each of `bumpy` and `half-shadow` (32×32, frame 0, pass 1, CPU G-buffer and CPU canonical
/// reservoirs as inputs): fail codes and the integer fields of `T(x)` equal up to
/// [`SHIFT_MISMATCH_FRACTION`], Jacobian, targets and sample floats within [`SHIFT_BOUNDS`].
/// Negative controls: the GPU run with every kind index moved to the next kind, and with
/// another run seed (γ of inversion and the deferred pick change), must be rejected.
#[test]
fn every_shift_kind_matches_the_cpu() {
    let Some((mut context, kernel)) = kernel_or_skip("shift parity", PARITY_REUSE) else {
        return;
    };
    for name in SCENES {
        let scene = scene(name);
        let gbuffer = GBuffer::render(&scene, 0);
        let reservoirs = canonical(&scene, &gbuffer, SEED);
        let input = pass_input(&scene, &gbuffer, &reservoirs, 1, SEED);
        let cases = shift_cases(&input, 150);
        assert_eq!(
            cases.len(),
            150 * ShiftKind::ALL.len(),
            "{name}: too few pairs"
        );
        let cpu: Vec<ShiftResult> = cases.iter().map(|c| cpu_shift(&input, c)).collect();
        let gpu_scene = GpuScene::upload(&context, &scene).unwrap();
        let pixels = Buffer::from_slice(&context, &gpu_pixels(&gbuffer)).unwrap();
        let stored = Buffer::from_slice(&context, &reservoirs).unwrap();
        let mut run = |seed: u64, cases: &[ShiftCase]| {
            let frame = FrameParams::new(&scene, 0, None, seed)
                .buffer(&context)
                .unwrap();
            let mut inputs: Vec<&Buffer> = gpu_scene.buffers().to_vec();
            inputs.extend([&frame, &pixels, &stored]);
            run_parity::<_, ShiftResult>(&mut context, &kernel, &inputs, 2, cases)
        };
        let gpu = run(SEED, &cases);
        let mut tally = Tally::new(&SHIFT_BOUNDS);
        compare_shifts(&cpu, &gpu, &mut tally);
        let per_kind: Vec<String> = ShiftKind::ALL
            .iter()
            .enumerate()
            .map(|(k, kind)| {
                let ok = cpu
                    .iter()
                    .zip(&cases)
                    .filter(|(r, c)| c.kind == k as u32 && r.fail == 0)
                    .count();
                format!("{} {ok}", kind.name())
            })
            .collect();
        eprintln!(
            "shift parity, {name}: {} shifts, {} mismatched ({:.2e}), {} beyond bounds; worst {:?}; successes per kind: {}",
            tally.compared,
            tally.mismatched,
            tally.mismatch_fraction(),
            tally.beyond_bounds,
            tally.worst,
            per_kind.join(", ")
        );
        assert!(
            tally.mismatch_fraction() <= SHIFT_MISMATCH_FRACTION,
            "{name}: {} of {} shifts differ in fail code or integer fields (allowed {SHIFT_MISMATCH_FRACTION})",
            tally.mismatched,
            tally.compared
        );
        assert_eq!(
            tally.beyond_bounds, 0,
            "{name}: float errors beyond SHIFT_BOUNDS; worst {:?}",
            tally.worst
        );
        let moved: Vec<ShiftCase> = cases
            .iter()
            .map(|c| ShiftCase {
                kind: (c.kind + 1) % ShiftKind::ALL.len() as u32,
                ..*c
            })
            .collect();
        let mut wrong_kind = Tally::new(&SHIFT_BOUNDS);
        compare_shifts(&cpu, &run(SEED, &moved), &mut wrong_kind);
        let random: Vec<usize> = (0..cases.len())
            .filter(|&i| {
                matches!(
                    ShiftKind::ALL[cases[i].kind as usize],
                    ShiftKind::InvertingExact | ShiftKind::InvertingDeferred
                ) && cpu[i].fail == 0
            })
            .collect();
        let wrong_seed = run(SEED + 1, &cases);
        let mut seeded = Tally::new(&SHIFT_BOUNDS);
        compare_shifts(
            &random.iter().map(|&i| cpu[i]).collect::<Vec<_>>(),
            &random.iter().map(|&i| wrong_seed[i]).collect::<Vec<_>>(),
            &mut seeded,
        );
        eprintln!(
            "shift parity, {name}: controls rejected {:.3} (kind + 1), {:.3} (seed + 1, {} inversions)",
            wrong_kind.rejected_fraction(),
            seeded.rejected_fraction(),
            random.len()
        );
        assert!(
            wrong_kind.rejected_fraction() > 10.0 * SHIFT_MISMATCH_FRACTION,
            "{name}: negative control (kind + 1) undetected"
        );
        assert!(
            seeded.rejected_fraction() > 10.0 * SHIFT_MISMATCH_FRACTION,
            "{name}: negative control (seed + 1) undetected"
        );
    }
}

/// `parity_reuse.glsl` mode 4: slot `slot` of pass `pass` at `pixel`, shift kind `kind`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct ExchangeCase {
    pixel: u32,
    slot: u32,
    pass: u32,
    kind: u32,
    radius: f32,
    pad: [u32; 3],
}

/// `exchange_send`'s status (`EXCHANGE_*` of `engine/glsl/include/exchange.glsl`) and values
/// (`y`, `J`, `p̂_partner(y)`, `p̂_own(x)`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct ExchangeResult {
    y: SssSample,
    jacobian: f32,
    target: f32,
    source_target: f32,
    status: u32,
    pad: [u32; 3],
}

/// The `EXCHANGE_*` codes.
const UNTAKEN: u32 = ExchangeStatus::Untaken.code();
const UNSHIFTED: u32 = ExchangeStatus::Unshifted.code();
const SENT: u32 = ExchangeStatus::Sent.code();
const FAILED: u32 = ExchangeStatus::Failed.code();

/// The CPU's [`Exchanged`] as `exchange_send` encodes it.
fn exchange_result(sent: &Exchanged) -> ExchangeResult {
    let (status, y, jacobian, target, source_target) = match *sent {
        Exchanged::Untaken => (UNTAKEN, SssSample::zeroed(), 0.0, 0.0, 0.0),
        Exchanged::Unshifted => (UNSHIFTED, SssSample::zeroed(), 0.0, 0.0, 0.0),
        Exchanged::Sent {
            shifted,
            target,
            source_target,
        } => (SENT, shifted.y, shifted.jacobian, target, source_target),
        Exchanged::Failed(fail) => (
            FAILED | fail.code() << 8,
            SssSample::zeroed(),
            0.0,
            0.0,
            0.0,
        ),
    };
    ExchangeResult {
        y,
        jacobian,
        target,
        source_target,
        status,
        pad: [0; 3],
    }
}

/// Compares exchanged entries as shifts: the status (and `y`'s integer fields where sent) must
/// match, `J`, both targets and `y`'s floats stay within [`SHIFT_BOUNDS`]. A failure matches a
/// failure whatever its reason, and a GPU shift sent with `p̂_partner(y) = 0` matches a CPU
/// failure: the CPU shifts with `Shift::shift_supported`, which may fail with any reason where
/// `p̂_dst = 0` (its contract; resampling gives such an input weight 0 either way), while
/// `shift_shift` reports its first failed check.
fn compare_exchanged(cpu: &[ExchangeResult], gpu: &[ExchangeResult], tally: &mut Tally) {
    let class = |r: &ExchangeResult| r.status & 0xFF;
    let as_shift = |r: &ExchangeResult, status: u32, target: f32| ShiftResult {
        y: r.y,
        jacobian: r.jacobian,
        fail: if status == SENT { 0 } else { status | 0x100 },
        target,
        pad: 0,
    };
    let (mut want, mut got, mut want_own, mut got_own) = (vec![], vec![], vec![], vec![]);
    for (c, g) in cpu.iter().zip(gpu) {
        let unsupported = class(c) == FAILED && class(g) == SENT && g.target == 0.0;
        let g_class = if unsupported { FAILED } else { class(g) };
        want.push(as_shift(c, class(c), c.target));
        got.push(as_shift(g, g_class, g.target));
        want_own.push(as_shift(c, class(c), c.source_target));
        got_own.push(as_shift(g, g_class, g.source_target));
    }
    compare_shifts(&want, &got, tally);
    let mut own = Tally::new(&SHIFT_BOUNDS);
    compare_shifts(&want_own, &got_own, &mut own);
    tally.beyond_bounds += own.beyond_bounds;
    if let Some(&(_, e)) = own.worst.iter().find(|(n, _)| *n == "target") {
        tally.float("target", e);
    }
}

/// Phase 1 of a reciprocal spatial pass (`engine::reciprocal::shift_to_partners`; GLSL twin
/// `engine/glsl/include/exchange.glsl`) on `bumpy` and `half-shadow` (32×32, frame 0, pass 1,
/// CPU canonical reservoirs, the CPU's frame radius): what every translucent pixel sends its
/// partner of each of 4 slots, for every shift kind. Statuses (see [`compare_exchanged`]) and
/// `y`'s integer fields equal up to [`SHIFT_MISMATCH_FRACTION`], `J`, `p̂_partner(y)`, `p̂_own(x)` and `y`'s floats within
/// [`SHIFT_BOUNDS`], as for single shifts. Negative control: the GPU's entries of the next slot
/// must be rejected.
#[test]
fn reciprocal_exchange_matches_the_cpu() {
    let Some((mut context, kernel)) = kernel_or_skip("exchange parity", PARITY_REUSE) else {
        return;
    };
    const SLOTS: u32 = 4;
    for name in SCENES {
        let scene = scene(name);
        let gbuffer = GBuffer::render(&scene, 0);
        let reservoirs = canonical(&scene, &gbuffer, SEED);
        let input = pass_input(&scene, &gbuffer, &reservoirs, 1, SEED);
        let domains = reciprocal::domains(&input);
        let radius = reciprocal::frame_radius(&input, &domains, RadiusRule::Clamped);
        let pairings = reciprocal::pairings(&input, radius, SLOTS);
        let (mut cases, mut cpu) = (Vec::new(), Vec::new());
        let mut sent = [Exchanged::Untaken; SLOTS as usize];
        for (kind, shift) in ShiftKind::ALL.iter().enumerate() {
            for pixel in 0..gbuffer.pixels.len() as u32 {
                if domains[pixel as usize].is_none() {
                    continue;
                }
                reciprocal::shift_to_partners(
                    &input, &domains, &pairings, *shift, pixel, &mut sent,
                );
                for slot in 0..SLOTS {
                    cases.push(ExchangeCase {
                        pixel,
                        slot,
                        pass: 1,
                        kind: kind as u32,
                        radius,
                        pad: [0; 3],
                    });
                    cpu.push(exchange_result(&sent[slot as usize]));
                }
            }
        }
        let gpu_scene = GpuScene::upload(&context, &scene).unwrap();
        let pixels = Buffer::from_slice(&context, &gpu_pixels(&gbuffer)).unwrap();
        let stored = Buffer::from_slice(&context, &reservoirs).unwrap();
        let frame = FrameParams::new(&scene, 0, None, SEED)
            .buffer(&context)
            .unwrap();
        let mut inputs: Vec<&Buffer> = gpu_scene.buffers().to_vec();
        inputs.extend([&frame, &pixels, &stored]);
        let gpu: Vec<ExchangeResult> = run_parity(&mut context, &kernel, &inputs, 4, &cases);
        let mut tally = Tally::new(&SHIFT_BOUNDS);
        compare_exchanged(&cpu, &gpu, &mut tally);
        let count = |status: u32| cpu.iter().filter(|r| r.status & 0xFF == status).count();
        let next_slot: Vec<ExchangeResult> = gpu
            .chunks(SLOTS as usize)
            .flat_map(|slots| (0..slots.len()).map(move |s| slots[(s + 1) % slots.len()]))
            .collect();
        let mut control = Tally::new(&SHIFT_BOUNDS);
        compare_exchanged(&cpu, &next_slot, &mut control);
        eprintln!(
            "exchange parity, {name}: radius {radius} px, {} entries ({} untaken, {} unshifted, \
             {} sent, {} failed), {} mismatched ({:.2e}), {} beyond bounds; worst {:?}; \
             control (next slot) rejected {:.3}",
            tally.compared,
            count(UNTAKEN),
            count(UNSHIFTED),
            count(SENT),
            count(FAILED),
            tally.mismatched,
            tally.mismatch_fraction(),
            tally.beyond_bounds,
            tally.worst,
            control.rejected_fraction()
        );
        assert!(
            tally.mismatch_fraction() <= SHIFT_MISMATCH_FRACTION,
            "{name}: {} of {} entries differ in status or integer fields",
            tally.mismatched,
            tally.compared
        );
        assert_eq!(tally.beyond_bounds, 0, "{name}: worst {:?}", tally.worst);
        assert!(
            control.rejected_fraction() > 10.0 * SHIFT_MISMATCH_FRACTION,
            "{name}: negative control (next slot) undetected"
        );
    }
}

/// One reuse pass configuration of the registered presets.
#[derive(Clone, Copy, Debug)]
struct PassCase {
    spec: PassSpec,
    /// The pass's index in its preset.
    pass: u32,
}

/// The frame radius of a reciprocal spatial pass (`engine::reciprocal::frame_radius` with the
/// clamped rule; GLSL twin `engine/glsl/include/frame_radius.glsl`) on both scenes at 192×192
/// (at [`SIZE`] every radius clamps to 5 px), frames 0 and 5, passes 1 and 2: bit-identical.
/// Negative controls: the mean accumulated in f32, and the mean over the translucent pixels of
/// the frame before (another camera pose), differ from it.
#[test]
fn frame_radius_is_bit_identical() {
    let Some((mut context, kernel)) = kernel_or_skip("frame radius parity", PARITY_REUSE) else {
        return;
    };
    let placeholder = Buffer::zeroed(&context, 16).unwrap();
    for name in SCENES {
        let mut scene = Scene::builtin(name).unwrap();
        scene.camera = scene.camera.with_resolution(192, 192);
        let gpu_scene = GpuScene::upload(&context, &scene).unwrap();
        let mut before = None;
        for frame in [0u32, 5] {
            let gbuffer = GBuffer::render(&scene, frame);
            let passes = [1u32, 2];
            let cpu: Vec<f32> = passes
                .iter()
                .map(|&pass| {
                    let input = pass_input(&scene, &gbuffer, &[], pass, SEED);
                    let domains = reciprocal::domains(&input);
                    reciprocal::frame_radius(&input, &domains, RadiusRule::Clamped)
                })
                .collect();
            let frame_buffer = FrameParams::new(&scene, frame, None, SEED)
                .buffer(&context)
                .unwrap();
            let pixels = Buffer::from_slice(&context, &gpu_pixels(&gbuffer)).unwrap();
            let mut inputs: Vec<&Buffer> = gpu_scene.buffers().to_vec();
            inputs.extend([&frame_buffer, &pixels, &placeholder]);
            let gpu: Vec<f32> = run_parity(&mut context, &kernel, &inputs, 3, &passes);
            let bits = |v: &[f32]| v.iter().map(|r| r.to_bits()).collect::<Vec<_>>();
            assert_eq!(
                bits(&gpu),
                bits(&cpu),
                "{name}, frame {frame}: {gpu:?} vs {cpu:?}"
            );
            let input = pass_input(&scene, &gbuffer, &[], 1, SEED);
            let radii: Vec<f32> = reciprocal::domains(&input)
                .iter()
                .flatten()
                .map(|d| {
                    let x1 = d.x1().position;
                    let max_d = d.material().d().max_element();
                    RadiusRule::Clamped.radius_px(&scene.camera, frame, x1, max_d)
                })
                .collect();
            let single = radii.iter().sum::<f32>() / radii.len() as f32;
            assert_ne!(
                single.to_bits(),
                gpu[0].to_bits(),
                "{name}: an f32 sum matched"
            );
            if let Some(previous) = before.replace(gpu[0]) {
                assert_ne!(previous, gpu[0], "{name}: another frame's radius matched");
            }
            let (low, high) = radii
                .iter()
                .fold((f32::MAX, f32::MIN), |(l, h), &r| (l.min(r), h.max(r)));
            eprintln!(
                "frame radius parity, {name}, frame {frame}: {} translucent pixels, radii \
                 {low}–{high} px, mean {} px (f32 sum: {single})",
                radii.len(),
                gpu[0]
            );
        }
    }
}

/// Paper 001's temporal confidence cap, run besides the presets' default
/// (`shifts::preset::TEMPORAL_CAP`) so that the kernel is seen to take the cap from its
/// parameters.
const SEED_001_CAP: f32 = 20.0;

/// Confidence of the previous frame's reservoirs in the pass comparison: between the default
/// temporal cap and [`SEED_001_CAP`], so the cap binds under one and not under the other.
const HISTORY_CONFIDENCE: f32 = 8.0;

/// The temporal and spatial passes of every registered preset (deduplicated), with their
/// temporal passes also at [`SEED_001_CAP`]: temporal GBH and spatial defensive pairwise without
/// cap, over their shifts and neighbour counts.
fn preset_pass_cases() -> Vec<PassCase> {
    let mut cases: Vec<PassCase> = Vec::new();
    let presets = Preset::all().into_iter().flat_map(|p| {
        let seed_001 = p.clone().with_temporal_cap(SEED_001_CAP);
        [p, seed_001]
    });
    for preset in presets {
        for (pass, spec) in preset.passes.iter().enumerate() {
            if matches!(spec, PassSpec::Candidates { .. }) {
                continue;
            }
            let case = PassCase {
                spec: *spec,
                pass: pass as u32,
            };
            if !cases
                .iter()
                .any(|c| c.spec == case.spec && c.pass == case.pass)
            {
                cases.push(case);
            }
        }
    }
    cases
}

/// The CPU's reuse pass: the reservoir and diag `(shifted, failed, improved, 0)` per pixel.
fn cpu_reuse(
    input: &PassInput,
    previous: Option<&Previous>,
    spec: &PassSpec,
) -> Vec<(PixelReservoir, [u32; 4])> {
    cpu_reused(input, previous, spec, Shade::Selected)
        .into_iter()
        .map(|r| {
            let c = r.shifts;
            (r.reservoir, [c.shifted, c.failed, c.improved, 0])
        })
        .collect()
}

/// The CPU's reuse pass with `shade`, per pixel.
fn cpu_reused(
    input: &PassInput,
    previous: Option<&Previous>,
    spec: &PassSpec,
    shade: Shade,
) -> Vec<Reused> {
    (0..input.gbuffer.pixels.len() as u32)
        .map(|pixel| {
            reuse::pass(input, previous, pixel, spec, shade)
                .expect("only reuse passes are compared")
                .unwrap()
        })
        .collect()
}

/// Bound on the relative error `max_c |g_c − c_c| / max_c |c_c|` of a pixel's Rao-Blackwellised
/// value: a sum of ≤ 5 terms `f(y_i)·m_i·W_i·J_i`, each factor within ~1e-5 relative as the
/// [`PASS_BOUNDS`] (`f` carries the profile's `exp`). Seen: ≤ 4.3e-6 (`bumpy`, `half-shadow`,
/// every reuse pass of the presets, 208–1 024 pixels each); bound 1e-4. The control (the
/// selected `f(Y)·W` in its place) is rejected on ≥ 21 % of the pixels where the CPU shifted.
const RAO_BLACKWELLISED_BOUND: f64 = 1e-4;

/// `max_c |got_c − want_c| / max_c |want_c|` (0 when equal, infinite against a zero value).
fn vector_error(got: [f32; 3], want: glam::Vec3) -> f64 {
    let scale = want.abs().max_element() as f64;
    let diff = (0..3)
        .map(|c| (got[c] as f64 - want[c] as f64).abs())
        .fold(0.0, f64::max);
    if diff == 0.0 {
        0.0
    } else if scale > 0.0 && diff.is_finite() {
        diff / scale
    } else {
        f64::INFINITY
    }
}

/// Of the pixels where the CPU's reservoir (integer fields) and diag agree with the GPU's and `want` has a
/// value: how many, and how many of the GPU's values are absent or beyond
/// [`RAO_BLACKWELLISED_BOUND`]; and the worst error within it.
fn compare_rao_blackwellised(
    cpu: &[(PixelReservoir, [u32; 4])],
    want: &[Option<glam::Vec3>],
    reservoirs: &[PixelReservoir],
    diag: &[[u32; 4]],
    values: &[[f32; 4]],
) -> (usize, usize, f64) {
    let (mut compared, mut beyond, mut worst) = (0, 0, 0.0f64);
    for (((c, w), (r, d)), v) in cpu
        .iter()
        .zip(want)
        .zip(reservoirs.iter().zip(diag))
        .zip(values)
    {
        let key =
            |r: &PixelReservoir| (r.has_sample, (r.has_sample != 0).then(|| sample_key(&r.y)));
        let same = key(&c.0) == key(r) && c.1 == *d;
        match w {
            Some(w) if same => {
                compared += 1;
                let error = if v[3] == 1.0 {
                    vector_error([v[0], v[1], v[2]], *w)
                } else {
                    f64::INFINITY
                };
                if error > RAO_BLACKWELLISED_BOUND {
                    beyond += 1;
                } else {
                    worst = worst.max(error);
                }
            }
            _ => {}
        }
    }
    (compared, beyond, worst)
}

/// Bounds of the pass comparison: those of [`SHIFT_BOUNDS`] for the stored sample; the
/// confidence is a sum and a min of exact inputs (exact); `W = w_sum / p̂` combines a few targets,
/// Jacobians and MIS weights, each within ~1e-5 relative. Seen: ucw 1.6e-5, p_disk 1.6e-5,
/// u 2.1e-5, bary 9.0e-6; bound 1e-4 for each.
const PASS_BOUNDS: [(&str, f64); 6] = [
    ("confidence", 0.0),
    ("ucw", 1e-4),
    ("u_radius, u_angle", 1e-4),
    ("p_disk", 1e-4),
    ("bary", 1e-4),
    ("x3", 0.0),
];

/// At most this fraction of pixels may differ in an integer field of the reservoir or in a diag
/// counter: a selection `u · w_sum < w`, a spatial neighbour pixel (the disk point uses the GPU's
/// cos/sin) or a shift decision (see [`SHIFT_MISMATCH_FRACTION`]) within an ulp of its boundary.
const PASS_MISMATCH_FRACTION: f64 = 1e-2;

/// Compares every pixel, or with `reused_only` the pixels where the CPU shifted a sample (the
/// negative controls' statistic: a wrong seed or shift can only change those).
fn compare_pass(
    cpu: &[(PixelReservoir, [u32; 4])],
    reservoirs: &[PixelReservoir],
    diag: &[[u32; 4]],
    reused_only: bool,
) -> Tally {
    let mut tally = Tally::new(&PASS_BOUNDS);
    for ((want, want_diag), (got, got_diag)) in cpu.iter().zip(reservoirs.iter().zip(diag)) {
        if reused_only && want_diag[0] == 0 {
            continue;
        }
        tally.compared += 1;
        let key =
            |r: &PixelReservoir| (r.has_sample, (r.has_sample != 0).then(|| sample_key(&r.y)));
        if key(want) != key(got) || want_diag != got_diag {
            tally.mismatched += 1;
            continue;
        }
        let mut beyond = tally.float("confidence", rel_error(got.confidence, want.confidence));
        beyond |= tally.float("ucw", rel_error(got.ucw, want.ucw));
        if want.has_sample != 0 {
            beyond |= compare_sample_floats(&mut tally, &got.y, &want.y);
        }
        tally.beyond_bounds += usize::from(beyond);
    }
    tally
}

/// Pass-level parity of `pass_temporal` and `pass_spatial` with `reuse::temporal` /
/// `reuse::spatial` for every reuse pass of the registered presets, on `bumpy` and
/// `half-shadow` at 32×32. Inputs from the CPU: G-buffers of frames 0 and 1 and the candidates
/// pass's reservoirs of both frames (temporal reuses frame 0's into frame 1; spatial runs on frame
/// 1), frame 0's with confidence [`HISTORY_CONFIDENCE`] so that the temporal cap binds. Every
/// pixel's reservoir and diag are compared. Negative controls: the GPU run with a wrong shift
/// index, with another seed, and (temporal passes) with the other temporal cap must differ in
/// more than 2 × [`PASS_MISMATCH_FRACTION`] of the pixels where the CPU shifted a sample.
/// With `PassParams::shade = 0` the kernels leave the Rao-Blackwellised buffer untouched; with 1
/// they write the same reservoirs and diag, a value exactly on the pixels `Reused` has one, each
/// within [`RAO_BLACKWELLISED_BOUND`] of the CPU's where the decisions agree (control: the
/// selected value in its place).
#[test]
fn reuse_passes_match_the_cpu() {
    let opened = kernel_or_skip("reuse pass parity", TEMPORAL).map(|(context, temporal)| {
        (
            Kernel::for_shader(&context, SPATIAL).unwrap(),
            context,
            temporal,
        )
    });
    let Some((spatial, mut context, temporal)) = opened else {
        return;
    };
    // The wrong shift index of the control: where the camera barely moves between the frames
    // (y1 ≈ x1), delayed reconnection, its negative controls, the hybrid and reconnection all
    // return nearly the same sample (J ≈ 1), so a kind that re-draws the random numbers
    // (inversion) stands in for them, and DelayedWithoutJacobian for the inverting passes.
    let wrong_shift = |spec: &PassSpec| match spec.shift() {
        Some(ShiftKind::InvertingExact | ShiftKind::InvertingDeferred) => {
            ShiftKind::DelayedWithoutJacobian.code()
        }
        _ => ShiftKind::InvertingDeferred.code(),
    };
    for name in SCENES {
        let scene = scene(name);
        let (g0, g1) = (GBuffer::render(&scene, 0), GBuffer::render(&scene, 1));
        let (mut r0, r1) = (canonical(&scene, &g0, SEED), canonical(&scene, &g1, SEED));
        for r in &mut r0 {
            r.confidence = HISTORY_CONFIDENCE;
        }
        let gpu_scene = GpuScene::upload(&context, &scene).unwrap();
        let p0 = Buffer::from_slice(&context, &gpu_pixels(&g0)).unwrap();
        let p1 = Buffer::from_slice(&context, &gpu_pixels(&g1)).unwrap();
        let b0 = Buffer::from_slice(&context, &r0).unwrap();
        let b1 = Buffer::from_slice(&context, &r1).unwrap();
        let n = r1.len();
        for case in preset_pass_cases() {
            let input = pass_input(&scene, &g1, &r1, case.pass, SEED);
            let previous = Previous {
                scene: &scene,
                gbuffer: &g0,
                reservoirs: &r0,
                sharing: None,
            };
            let cpu = cpu_reuse(&input, Some(&previous), &case.spec);
            let is_temporal = matches!(case.spec, PassSpec::Temporal { .. });
            let mut run = |seed: u64, shift: Option<u32>, cap: Option<f32>, shade: u32| {
                let frame = FrameParams::new(&scene, 1, Some(0), seed)
                    .buffer(&context)
                    .unwrap();
                let out = Buffer::zeroed(&context, n * PixelReservoir::BYTES).unwrap();
                let diag = Buffer::zeroed(&context, n * 16).unwrap();
                let rao_blackwellised = Buffer::zeroed(&context, n * 16).unwrap();
                let mut buffers: Vec<&Buffer> = gpu_scene.buffers().to_vec();
                buffers.extend([&frame, &p1, &b1]);
                if is_temporal {
                    buffers.extend([&p0, &b0]);
                }
                buffers.extend([&out, &diag, &rao_blackwellised]);
                let mut params = PassParams::new(case.pass, Some(&case.spec), true);
                params.shade = shade;
                if let Some(shift) = shift {
                    params.shift = shift;
                }
                if let Some(cap) = cap {
                    params.confidence_cap = cap;
                }
                let kernel = if is_temporal { &temporal } else { &spatial };
                let timing = context
                    .dispatch(
                        kernel,
                        &buffers,
                        bytemuck::bytes_of(&params),
                        [groups_for(n as u32, 64), 1, 1],
                    )
                    .unwrap();
                (
                    out.read::<PixelReservoir>().unwrap(),
                    diag.read::<[u32; 4]>().unwrap(),
                    timing.gpu_seconds,
                    rao_blackwellised.read::<[f32; 4]>().unwrap(),
                )
            };
            let (reservoirs, diag, seconds, untouched) = run(SEED, None, None, 0);
            assert!(
                untouched.iter().all(|v| *v == [0.0; 4]),
                "{name}: selected shading wrote Rao-Blackwellised values"
            );
            let tally = compare_pass(&cpu, &reservoirs, &diag, false);
            let label = case.spec.label();
            let moved = cpu
                .iter()
                .zip(&r1)
                .filter(|((r, _), c)| r.has_sample != 0 && r.y != c.y)
                .count();
            let shifted: u32 = cpu.iter().map(|(_, d)| d[0]).sum();
            eprintln!(
                "pass parity, {name} {label} (pass {}): {} pixels, {shifted} shifts, {moved} took a neighbour's sample, {} mismatched ({:.2e}), {} beyond bounds; worst {:?}; {}",
                case.pass,
                tally.compared,
                tally.mismatched,
                tally.mismatch_fraction(),
                tally.beyond_bounds,
                tally.worst,
                seconds.map_or("no timestamps".into(), |s| format!("{:.2} ms GPU", s * 1e3))
            );
            assert!(
                moved > 0 && shifted as usize > n / 10,
                "{name} {label}: the pass reused too little"
            );
            assert!(
                diag.iter().all(|d| d[3] == 0),
                "{name} {label}: a pixel reported an error code"
            );
            assert!(
                tally.mismatch_fraction() <= PASS_MISMATCH_FRACTION,
                "{name} {label}: {} of {} pixels differ in an integer field (allowed {PASS_MISMATCH_FRACTION})",
                tally.mismatched,
                tally.compared
            );
            assert_eq!(
                tally.beyond_bounds, 0,
                "{name} {label}: float errors beyond PASS_BOUNDS; worst {:?}",
                tally.worst
            );
            // The other cap, for a temporal pass: the kernel must read its cap.
            let wrong_cap = match case.spec {
                PassSpec::Temporal { confidence_cap, .. } => {
                    Some(if confidence_cap == SEED_001_CAP {
                        TEMPORAL_CAP
                    } else {
                        SEED_001_CAP
                    })
                }
                _ => None,
            };
            let mut controls = vec![
                (
                    "wrong shift index",
                    SEED,
                    Some(wrong_shift(&case.spec)),
                    None,
                ),
                ("seed + 1", SEED + 1, None, None),
            ];
            if wrong_cap.is_some() {
                controls.push(("other temporal cap", SEED, None, wrong_cap));
            }
            // Rao-Blackwellised shading (PassParams::shade = 1): the same reservoirs and diag,
            // and on the pixels the CPU resampled its value within RAO_BLACKWELLISED_BOUND.
            // Control: the CPU's selected value f(Y)·W in its place is rejected on the pixels
            // where the CPU shifted a sample.
            let (rb_reservoirs, rb_diag, _, values) = run(SEED, None, None, 1);
            assert_eq!(
                (bytemuck::cast_slice::<_, u8>(&rb_reservoirs), &rb_diag),
                (bytemuck::cast_slice::<_, u8>(&reservoirs), &diag),
                "{name} {label}: shade = 1 changed the reservoirs or diag"
            );
            let want: Vec<Option<glam::Vec3>> =
                cpu_reused(&input, Some(&previous), &case.spec, Shade::AllInputs)
                    .iter()
                    .map(|r| r.rao_blackwellised)
                    .collect();
            // Whether a pass resamples a pixel depends on the G-buffers only (bit-identical).
            let presence = want
                .iter()
                .zip(&values)
                .filter(|(w, v)| w.is_some() != (v[3] == 1.0))
                .count();
            assert_eq!(
                presence, 0,
                "{name} {label}: values written on other pixels"
            );
            let (compared, beyond, worst) =
                compare_rao_blackwellised(&cpu, &want, &reservoirs, &diag, &values);
            eprintln!(
                "pass parity, {name} {label}: Rao-Blackwellised values: {compared} compared, {beyond} absent or beyond {RAO_BLACKWELLISED_BOUND}, worst within {worst:.2e}"
            );
            assert!(
                compared > 0 && beyond == 0,
                "{name} {label}: {beyond} Rao-Blackwellised values absent or beyond the bound"
            );
            let selected: Vec<Option<glam::Vec3>> = (0..n as u32)
                .map(|pixel| {
                    let (domain, _) = input.domain(pixel)?;
                    want[pixel as usize]?;
                    let shifted = cpu[pixel as usize].1[0] > 0;
                    shifted.then(|| reuse::shade(&domain, &cpu[pixel as usize].0))
                })
                .collect();
            let (shifted, rejected, _) =
                compare_rao_blackwellised(&cpu, &selected, &reservoirs, &diag, &values);
            let rejected = rejected as f64 / shifted.max(1) as f64;
            eprintln!(
                "pass parity, {name} {label}: control (selected f(Y)·W) rejected {rejected:.3}"
            );
            assert!(
                rejected > 2.0 * PASS_MISMATCH_FRACTION,
                "{name} {label}: control, the selected value passes for the Rao-Blackwellised one"
            );
            for (control, seed, shift, cap) in controls {
                let (reservoirs, diag, _, _) = run(seed, shift, cap, 0);
                let rejected = compare_pass(&cpu, &reservoirs, &diag, true).rejected_fraction();
                eprintln!(
                    "pass parity, {name} {label}: control ({control}) rejected {rejected:.3}"
                );
                assert!(
                    rejected > 2.0 * PASS_MISMATCH_FRACTION,
                    "{name} {label}: negative control ({control}) undetected"
                );
            }
        }
    }
}
