//! `reshift toy`: the toy GRIS chains of `restir::toy` for every correct shift × MIS scheme,
//! `1/M` on equal and differing supports, and the broken shifts, as a Markdown table of their
//! bias against the closed-form integrals.

use std::time::Instant;

use restir::check::{CheckName, CheckReport, image_equivalence, negative_control};
use restir::mis::{ConfidenceOnly, DefensivePairwise, Gbh, MisScheme, Pairwise};
use restir::resample::ResampleError;
use restir::shift::Shift;
use restir::stats::Verdict;
use restir::toy::chain::{ChainConfig, ToyScene};
use restir::toy::kit::{KitConfig, chain_outputs, chain_reports, geometry_reports, mis_report};
use restir::toy::shifts::{
    AsymmetricRejection, BackShiftBug, NoBackShift, Replay, Scaling, ScalingUnitJacobian,
    Translation,
};
use restir::toy::{Supports, ToyPixel};

/// Replicas per row, tolerance δ and CI confidence of the table.
const REPLICAS: usize = 4000;
const DELTA: f64 = 0.03;
const CONFIDENCE: f64 = 0.99;

struct Row<'a> {
    shift: &'a str,
    shift_impl: &'a dyn Shift<ToyPixel>,
    mis: &'a dyn MisScheme,
    supports: Supports,
    broken: bool,
}

/// Runs every row and prints the table and the negative controls' notes.
pub fn run() -> Result<(), ResampleError> {
    let chain = ChainConfig::default();
    println!(
        "# reshift toy GRIS chains\n\n{}×{} pixels, {} frames: {} candidates → temporal (GBH, cap {}) → \
         2 spatial passes ({} neighbours, the MIS below). Relative bias of the image total vs. the \
         closed-form integral; {REPLICAS} replicas per row.\n",
        chain.width,
        chain.height,
        chain.frames,
        chain.candidates,
        chain.temporal_cap,
        chain.neighbours
    );
    let correct: [(&str, &dyn Shift<ToyPixel>); 3] = [
        ("translation", &Translation),
        ("scaling", &Scaling),
        ("replay", &Replay),
    ];
    let schemes: [&dyn MisScheme; 4] = [&Gbh, &Pairwise, &DefensivePairwise, &ConfidenceOnly];
    let mut rows = Vec::new();
    for (shift, shift_impl) in correct {
        for mis in schemes {
            rows.push(Row {
                shift,
                shift_impl,
                mis,
                supports: Supports::Differing,
                broken: false,
            });
        }
    }
    rows.push(Row {
        shift: "replay",
        shift_impl: &Replay,
        mis: &ConfidenceOnly,
        supports: Supports::Equal,
        broken: false,
    });
    let unshifted = NoBackShift {
        inner: Translation,
        bug: BackShiftBug::Unshifted,
    };
    let no_jacobian = NoBackShift {
        inner: Scaling,
        bug: BackShiftBug::NoJacobian,
    };
    let broken: [(&str, &dyn Shift<ToyPixel>); 4] = [
        ("BROKEN scaling, J = 1", &ScalingUnitJacobian),
        ("BROKEN MIS at un-shifted point", &unshifted),
        ("BROKEN MIS without back-shift J", &no_jacobian),
        ("BROKEN asymmetric rejection", &AsymmetricRejection),
    ];
    for (shift, shift_impl) in broken {
        rows.push(Row {
            shift,
            shift_impl,
            mis: &DefensivePairwise,
            supports: Supports::Differing,
            broken: true,
        });
    }

    println!(
        "| shift | MIS | MIS declares | supports | N | relative bias | 99% CI | δ | verdict | pixels biased (Holm) | time |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|");
    let mut controls = Vec::new();
    for row in &rows {
        let cfg = KitConfig {
            chain: ChainConfig {
                supports: row.supports,
                ..chain
            },
            replicas: REPLICAS,
            ..KitConfig::default()
        };
        let scene = ToyScene::new(cfg.chain);
        let start = Instant::now();
        let outputs = chain_outputs(row.shift_impl, row.mis, &scene, &cfg)?;
        let elapsed = start.elapsed();
        let reference: Vec<f64> = scene
            .last_frame()
            .iter()
            .map(ToyPixel::integrand_integral)
            .collect();
        let e = image_equivalence(&outputs.estimates, &reference, DELTA, CONFIDENCE);
        let reports = chain_reports(&outputs, &scene, &cfg);
        let holm = reports
            .iter()
            .find(|r| r.check == CheckName::Unbiasedness)
            .and_then(|r| r.figure("holm_rejections"))
            .unwrap_or(f64::NAN);
        let verdict = match e.verdict {
            _ if holm > 0.0 => "**biased** (pixels)",
            Verdict::Equivalent => "equivalent",
            Verdict::Biased => "**biased**",
            Verdict::Inconclusive => "inconclusive",
        };
        println!(
            "| {} | {} | {} | {:?} | {} | {:+.2}% | [{:+.2}%, {:+.2}%] | ±{:.0}% | {verdict} | {holm}/{} | {:.2} s |",
            row.shift,
            row.mis.name(),
            row.mis.bias(),
            row.supports,
            e.n,
            100.0 * e.relative_bias,
            100.0 * e.ci_low,
            100.0 * e.ci_high,
            100.0 * e.delta,
            reference.len(),
            elapsed.as_secs_f64()
        );
        if row.broken {
            let mut all: Vec<CheckReport> = geometry_reports(row.shift_impl, &scene, &cfg);
            all.push(mis_report(row.shift_impl, row.mis, &scene, &cfg));
            all.extend(reports);
            controls.push(negative_control(row.shift, &all));
        }
    }
    let kit = KitConfig::default();
    println!(
        "\nVerdict: the image total's equivalence test, overruled to biased when any pixel's zero-bias \
         test is rejected by Holm at α = {} (family of all pixels).\n\n\
         ## Negative controls (conformance kit, α = {}, δ = ±{:.0}%, N = {REPLICAS})\n",
        kit.alpha,
        kit.alpha,
        100.0 * kit.delta
    );
    for control in controls {
        println!("- {}", control.note);
    }
    Ok(())
}
