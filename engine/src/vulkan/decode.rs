//! What a pass kernel's diag buffer says (a `uvec4` per pixel): its error code, decoded to the
//! CPU's errors, and its counters, added to the run's diagnostics.

use restir::resample::ResampleError;
use restir::reservoir::InvalidCandidate;

use super::error::VulkanError;
use crate::PipelineError;
use crate::candidates::ProbeCounts;
use crate::contract::{HIT_OVERFLOW, KEPT_HITS, LOOP_BUDGET_CUT};
use crate::diagnostics::{Counters, HybridChoice};
use crate::plan::{PassKernel, Step};
use crate::reuse::ShiftCounts;

/// Decodes a pass's per-pixel error code (diag `w`; 0 = none, [`LOOP_BUDGET_CUT`] and
/// [`HIT_OVERFLOW`] are handled before) with [`ResampleError::from_gpu`]. A code outside the
/// contract's `ResampleCode`s is reported as a `Weight(NaN)` of the pass.
pub fn decode_error(code: u32) -> ResampleError {
    ResampleError::from_gpu(code).unwrap_or(ResampleError::Candidate {
        source: ((code >> 8) & 0xff) as usize,
        error: InvalidCandidate::Weight(f32::NAN),
    })
}

/// The error a pass's diag reports, if any: loops the device cut short
/// ([`LOOP_BUDGET_CUT`]), probes with more hits than kept ([`HIT_OVERFLOW`]), or the first
/// pixel's resampling error ([`decode_error`]).
pub(super) fn check_diag(
    frame: u32,
    pass: usize,
    step: &Step,
    diag: &[[u32; 4]],
) -> Result<(), PipelineError> {
    let pixels_with = |code| diag.iter().filter(|d| d[3] == code).count() as u64;
    let shader = step.kernel.name();
    match (pixels_with(LOOP_BUDGET_CUT), pixels_with(HIT_OVERFLOW)) {
        (0, 0) => {}
        (0, count) => {
            return Err(PipelineError::Vulkan(VulkanError::TooManyHits {
                shader,
                kept: KEPT_HITS as u32,
                count,
            }));
        }
        (count, _) => {
            return Err(PipelineError::Vulkan(VulkanError::LoopsCut {
                shader,
                count,
            }));
        }
    }
    let Some(pixel) = diag.iter().position(|d| d[3] != 0) else {
        return Ok(());
    };
    let pixel = pixel as u32;
    Err(match (step.kernel, decode_error(diag[pixel as usize][3])) {
        (PassKernel::Candidates, ResampleError::Candidate { error, .. }) => {
            PipelineError::Candidate {
                frame,
                pixel,
                error,
            }
        }
        (_, error) => PipelineError::Resample {
            frame,
            pass,
            pixel,
            error,
        },
    })
}

/// Adds a pass's diag counters: shifted / failed / improved of a reuse pass, or probes, hits
/// and the hybrid choice (1 reconnection, 2 delayed) of the candidates pass.
pub(super) fn add_diag(counters: &mut Counters, pass: usize, step: &Step, diag: &[[u32; 4]]) {
    if step.spec.is_some_and(|s| s.shift().is_some()) {
        let shifts: Vec<ShiftCounts> = diag
            .iter()
            .map(|d| ShiftCounts {
                shifted: d[0],
                failed: d[1],
                improved: d[2],
            })
            .collect();
        // Candidates are pass 0 and every later pass reuses (Preset::validate).
        counters.add_shifts(pass - 1, &shifts);
        return;
    }
    let probes: Vec<_> = diag
        .iter()
        .map(|d| {
            let choice = match d[2] {
                1 => HybridChoice::Reconnection,
                2 => HybridChoice::Delayed,
                _ => HybridChoice::None,
            };
            (
                ProbeCounts {
                    probes: d[0],
                    hits: d[1],
                },
                choice,
            )
        })
        .collect();
    counters.add_candidates(&probes);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unknown_error_codes_are_errors_too() {
        assert!(matches!(
            decode_error(0x0107),
            ResampleError::BadJacobian { source: 1, .. }
        ));
        assert!(matches!(
            decode_error(0x0309),
            ResampleError::Candidate {
                source: 3,
                error: InvalidCandidate::Weight(_)
            }
        ));
    }
}
