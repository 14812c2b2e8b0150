//! The pipeline as data (DESIGN §6): a [`Preset`] is a list of passes, each naming its shift, MIS
//! scheme, neighbour count and confidence cap, and the registry of named presets [001 §5.1].
//!
//! A new shift is usable in any pass by adding one arm to [`ShiftKind`] (its name and how to
//! build it); the backend never matches on shifts.

use std::fmt;

use restir::mis::{ConfidenceOnly, DefensivePairwise, Gbh, MAX_DOMAINS, MisScheme, Pairwise};
use restir::shift::Shift;
use shifts::{
    DelayedReconnection, Hybrid, Identity, IndexPolicy, InvertingReconnection, Reconnection,
    SssDomain, broken,
};
use sss::material::Translucent;

/// Every shift of the `shifts` crate, negative controls included (so a test can build a preset
/// with a deliberately wrong shift).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ShiftKind {
    Identity,
    Reconnection,
    DelayedReconnection,
    /// Hybrid shift [001 §4.1] with κ_dist = 2·max d of the receiver's material, κ_orient = 0.5.
    Hybrid,
    /// Reconnection + probabilistic inversion [001 Alg. 4], the sequential scheme's reconnection.
    InvertingReconnection(IndexPolicy),
    /// Negative control: delayed reconnection with J = 1.
    DelayedWithoutJacobian,
    /// Negative control: delayed reconnection without the y2↔x3 visibility test.
    DelayedWithoutVisibility,
    /// Negative control: a hybrid whose offset path ignores the criterion.
    HybridIgnoringCriterion,
}

impl ShiftKind {
    /// Every kind, for registries and tests.
    pub const ALL: [ShiftKind; 9] = [
        ShiftKind::Identity,
        ShiftKind::Reconnection,
        ShiftKind::DelayedReconnection,
        ShiftKind::Hybrid,
        ShiftKind::InvertingReconnection(IndexPolicy::Exact),
        ShiftKind::InvertingReconnection(IndexPolicy::Deferred),
        ShiftKind::DelayedWithoutJacobian,
        ShiftKind::DelayedWithoutVisibility,
        ShiftKind::HybridIgnoringCriterion,
    ];

    pub fn name(&self) -> &'static str {
        match self {
            ShiftKind::Identity => "identity",
            ShiftKind::Reconnection => "reconnection",
            ShiftKind::DelayedReconnection => "delayed",
            ShiftKind::Hybrid => "hybrid",
            ShiftKind::InvertingReconnection(IndexPolicy::Exact) => "inverting-reconnection-exact",
            ShiftKind::InvertingReconnection(IndexPolicy::Deferred) => {
                "inverting-reconnection-deferred"
            }
            ShiftKind::DelayedWithoutJacobian => "broken:delayed-without-jacobian",
            ShiftKind::DelayedWithoutVisibility => "broken:delayed-without-visibility",
            ShiftKind::HybridIgnoringCriterion => "broken:hybrid-ignoring-criterion",
        }
    }

    /// Whether the selected sample of a pass with this shift needs its intersection index
    /// resolved afterwards (`shifts::resolve_deferred_index`, deferred policy [001 §4.3]).
    pub fn resolves_deferred_index(&self) -> bool {
        matches!(
            self,
            ShiftKind::InvertingReconnection(IndexPolicy::Deferred)
        )
    }

    /// Runs `f` with the shift built for a receiver of material `material` (the hybrid's κ_dist
    /// depends on it; every shift fails between different objects, so one material suffices).
    pub fn with_shift<R>(
        &self,
        material: &Translucent,
        f: impl FnOnce(&dyn for<'s> Shift<SssDomain<'s>>) -> R,
    ) -> R {
        match self {
            ShiftKind::Identity => f(&Identity),
            ShiftKind::Reconnection => f(&Reconnection),
            ShiftKind::DelayedReconnection => f(&DelayedReconnection),
            ShiftKind::Hybrid => f(&Hybrid::for_material(material)),
            ShiftKind::InvertingReconnection(policy) => {
                f(&InvertingReconnection { policy: *policy })
            }
            ShiftKind::DelayedWithoutJacobian => f(&broken::DelayedWithoutJacobian),
            ShiftKind::DelayedWithoutVisibility => f(&broken::DelayedWithoutVisibility),
            ShiftKind::HybridIgnoringCriterion => f(&broken::HybridIgnoringCriterion),
        }
    }
}

/// The resampling MIS schemes of `restir::mis`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MisKind {
    Gbh,
    Pairwise,
    DefensivePairwise,
    /// `1/M` with confidences: biased unless supports agree (a control, not a default).
    ConfidenceOnly,
}

