//! Reuse telemetry of a run's last frame (issue 10): where each pixel's final sample came from
//! (its own candidate, the temporal pass or a spatial pass), per reuse pass the shifts tried and
//! failed by [`Fail`] kind and the MIS weight left to the pixel's own sample, the final
//! confidence `c`, and how many pixels hold the same entry point x2. Collected with the
//! diagnostics on the CPU backend. It only observes: no random number is drawn and no output
//! changes (`engine/src/cpu.rs` tests the bits).

use restir::shift::Fail;
use shifts::PixelReservoir;

use crate::reuse::StepTelemetry;

/// Failure kinds, indexed by `Fail::code() − 1`.
pub const FAIL_KINDS: usize = Fail::ALL.len();

/// One reuse pass of the last frame, per pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct PassTelemetry {
    /// [`crate::PassSpec::label`] of the pass.
    pub label: String,
    /// Neighbour samples the shift was applied to.
    pub shifted: Vec<u32>,
    /// Of these, the failed ones by [`Fail`] kind (index `code − 1`).
    pub failed_by: Vec<[u32; FAIL_KINDS]>,
    /// The MIS weight `m_0(y_0)` of the pixel's own sample where it had a positive weight.
    pub canonical_mis: Vec<Option<f32>>,
}

/// The reuse telemetry of one frame (row-major per-pixel vectors).
#[derive(Clone, Debug, PartialEq)]
pub struct Telemetry {
    pub frame: u32,
    pub width: u32,
    pub height: u32,
    /// The plan's pass labels by pass index (0: candidates).
    pub pass_labels: Vec<String>,
    /// The reuse passes in order (pass index 1, 2, …).
    pub passes: Vec<PassTelemetry>,
    /// Per pixel, the pass that last moved the final sample into the pixel: 0 its own
    /// candidate (kept through every pass), `p` the reuse pass `p` (temporal or spatial) that
    /// selected another input; `None` without a final sample. A tie (an input bit-identical to
    /// the pixel's own sample) counts for the input the stream selected.
    pub origin: Vec<Option<u32>>,
    /// Per pixel with a final sample, its reservoir's confidence `c`.
    pub confidence: Vec<Option<f32>>,
    /// Per pixel with a final sample, the number of pixels whose final sample has the same x2
    /// (object, triangle, barycentrics): 1 for a sample no other pixel holds; 0 without one.
    pub sharing: Vec<u32>,
}

/// Builds the [`Telemetry`] of one frame pass by pass.
#[derive(Clone, Debug)]
pub(crate) struct Recorder {
    telemetry: Telemetry,
}

impl Recorder {
    /// `pass_labels`: every pass of the plan by index, candidates first.
    pub(crate) fn new(width: u32, height: u32, frame: u32, pass_labels: Vec<String>) -> Recorder {
        let n = width as usize * height as usize;
        let passes = pass_labels[1..]
            .iter()
            .map(|label| PassTelemetry {
                label: label.clone(),
                shifted: vec![0; n],
                failed_by: vec![[0; FAIL_KINDS]; n],
                canonical_mis: vec![None; n],
            })
            .collect();
        Recorder {
            telemetry: Telemetry {
                frame,
                width,
                height,
                pass_labels,
                passes,
                origin: vec![None; n],
                confidence: vec![None; n],
                sharing: vec![0; n],
            },
        }
    }

    /// The candidate pass's reservoirs: each pixel with a sample holds its own.
    pub(crate) fn candidates<'a>(&mut self, reservoirs: impl Iterator<Item = &'a PixelReservoir>) {
        for (origin, r) in self.telemetry.origin.iter_mut().zip(reservoirs) {
            *origin = (r.has_sample != 0).then_some(0);
        }
    }

    /// Reuse pass `pass` (≥ 1): per pixel its output reservoir, what it observed and how many
    /// neighbour samples it shifted.
    pub(crate) fn reuse<'a>(
        &mut self,
        pass: u32,
        cells: impl Iterator<Item = (&'a PixelReservoir, &'a StepTelemetry, u32)>,
    ) {
        let t = &mut self.telemetry;
        let record = &mut t.passes[pass as usize - 1];
        for (i, (reservoir, step, shifted)) in cells.enumerate() {
            record.shifted[i] = shifted;
            record.failed_by[i] = step.failed_by;
            record.canonical_mis[i] = step.canonical_mis;
            t.origin[i] = match (reservoir.has_sample != 0, step.selected) {
                (false, _) => None,
                (true, Some(source)) if source > 0 => Some(pass),
                (true, _) => t.origin[i],
            };
        }
    }

    /// The telemetry, with the confidence and x2 sharing of the frame's final `reservoirs`.
    pub(crate) fn finish(mut self, reservoirs: &[PixelReservoir]) -> Telemetry {
        let t = &mut self.telemetry;
        for (i, r) in reservoirs.iter().enumerate() {
            t.confidence[i] = (r.has_sample != 0).then_some(r.confidence);
        }
        t.sharing = crate::duplication::sharing(reservoirs);
        self.telemetry
    }
}
