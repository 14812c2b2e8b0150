//! `experiments`: paper 001's experiments and their findings, built on the lab's comparisons
//! ([`lab::compare`]). Each named experiment ([`Experiment`]) reproduces one of paper 001's
//! figures (DESIGN §7) and ends in a table of the paper's qualitative findings and whether the
//! measured numbers reproduce them ([`findings`]). The comparisons (Fig. 6–9) run
//! [`lab::compare`] at equal time; the diagnostics figures (Fig. 4, 5, 10) average
//! `engine::diagnostics` per region. `ground-truth` measures every method against the volumetric
//! random walk [000]. The one-off measurements of the examples (`examples/`) read the same
//! methods and regions. docs/experiments.md has the protocol and measured results.

mod ablation;
mod denoised;
mod figures;
pub mod findings;
pub mod ground_truth;
mod materials;
mod mfp_scaling;
pub mod model_gap;
mod paper_scenes;
mod setup;
mod shift_comparison;

pub use setup::{Report, Settings, equal_time_comparison};

use lab::error::Error;
use lab::progress::Progress;

/// An experiment by name ([`Experiment::name`]); [`Experiment::about`] says what it reproduces.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Experiment {
    ShiftComparison,
    ManyLights,
    Materials,
    MfpScaling,
    HybridMap,
    ImprovedFraction,
    TemporalShift,
    GroundTruth,
    ModelGap,
    Ablation,
    Denoised,
    PaperAjax,
    PaperAjaxManyLights,
}

/// An experiment's default replicas, resolution and reference spp (the command line's).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Defaults {
    pub replicas: u32,
    pub resolution: (u32, u32),
    pub reference_spp: u32,
}

impl Experiment {
    pub const ALL: [Experiment; 13] = [
        Experiment::ShiftComparison,
        Experiment::ManyLights,
        Experiment::Materials,
        Experiment::MfpScaling,
        Experiment::HybridMap,
        Experiment::ImprovedFraction,
        Experiment::TemporalShift,
        Experiment::GroundTruth,
        Experiment::ModelGap,
        Experiment::Ablation,
        Experiment::Denoised,
        Experiment::PaperAjax,
        Experiment::PaperAjaxManyLights,
    ];