impl MisKind {
    pub fn scheme(&self) -> &'static dyn MisScheme {
        match self {
            MisKind::Gbh => &Gbh,
            MisKind::Pairwise => &Pairwise,
            MisKind::DefensivePairwise => &DefensivePairwise,
            MisKind::ConfidenceOnly => &ConfidenceOnly,
        }
    }
}

/// One pass of a frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PassSpec {
    /// Candidate generation [001 §3.1, Eq. 10]: `bssrdf_samples` BSSRDF samples (M), every hit
    /// of each probe a candidate; `shared_light`: one light sample per probe, shared by its hits
    /// [001 §5.2]. The selected sample is shadow-tested.
    Candidates {
        bssrdf_samples: u32,
        shared_light: bool,
    },
    /// Temporal reuse: the previous frame's final reservoir at the reprojected pixel, its
    /// confidence capped at `confidence_cap` × the current one.
    Temporal {
        shift: ShiftKind,
        mis: MisKind,
        confidence_cap: f32,
    },
    /// Spatial reuse: `neighbours` pixels drawn uniformly in the disk of radius
    /// `Camera::spatial_radius_px`; each neighbour's confidence capped at `confidence_cap` × the
    /// receiver's when given.
    Spatial {
        shift: ShiftKind,
        mis: MisKind,
        neighbours: u32,
        confidence_cap: Option<f32>,
    },
}

impl PassSpec {
    /// Short label for tables: `candidates`, `temporal:reconnection`, `spatial4:delayed`.
    pub fn label(&self) -> String {
        match self {
            PassSpec::Candidates { .. } => "candidates".into(),
            PassSpec::Temporal { shift, .. } => format!("temporal:{}", shift.name()),
            PassSpec::Spatial {
                shift, neighbours, ..
            } => {
                format!("spatial{neighbours}:{}", shift.name())
            }
        }
    }

    /// The shift of a reuse pass.
    pub fn shift(&self) -> Option<ShiftKind> {
        match self {
            PassSpec::Candidates { .. } => None,
            PassSpec::Temporal { shift, .. } | PassSpec::Spatial { shift, .. } => Some(*shift),
        }
    }
}

/// A named list of passes run once per frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Preset {
    pub name: String,
    pub passes: Vec<PassSpec>,
}

/// Why a preset cannot run.
#[derive(Clone, Debug, PartialEq)]
pub struct PresetError {
    pub preset: String,
    pub pass: usize,
    pub reason: String,
}

impl fmt::Display for PresetError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "preset `{}`, pass {}: {}",
            self.preset, self.pass, self.reason
        )
    }
}

impl std::error::Error for PresetError {}

/// Temporal confidence cap of seed 001 §5.1.
pub const TEMPORAL_CAP: f32 = 20.0;

/// Names of the registered presets.
pub const PRESET_NAMES: [&str; 5] = [
    "reconnection",
    "delayed",
    "hybrid",
    "sequential",
    "sequential-exact",
];

fn candidates() -> PassSpec {
    PassSpec::Candidates {
        bssrdf_samples: 1,
        shared_light: true,
    }
}

fn temporal(shift: ShiftKind) -> PassSpec {
    PassSpec::Temporal {
        shift,
        mis: MisKind::Gbh,
        confidence_cap: TEMPORAL_CAP,
    }
}

fn spatial(shift: ShiftKind, neighbours: u32) -> PassSpec {
    PassSpec::Spatial {
        shift,
        mis: MisKind::DefensivePairwise,
        neighbours,
        confidence_cap: None,
    }
}

impl Preset {
    /// Candidates → temporal → one spatial pass with 4 neighbours, all with `shift` [001 §5.1].
    pub fn single_shift(name: &str, shift: ShiftKind) -> Preset {
        Preset {
            name: name.into(),
            passes: vec![candidates(), temporal(shift), spatial(shift, 4)],
        }
    }

    /// The sequential scheme [001 §4.3, §5.1]: temporal reconnection → spatial 2 neighbours
    /// reconnection → spatial 2 neighbours delayed. Both reconnection passes invert the random
    /// numbers for the receiver (the delayed pass replays the numbers a sample carries, which
    /// must belong to the pixel it sits in, also for samples taken over by temporal reuse).
    pub fn sequential(name: &str, policy: IndexPolicy) -> Preset {
        let invert = ShiftKind::InvertingReconnection(policy);
        Preset {
            name: name.into(),
            passes: vec![
                candidates(),
                temporal(invert),
                spatial(invert, 2),
                spatial(ShiftKind::DelayedReconnection, 2),
            ],
        }
    }