    /// The name on the command line and of the default output folder `out/experiment-<name>`.
    pub fn name(self) -> &'static str {
        match self {
            Experiment::ShiftComparison => "shift-comparison",
            Experiment::ManyLights => "many-lights",
            Experiment::Materials => "materials",
            Experiment::MfpScaling => "mfp-scaling",
            Experiment::HybridMap => "hybrid-map",
            Experiment::ImprovedFraction => "improved-fraction",
            Experiment::TemporalShift => "temporal-shift",
            Experiment::GroundTruth => "ground-truth",
            Experiment::ModelGap => "model-gap",
            Experiment::Ablation => "ablation",
            Experiment::Denoised => "denoised",
            Experiment::PaperAjax => "paper-ajax",
            Experiment::PaperAjaxManyLights => "paper-ajax-many-lights",
        }
    }

    /// The figure of paper 001 it reproduces and how, in one line.
    pub fn about(self) -> &'static str {
        match self {
            Experiment::ShiftComparison => {
                "Fig. 6: the four shifts vs. path tracing at equal time, one large light (`bumpy`)"
            }
            Experiment::ManyLights => {
                "Fig. 7: the shift comparison with 512 small lights (`many-lights`)"
            }
            Experiment::Materials => {
                "Fig. 8: hybrid and sequential vs. path tracing on the ten measured materials (`materials`)"
            }
            Experiment::MfpScaling => {
                "Fig. 9: the gain of hybrid / sequential over equal-time path tracing vs. the mean free path"
            }
            Experiment::HybridMap => {
                "Fig. 4: where the hybrid criterion picks reconnection, per region"
            }
            Experiment::ImprovedFraction => {
                "Fig. 5: the fraction of improved samples, hybrid vs. sequential"
            }
            Experiment::TemporalShift => {
                "Fig. 10: reconnection vs. delayed reconnection in the sequential scheme's temporal pass"
            }
            Experiment::GroundTruth => {
                "every method against the volumetric random walk (000): model error, noise, equal-time efficiency"
            }
            Experiment::ModelGap => {
                "the random walk minus the diffusion BSSRDF, split by scattering order, profile and boundary (000)"
            }
            Experiment::Ablation => {
                "issue 10: one ReSTIR preset varied one knob at a time, efficiency over pt per region"
            }
            Experiment::Denoised => {
                "Fig. 6 and 7 with and without each denoiser (OIDN, SVGF) at equal time, at the resolution and twice it"
            }
            Experiment::PaperAjax => {
                "Fig. 6 on the paper's own scene (`ajax`, assets): pt at 1/6/12 spp and equal time, the presets and the best configuration, raw and denoised"
            }
            Experiment::PaperAjaxManyLights => {
                "Fig. 7 on the paper's own scene (`ajax-many-lights`, assets), as paper-ajax"
            }
        }
    }

    /// Its defaults: `ground-truth` (21 scenes, every registry method, the walk as reference; 32×24, 16
    /// replicas, a 4096-spp walk: about 5 minutes on the shared 2-core machine) and `model-gap`
    /// (7 scenes × 3 boundaries, 8 estimators per sample; `reference_spp` is every estimator's
    /// total over the replicas) run small; `ablation` (14 rows per method in 6 comparisons, up to
    /// 384×288) at 128×96 with 4 replicas and 1024-spp references; the figures at 128×96, 16
    /// replicas, 8192-spp references; `denoised` (4 comparisons with every denoiser) at 256×192 and
    /// 512×384, 8 replicas, 4096-spp references, as the main job; `paper-ajax` and
    /// `paper-ajax-many-lights` at half the paper's size (360×540), 8 replicas, 2048-spp
    /// references (docs/experiments.md, "Paper 001 on its own scene", for their cost).
    pub fn defaults(self) -> Defaults {
        match self {
            Experiment::GroundTruth => Defaults {
                replicas: 16,
                resolution: (32, 24),
                reference_spp: 4096,
            },
            Experiment::ModelGap => Defaults {
                replicas: 16,
                resolution: (32, 24),
                reference_spp: 256,
            },
            Experiment::Ablation => Defaults {
                replicas: 4,
                resolution: (128, 96),
                reference_spp: 1024,
            },
            Experiment::Denoised => Defaults {
                replicas: 8,
                resolution: (256, 192),
                reference_spp: 4096,
            },
            Experiment::PaperAjax | Experiment::PaperAjaxManyLights => Defaults {
                replicas: 8,
                resolution: (360, 540),
                reference_spp: 2048,
            },
            _ => Defaults {
                replicas: 16,
                resolution: (128, 96),
                reference_spp: 8192,
            },
        }
    }

    /// Whether it runs a list of scenes that [`Settings::scenes`] may replace.
    pub fn takes_scenes(self) -> bool {
        matches!(
            self,
            Experiment::GroundTruth | Experiment::ModelGap | Experiment::Ablation
        )
    }

    /// Whether [`Settings::methods`] may replace the methods it runs.
    pub fn takes_methods(self) -> bool {
        self == Experiment::Ablation
    }

    /// Runs the experiment, writing its tables, findings and images into its folder.
    pub fn run(self, settings: &Settings, progress: &mut dyn Progress) -> Result<Report, Error> {
        settings.check()?;
        let name = self.name();
        match self {
            Experiment::ShiftComparison => shift_comparison::run(settings, "bumpy", name, progress),
            Experiment::ManyLights => {
                shift_comparison::run(settings, "many-lights", name, progress)
            }
            Experiment::Materials => materials::run(settings, progress),
            Experiment::MfpScaling => mfp_scaling::run(settings, progress),
            Experiment::HybridMap => figures::hybrid_map(settings),
            Experiment::ImprovedFraction => figures::improved_fraction(settings),
            Experiment::TemporalShift => figures::temporal_shift(settings, progress),
            Experiment::GroundTruth => ground_truth::run(settings, progress),
            Experiment::ModelGap => model_gap::run(settings, progress),
            Experiment::Ablation => ablation::run(settings, progress),
            Experiment::Denoised => denoised::run(settings, name, progress),
            Experiment::PaperAjax => paper_scenes::run(settings, "ajax", name, progress),
            Experiment::PaperAjaxManyLights => {
                paper_scenes::run(settings, "ajax-many-lights", name, progress)
            }
        }
    }
}