    /// The registered preset `name` ([`PRESET_NAMES`]), or `None`.
    pub fn named(name: &str) -> Option<Preset> {
        Some(match name {
            "reconnection" => Preset::single_shift(name, ShiftKind::Reconnection),
            "delayed" => Preset::single_shift(name, ShiftKind::DelayedReconnection),
            "hybrid" => Preset::single_shift(name, ShiftKind::Hybrid),
            "sequential" => Preset::sequential(name, IndexPolicy::Deferred),
            "sequential-exact" => Preset::sequential(name, IndexPolicy::Exact),
            _ => return None,
        })
    }

    /// Every registered preset.
    pub fn all() -> Vec<Preset> {
        PRESET_NAMES
            .iter()
            .filter_map(|n| Preset::named(n))
            .collect()
    }

    /// Checks that the preset can run: exactly one candidate pass, first; at least one BSSRDF
    /// sample; neighbour counts in `1..MAX_DOMAINS`; caps finite and > 0.
    pub fn validate(&self) -> Result<(), PresetError> {
        let err = |pass: usize, reason: String| PresetError {
            preset: self.name.clone(),
            pass,
            reason,
        };
        if !matches!(self.passes.first(), Some(PassSpec::Candidates { .. })) {
            return Err(err(0, "the first pass must generate candidates".into()));
        }
        for (i, pass) in self.passes.iter().enumerate() {
            match *pass {
                PassSpec::Candidates { bssrdf_samples, .. } => {
                    if i > 0 {
                        return Err(err(i, "candidates can only be the first pass".into()));
                    }
                    if bssrdf_samples == 0 {
                        return Err(err(i, "bssrdf_samples = 0; need at least 1".into()));
                    }
                }
                PassSpec::Temporal { confidence_cap, .. } => {
                    if !(confidence_cap.is_finite() && confidence_cap > 0.0) {
                        return Err(err(
                            i,
                            format!("confidence_cap = {confidence_cap}; need > 0"),
                        ));
                    }
                }
                PassSpec::Spatial {
                    neighbours,
                    confidence_cap,
                    ..
                } => {
                    if neighbours == 0 || neighbours as usize >= MAX_DOMAINS {
                        return Err(err(
                            i,
                            format!("neighbours = {neighbours}; need 1..={}", MAX_DOMAINS - 1),
                        ));
                    }
                    if let Some(cap) = confidence_cap
                        && !(cap.is_finite() && cap > 0.0)
                    {
                        return Err(err(i, format!("confidence_cap = {cap}; need > 0")));
                    }
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn registry_matches_seed_001_defaults() {
        for name in PRESET_NAMES {
            let p = Preset::named(name).unwrap();
            assert_eq!(p.name, name);
            p.validate().unwrap();
        }
        assert!(Preset::named("nope").is_none());
        let hybrid = Preset::named("hybrid").unwrap();
        assert_eq!(hybrid.passes.len(), 3);
        assert!(matches!(
            hybrid.passes[2],
            PassSpec::Spatial {
                neighbours: 4,
                mis: MisKind::DefensivePairwise,
                ..
            }
        ));
        assert!(matches!(
            hybrid.passes[1],
            PassSpec::Temporal {
                mis: MisKind::Gbh,
                confidence_cap: 20.0,
                ..
            }
        ));
        let seq = Preset::named("sequential").unwrap();
        let labels: Vec<String> = seq.passes.iter().map(PassSpec::label).collect();
        assert_eq!(
            labels,
            [
                "candidates",
                "temporal:inverting-reconnection-deferred",
                "spatial2:inverting-reconnection-deferred",
                "spatial2:delayed"
            ]
        );
        assert!(seq.passes[1].shift().unwrap().resolves_deferred_index());
        let exact = Preset::named("sequential-exact").unwrap();
        assert!(!exact.passes[2].shift().unwrap().resolves_deferred_index());
    }

    #[test]
    fn invalid_presets_are_rejected_with_the_pass_named() {
        let mut p = Preset::named("delayed").unwrap();
        p.passes.swap(0, 1);
        assert_eq!(p.validate().unwrap_err().pass, 0);
        let mut p = Preset::named("delayed").unwrap();
        p.passes[2] = spatial(ShiftKind::Reconnection, MAX_DOMAINS as u32);
        assert_eq!(p.validate().unwrap_err().pass, 2);
        let mut p = Preset::named("delayed").unwrap();
        p.passes[1] = PassSpec::Temporal {
            shift: ShiftKind::Reconnection,
            mis: MisKind::Gbh,
            confidence_cap: f32::NAN,
        };
        assert_eq!(p.validate().unwrap_err().pass, 1);
        let p = Preset {
            name: "m0".into(),
            passes: vec![PassSpec::Candidates {
                bssrdf_samples: 0,
                shared_light: false,
            }],
        };
        assert!(p.validate().is_err());
        let names: std::collections::HashSet<_> = ShiftKind::ALL.iter().map(|s| s.name()).collect();
        assert_eq!(names.len(), ShiftKind::ALL.len());
    }
}
