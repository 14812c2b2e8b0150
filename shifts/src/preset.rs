//! Pass schedules as data (DESIGN §1, §6): a [`Preset`] is a list of passes, each naming its
//! shift, MIS scheme, neighbour count and confidence cap, and [`PRESETS`] names the presets of
//! paper 001 [001 §5.1].
//!
//! A registered shift (`registry.rs`) is usable in any pass by its [`ShiftKind`]; the backends
//! never match on shifts.

use std::fmt;

use restir::mis::{MAX_DOMAINS, MisKind};

use glam::Vec3;
use sss::scene::Camera;

use crate::IndexPolicy;
use crate::kind::ShiftKind;
use crate::numbers::Numbers;
use crate::target::Target;

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
    /// Spatial reuse: `neighbours` pixels drawn uniformly in the disk whose radius `radius`
    /// gives, independently per pixel or in reciprocal pairs (`pairs`); each neighbour's
    /// confidence capped at `confidence_cap` × the receiver's when given.
    Spatial {
        shift: ShiftKind,
        mis: MisKind,
        neighbours: u32,
        confidence_cap: Option<f32>,
        radius: RadiusRule,
        pairs: Pairs,
    },
}

/// How a spatial pass chooses its neighbours (`restir:<preset>/pairs=<name>`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Pairs {
    /// Each pixel draws its own neighbours in its own disk.
    #[default]
    Independent,
    /// Per neighbour slot, one offset for the whole frame pairs every pixel with one partner
    /// that takes it back (ReSTIR PT Enhanced, Lin, Kettunen, Wyman 2025): the two shifts of a
    /// pair serve as each pixel's forward shift and the other's MIS back-shift, evaluated once
    /// (`engine::reciprocal`). Needs a pairwise MIS.
    Reciprocal,
}

impl Pairs {
    /// Every choice, in the order `reshift shifts` lists them.
    pub const ALL: [Pairs; 2] = [Pairs::Independent, Pairs::Reciprocal];

    /// `independent` or `reciprocal`.
    pub const fn name(self) -> &'static str {
        match self {
            Pairs::Independent => "independent",
            Pairs::Reciprocal => "reciprocal",
        }
    }

    /// The choice named `name`.
    pub fn named(name: &str) -> Option<Pairs> {
        Pairs::ALL.into_iter().find(|p| p.name() == name)
    }

    /// One line for `reshift shifts`.
    pub fn about(self) -> &'static str {
        match self {
            Pairs::Independent => {
                "each pixel draws its neighbours uniformly in its own disk; each neighbour costs a shift and its MIS back-shift"
            }
            Pairs::Reciprocal => {
                "per slot one frame-wide offset pairs pixels that take each other; a pair's two shifts serve both pixels (CPU only; pairwise MIS)"
            }
        }
    }
}

/// The radius of a spatial pass's neighbour disk (DESIGN §9), from the screen length of
/// `2·max d` at the receiver's primary hit (`Camera::projected_radius_px`). The disk depends
/// only on the receiver's G-buffer, never on a reservoir, so it selects which domains enter the
/// pairwise MIS and does not enter any MIS weight: every rule keeps the estimator unbiased.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum RadiusRule {
    /// Clamped to [5, 30] px (`Camera::spatial_radius_px`).
    #[default]
    Clamped,
    /// The projection itself, floored at [`RadiusRule::FLOOR_PX`].
    Unclamped,
}

impl RadiusRule {
    /// The unclamped rule's floor: a disk narrower than a pixel would draw every neighbour
    /// inside the receiver's own pixel, which spatial reuse skips.
    pub const FLOOR_PX: f32 = 1.0;

    /// `clamped` or `unclamped`.
    pub fn name(self) -> &'static str {
        match self {
            RadiusRule::Clamped => "clamped",
            RadiusRule::Unclamped => "unclamped",
        }
    }

    /// The rule named `name`.
    pub fn named(name: &str) -> Option<RadiusRule> {
        [RadiusRule::Clamped, RadiusRule::Unclamped]
            .into_iter()
            .find(|r| r.name() == name)
    }

    /// The disk radius in pixels for a receiver whose primary hit is `x1` at `frame`.
    pub fn radius_px(self, camera: &Camera, frame: u32, x1: Vec3, max_d: f32) -> f32 {
        match self {
            RadiusRule::Clamped => camera.spatial_radius_px(frame, x1, max_d),
            RadiusRule::Unclamped => camera
                .projected_radius_px(frame, x1, max_d)
                .map_or(Self::FLOOR_PX, |r| r.max(Self::FLOOR_PX)),
        }
    }
}

impl PassSpec {
    /// Short label for tables: `candidates`, `temporal:reconnection`, `spatial4:delayed`.
    pub fn label(&self) -> String {
        match self {
            PassSpec::Candidates { .. } => "candidates".into(),
            PassSpec::Temporal { shift, .. } => format!("temporal:{}", shift.name()),
            PassSpec::Spatial {
                shift,
                neighbours,
                pairs,
                ..
            } => match pairs {
                Pairs::Independent => format!("spatial{neighbours}:{}", shift.name()),
                Pairs::Reciprocal => format!("spatial{neighbours}-reciprocal:{}", shift.name()),
            },
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

/// What the shade step paints on a translucent pixel.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Shade {
    /// `f(Y)·W` of the final reservoir [001 Alg. 2].
    #[default]
    Selected,
    /// The Rao-Blackwellised estimate of the last reuse pass that resampled the pixel,
    /// `Σ_i f(y_i)·m_i·W_i·J_i` over all its inputs (`restir::resample::resample_observed`):
    /// `E[f(Y)·W | inputs]`. Its luminance is `f(Y)·W`'s (`p̂ = luminance(f)`); it removes the
    /// colour noise of the one selected sample. The stored reservoirs, and so later frames, are
    /// unchanged. Both backends.
    AllInputs,
}

/// What temporal reuse does with the duplication of a history's sample
/// (`restir:<preset>/duplication=<name>`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Duplication {
    /// The history's confidence is its capped one [001 §5.1].
    #[default]
    Ignored,
    /// The duplication map [PTE]: the history's capped confidence divided by the number of
    /// pixels whose final sample in the previous frame had the same x2 (spatial reuse copies
    /// one good sample into many pixels, whose histories then carry it as if independent). The
    /// divisor depends on the history's own sample, so the MIS weights are no longer fixed
    /// given the inputs: a biased option, its bias measured in docs/experiments.md. CPU only.
    Divides,
}

impl Duplication {
    pub const ALL: [Duplication; 2] = [Duplication::Ignored, Duplication::Divides];

    pub fn name(self) -> &'static str {
        match self {
            Duplication::Ignored => "ignored",
            Duplication::Divides => "divides",
        }
    }

    pub fn named(name: &str) -> Option<Duplication> {
        Duplication::ALL.into_iter().find(|d| d.name() == name)
    }
}

/// A named list of passes run once per frame, and what the frame's shade step paints.
#[derive(Clone, Debug, PartialEq)]
pub struct Preset {
    pub name: String,
    pub passes: Vec<PassSpec>,
    pub shade: Shade,
    /// The target function `p̂` of every pass's domains.
    pub target: Target,
    /// What temporal reuse does with a history's duplication.
    pub duplication: Duplication,
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

/// Temporal confidence cap: `c_prev ≤ 3 · c_cur` (paper 001 §5.1 uses 20; `restir:<preset>/cap=20`).
///
/// With GBH the history's estimate enters the receiver's multiplied by the growth factor
/// `a = κρ / (κ + ρ) ≤ κ` (`κ = c_prev / c_cur`, `ρ = p̂_cur(y)·J / p̂_prev(x)`). Between
/// consecutive frames of a moving or jittered camera `ρ` scatters (`bumpy`, 128×96: `E[a²]` =
/// 1.0–1.5 for the hybrid and 1.5–3.1 for reconnection at κ = 20), and with `E[a²] ≥ 1` the error
/// grows with the length of the history (issue 10). κ = 3 gives `E[a²]` ≈ 0.55–0.75 and lowers
/// the frame-15 translucent MSE of every preset (`docs/experiments.md`, "Temporal confidence
/// cap"). A static, unjittered camera (`ρ = 1`) would favour a larger κ.
pub const TEMPORAL_CAP: f32 = 3.0;

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
        radius: RadiusRule::Clamped,
        pairs: Pairs::Independent,
    }
}

/// The registered presets: a name and how to build the preset called that [001 §5.1].
pub const PRESETS: [(&str, fn(&str) -> Preset); 5] = [
    ("reconnection", |n| {
        Preset::single_shift(n, ShiftKind::Reconnection)
    }),
    ("delayed", |n| {
        Preset::single_shift(n, ShiftKind::DelayedReconnection)
    }),
    ("hybrid", |n| Preset::single_shift(n, ShiftKind::Hybrid)),
    ("sequential", |n| {
        Preset::sequential(n, IndexPolicy::Deferred)
    }),
    ("sequential-exact", |n| {
        Preset::sequential(n, IndexPolicy::Exact)
    }),
];

/// Names of the registered presets, in [`PRESETS`] order.
pub const PRESET_NAMES: [&str; PRESETS.len()] = {
    let mut names = [""; PRESETS.len()];
    let mut i = 0;
    while i < names.len() {
        names[i] = PRESETS[i].0;
        i += 1;
    }
    names
};

impl Preset {
    /// Candidates → temporal → one spatial pass with 4 neighbours, all with `shift` [001 §5.1].
    pub fn single_shift(name: &str, shift: ShiftKind) -> Preset {
        Preset {
            name: name.into(),
            passes: vec![candidates(), temporal(shift), spatial(shift, 4)],
            shade: Shade::Selected,
            target: Target::Luminance,
            duplication: Duplication::Ignored,
        }
    }

    /// The sequential scheme [001 §4.3, §5.1]: temporal reconnection → spatial 2 neighbours
    /// reconnection → spatial 2 neighbours delayed. Both reconnection passes invert the random
    /// numbers for the receiver (the delayed pass replays the numbers a sample carries, which
    /// must belong to the pixel it sits in, also for samples taken over by temporal reuse).
    pub fn sequential(name: &str, policy: IndexPolicy) -> Preset {
        let invert = match policy {
            IndexPolicy::Exact => ShiftKind::InvertingExact,
            IndexPolicy::Deferred => ShiftKind::InvertingDeferred,
        };
        Preset {
            name: name.into(),
            passes: vec![
                candidates(),
                temporal(invert),
                spatial(invert, 2),
                spatial(ShiftKind::DelayedReconnection, 2),
            ],
            shade: Shade::Selected,
            target: Target::Luminance,
            duplication: Duplication::Ignored,
        }
    }

    /// The preset with every temporal pass's confidence cap set to `cap` (validated by
    /// [`Preset::validate`]).
    pub fn with_temporal_cap(mut self, cap: f32) -> Preset {
        for pass in &mut self.passes {
            if let PassSpec::Temporal { confidence_cap, .. } = pass {
                *confidence_cap = cap;
            }
        }
        self
    }

    /// The preset with every spatial pass's confidence cap set to `cap` (each neighbour's
    /// `c ≤ cap · c_receiver`; the registered presets leave it uncapped; validated by
    /// [`Preset::validate`]).
    pub fn with_spatial_cap(mut self, cap: f32) -> Preset {
        for pass in &mut self.passes {
            if let PassSpec::Spatial { confidence_cap, .. } = pass {
                *confidence_cap = Some(cap);
            }
        }
        self
    }

    /// The preset with every spatial pass taking `count` neighbours (validated by
    /// [`Preset::validate`]).
    pub fn with_neighbours(mut self, count: u32) -> Preset {
        for pass in &mut self.passes {
            if let PassSpec::Spatial { neighbours, .. } = pass {
                *neighbours = count;
            }
        }
        self
    }

    /// The preset with its spatial passes' shift replaced by `kind`, if they share one shift
    /// (every registered preset but the sequential ones); validated by [`Preset::validate`].
    pub fn with_spatial_shift(mut self, kind: ShiftKind) -> Result<Preset, String> {
        let shifts: Vec<&mut ShiftKind> = (self.passes.iter_mut())
            .filter_map(|pass| match pass {
                PassSpec::Spatial { shift, .. } => Some(shift),
                _ => None,
            })
            .collect();
        let names: Vec<&str> = shifts.iter().map(|s| s.name()).collect();
        match names.first() {
            None => return Err(format!("preset `{}` has no spatial pass", self.name)),
            Some(first) if names.iter().any(|n| n != first) => {
                return Err(format!(
                    "preset `{}` has several spatial shifts ({}); /spatial= needs one",
                    self.name,
                    names.join(", ")
                ));
            }
            Some(_) => {}
        }
        for shift in shifts {
            *shift = kind;
        }
        Ok(self)
    }

    /// The preset with every spatial pass's disk radius given by `rule`.
    pub fn with_radius(mut self, rule: RadiusRule) -> Preset {
        for pass in &mut self.passes {
            if let PassSpec::Spatial { radius, .. } = pass {
                *radius = rule;
            }
        }
        self
    }

    /// The preset with every spatial pass choosing its neighbours by `choice` (validated by
    /// [`Preset::validate`]).
    pub fn with_pairs(mut self, choice: Pairs) -> Preset {
        for pass in &mut self.passes {
            if let PassSpec::Spatial { pairs, .. } = pass {
                *pairs = choice;
            }
        }
        self
    }

    /// The preset whose temporal reuse treats a history's duplication as `choice`.
    pub fn with_duplication(self, choice: Duplication) -> Preset {
        Preset {
            duplication: choice,
            ..self
        }
    }

    /// Its passes' labels in order, e.g. `candidates → temporal:hybrid → spatial4:hybrid`.
    pub fn describe(&self) -> String {
        let labels: Vec<String> = self.passes.iter().map(PassSpec::label).collect();
        labels.join(" → ")
    }

    /// The registered preset `name` ([`PRESETS`]), or `None`.
    pub fn named(name: &str) -> Option<Preset> {
        let (_, build) = PRESETS.iter().find(|(n, _)| *n == name)?;
        Some(build(name))
    }

    /// Every registered preset.
    pub fn all() -> Vec<Preset> {
        PRESETS.iter().map(|(name, build)| build(name)).collect()
    }

    /// Checks that the preset can run: exactly one candidate pass, first; at least one BSSRDF
    /// sample; neighbour counts in `1..MAX_DOMAINS`; caps finite and > 0; reciprocal pairs only
    /// with a pairwise MIS; and no pass replays
    /// stored random numbers that an earlier pass may have left foreign ([`Self::chain_error`]).
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
                    mis,
                    pairs,
                    ..
                } => {
                    // A reciprocal pair shares the shifts of its two pixels: a scheme that also
                    // back-shifts a neighbour's sample into the other neighbours has no pair to
                    // share them with.
                    if pairs == Pairs::Reciprocal && mis.scheme().needs_all_targets(1) {
                        return Err(err(
                            i,
                            format!(
                                "pairs = reciprocal needs a pairwise MIS; {} reads every neighbour's back-shift",
                                mis.scheme().name()
                            ),
                        ));
                    }
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
        match self.chain_error() {
            Some((pass, reason)) => Err(err(pass, reason)),
            None => Ok(()),
        }
    }

    /// The first pass that replays the BSSRDF random numbers a sample stores where an earlier
    /// pass may have left them foreign, and why, from what the passes' shifts declare
    /// ([`ShiftKind::numbers`]).
    fn chain_error(&self) -> Option<(usize, String)> {
        self.chain_error_with(|_, pass| Some(pass.shift()?.numbers()))
    }

    /// [`Self::chain_error`] with the declaration of pass `i` given by `numbers(i, pass)`
    /// ([`Numbers::replays_foreign_of`]). "Earlier" is earlier in the frame, or any pass once a
    /// temporal pass at or before the replaying one carries the previous frame's final
    /// reservoirs into the frame.
    fn chain_error_with(
        &self,
        numbers: impl Fn(usize, &PassSpec) -> Option<Numbers>,
    ) -> Option<(usize, String)> {
        let temporal = self
            .passes
            .iter()
            .position(|p| matches!(p, PassSpec::Temporal { .. }));
        let reuse = |i: usize| numbers(i, &self.passes[i]);
        (0..self.passes.len()).find_map(|i| {
            let replaying = reuse(i)?;
            let feeds = |j: usize| j < i || temporal.is_some_and(|t| t <= i && j != i);
            let j = (0..self.passes.len())
                .filter(|&j| feeds(j))
                .find(|&j| reuse(j).is_some_and(|e| replaying.replays_foreign_of(e)))?;
            Some((
                i,
                format!(
                    "{} replays numbers pass {j} ({}) may leave foreign: biased; make pass {j} inverting-reconnection-exact",
                    self.passes[i].label(),
                    self.passes[j].label(),
                ),
            ))
        })
    }
}

#[cfg(test)]
mod tests {
    use restir::shift::{Fail, Shift, Shifted};

    use super::*;
    use crate::Hybrid;
    use crate::delayed::{Checks, Wanted, replay};
    use crate::numbers::{Cell, DeclaresNumbers, Effect, Interval, Outcome, Region};

    /// The rules round-trip their names; the clamped rule is `Camera::spatial_radius_px`, the
    /// unclamped one the projection itself above its floor and the floor below or behind the eye.
    #[test]
    fn radius_rules_name_and_radius() {
        for rule in [RadiusRule::Clamped, RadiusRule::Unclamped] {
            assert_eq!(RadiusRule::named(rule.name()), Some(rule));
        }
        assert_eq!(RadiusRule::named("wide"), None);
        assert_eq!(RadiusRule::default(), RadiusRule::Clamped);
        let camera = sss::scene::Scene::builtin("bumpy").unwrap().camera;
        let x1 = camera.eye(0) + 2.0 * camera.forward(0);
        for max_d in [1e-5, 0.01, 0.1, 10.0] {
            let clamped = RadiusRule::Clamped.radius_px(&camera, 0, x1, max_d);
            let unclamped = RadiusRule::Unclamped.radius_px(&camera, 0, x1, max_d);
            let r = camera.projected_radius_px(0, x1, max_d).unwrap();
            assert_eq!(clamped, camera.spatial_radius_px(0, x1, max_d));
            assert_eq!(unclamped, r.max(RadiusRule::FLOOR_PX), "{max_d}");
        }
        let behind = camera.eye(0) - camera.forward(0);
        assert_eq!(
            RadiusRule::Unclamped.radius_px(&camera, 0, behind, 0.1),
            RadiusRule::FLOOR_PX
        );
    }

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
                confidence_cap: 3.0,
                ..
            }
        ));
        let seed_001 = hybrid.clone().with_temporal_cap(20.0);
        assert!(matches!(
            seed_001.passes[1],
            PassSpec::Temporal {
                confidence_cap: 20.0,
                ..
            }
        ));
        assert_eq!(seed_001.passes[2], hybrid.passes[2]);
        let capped = hybrid.clone().with_spatial_cap(2.0).with_neighbours(8);
        assert!(matches!(
            capped.passes[2],
            PassSpec::Spatial {
                neighbours: 8,
                confidence_cap: Some(2.0),
                ..
            }
        ));
        assert_eq!(capped.passes[..2], hybrid.passes[..2]);
        let wide = hybrid.clone().with_radius(RadiusRule::Unclamped);
        assert!(matches!(
            wide.passes[2],
            PassSpec::Spatial {
                radius: RadiusRule::Unclamped,
                neighbours: 4,
                ..
            }
        ));
        assert_eq!(wide.passes[..2], hybrid.passes[..2]);
        let seq = Preset::named("sequential").unwrap().with_neighbours(3);
        let counts: Vec<u32> = seq
            .passes
            .iter()
            .filter_map(|p| match p {
                PassSpec::Spatial { neighbours, .. } => Some(*neighbours),
                _ => None,
            })
            .collect();
        assert_eq!(counts, [3, 3]);
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
        let p = Preset::named("hybrid").unwrap().with_temporal_cap(0.0);
        assert_eq!(p.validate().unwrap_err().pass, 1);
        let p = Preset::named("hybrid").unwrap().with_spatial_cap(-1.0);
        assert_eq!(p.validate().unwrap_err().pass, 2);
        let p = Preset::named("hybrid").unwrap().with_neighbours(0);
        assert_eq!(p.validate().unwrap_err().pass, 2);
        let p = Preset {
            name: "m0".into(),
            passes: vec![PassSpec::Candidates {
                bssrdf_samples: 0,
                shared_light: false,
            }],
            shade: Shade::Selected,
            target: Target::Luminance,
            duplication: Duplication::Ignored,
        };
        assert!(p.validate().is_err());
    }

    /// A pass that replays stored random numbers (delayed, hybrid) after one that keeps them
    /// while moving samples (reconnection, or the hybrid for delayed) is refused, naming both
    /// passes; within a frame only the order counts, and a temporal pass makes every pass
    /// earlier. Every registered preset passes; the bias the rule prevents is measured in
    /// `shifts/tests/unbiased.rs` (`reconnection_then_delayed_is_biased`).
    #[test]
    fn replaying_numbers_another_pass_left_foreign_is_refused() {
        let with_temporal = |name: &str, shift| {
            let mut p = Preset::named(name).unwrap();
            p.passes[1] = temporal(shift);
            p
        };
        // (preset, temporal shift, the replaying pass, the pass that leaves numbers foreign):
        // across frames the temporal pass replays what the previous frame's hybrid reconnected.
        for (name, shift, pass, earlier) in [
            ("sequential", ShiftKind::Reconnection, 3, 1),
            ("sequential-exact", ShiftKind::Reconnection, 3, 1),
            ("delayed", ShiftKind::Reconnection, 2, 1),
            ("hybrid", ShiftKind::Reconnection, 2, 1),
            ("delayed", ShiftKind::Hybrid, 2, 1),
            ("delayed", ShiftKind::DistantReconnection, 2, 1),
            ("hybrid", ShiftKind::DelayedReconnection, 1, 2),
            ("reconnection", ShiftKind::DelayedReconnection, 1, 2),
        ] {
            let e = with_temporal(name, shift).validate().unwrap_err();
            assert_eq!(e.pass, pass, "{e}");
            let line = e.to_string();
            assert!(!line.contains('\n'), "{line}");
            let cause = format!(
                "pass {earlier} ({})",
                with_temporal(name, shift).passes[earlier].label()
            );
            assert!(line.contains(&cause) && line.contains("biased"), "{line}");
        }
        for (name, shift) in [
            ("hybrid", ShiftKind::DistantReconnection),
            ("sequential", ShiftKind::DelayedReconnection),
            ("sequential", ShiftKind::InvertingExact),
            ("delayed", ShiftKind::InvertingExact),
        ] {
            with_temporal(name, shift).validate().unwrap();
        }
        // Without a temporal pass, a reconnection after the delayed pass feeds nothing.
        let spatial_only = |shifts: [ShiftKind; 2]| Preset {
            name: "spatial-only".into(),
            passes: vec![candidates(), spatial(shifts[0], 2), spatial(shifts[1], 2)],
            shade: Shade::Selected,
            target: Target::Luminance,
            duplication: Duplication::Ignored,
        };
        use ShiftKind::{DelayedReconnection as D, Reconnection as R};
        spatial_only([D, R]).validate().unwrap();
        assert_eq!(spatial_only([R, D]).validate().unwrap_err().pass, 2);
    }

    /// The choices round-trip their names; `with_pairs` sets every spatial pass's choice and
    /// labels it; reciprocal pairs validate with (defensive) pairwise MIS and are refused, in one
    /// line naming the pass, with GBH, whose neighbour weights read back-shifts no pair shares.
    #[test]
    fn reciprocal_pairs_need_a_pairwise_mis() {
        for pairs in Pairs::ALL {
            assert_eq!(Pairs::named(pairs.name()), Some(pairs));
        }
        assert_eq!(Pairs::named("mirrored"), None);
        let p = Preset::named("sequential")
            .unwrap()
            .with_pairs(Pairs::Reciprocal);
        p.validate().unwrap();
        assert_eq!(
            p.describe(),
            "candidates → temporal:inverting-reconnection-deferred → \
             spatial2-reciprocal:inverting-reconnection-deferred → spatial2-reciprocal:delayed"
        );
        let mut gbh = Preset::named("hybrid")
            .unwrap()
            .with_pairs(Pairs::Reciprocal);
        if let PassSpec::Spatial { mis, .. } = &mut gbh.passes[2] {
            *mis = MisKind::Gbh;
        }
        let e = gbh.validate().unwrap_err();
        assert_eq!(e.pass, 2);
        assert!(
            e.reason.contains("pairwise") && !e.to_string().contains('\n'),
            "{e}"
        );
        if let PassSpec::Spatial { mis, .. } = &mut gbh.passes[2] {
            *mis = MisKind::Pairwise;
        }
        gbh.validate().unwrap();
    }

    /// `/spatial=` replaces the one spatial shift of a preset and refuses a preset with several;
    /// the result is validated like any preset.
    #[test]
    fn the_spatial_shift_is_replaced_where_the_preset_has_one() {
        let p = Preset::named("hybrid")
            .unwrap()
            .with_spatial_shift(ShiftKind::DistantReconnection)
            .unwrap();
        assert_eq!(
            p.describe(),
            "candidates → temporal:hybrid → spatial4:distant-reconnection"
        );
        p.validate().unwrap();
        let refused = Preset::named("hybrid")
            .unwrap()
            .with_spatial_shift(ShiftKind::Reconnection)
            .unwrap();
        assert_eq!(refused.validate().unwrap_err().pass, 1);
        let e = Preset::named("sequential")
            .unwrap()
            .with_spatial_shift(ShiftKind::DelayedReconnection)
            .unwrap_err();
        assert!(
            e.contains("inverting-reconnection-deferred, delayed"),
            "{e}"
        );
        let mut none = Preset::named("hybrid").unwrap();
        none.passes.pop();
        assert!(none.with_spatial_shift(ShiftKind::Hybrid).is_err());
    }

    /// A hybrid-style shift with its own criterion: reconnection where `‖x2 − x1‖ > 2·max d` at
    /// both ends, delayed reconnection elsewhere (failing where the replayed path is far at the
    /// destination). It is registered nowhere: the rule needs only its declaration.
    struct FarReconnectedNearDelayed;

    impl FarReconnectedNearDelayed {
        fn far(x1: &sss::bssrdf::ExitPoint, x2: glam::Vec3, dst: &crate::SssDomain) -> bool {
            (x2 - x1.position).length() > 2.0 * dst.material().d().max_element()
        }
    }

    impl DeclaresNumbers for FarReconnectedNearDelayed {
        const NUMBERS: Numbers = Numbers(&[
            Outcome {
                effect: Effect::Kept,
                paths: Region(&[Cell::distance(Interval::above(2.0))]),
            },
            Outcome {
                effect: Effect::Replayed,
                paths: Region(&[Cell::distance(Interval::at_most(2.0))]),
            },
        ]);
    }

    impl Shift<crate::SssDomain<'_>> for FarReconnectedNearDelayed {
        fn shift(
            &self,
            x: &crate::SssSample,
            src: &crate::SssDomain,
            dst: &crate::SssDomain,
        ) -> Result<Shifted<crate::SssSample>, Fail> {
            let x2 = src.entry_point(x).ok_or(Fail::Rejected)?.position;
            if Self::far(src.x1(), x2, src) {
                let shifted = crate::reconnection::reconnect_shifted(x, src, dst)?;
                let y2 = dst.entry_point(&shifted.y).ok_or(Fail::Rejected)?.position;
                if !Self::far(dst.x1(), y2, dst) {
                    return Err(Fail::Rejected);
                }
                return Ok(shifted);
            }
            let replayed = replay(x, src, dst, Checks::ALL)?;
            let far = Self::far(dst.x1(), replayed.y2.position, dst);
            replayed.finish(dst, far, Wanted::Every)
        }
    }

    /// `restir:hybrid/temporal=<that shift>` is refused: its temporal pass replays near paths,
    /// which last frame's hybrid spatial pass reconnects when they are steeply oriented
    /// (`n1·n2 ≤ 0.5`), keeping numbers of another x1. Declared as the hybrid (the closest flag
    /// of a list of kinds) it would pass. The shift alone, and the registered presets, pass.
    #[test]
    fn a_hybrid_style_shift_with_its_own_criterion_is_checked_by_its_declaration() {
        let mut p = Preset::named("hybrid").unwrap();
        p.name = "hybrid/temporal=far-reconnected-near-delayed".into();
        let in_temporal = |declared: Numbers| {
            move |i: usize, pass: &PassSpec| match i {
                1 => Some(declared),
                _ => Some(pass.shift()?.numbers()),
            }
        };
        let (pass, reason) = p
            .chain_error_with(in_temporal(FarReconnectedNearDelayed::NUMBERS))
            .expect("refused");
        assert_eq!(pass, 1, "{reason}");
        assert!(reason.contains("pass 2 (spatial4:hybrid)"), "{reason}");
        assert_eq!(p.chain_error_with(in_temporal(Hybrid::NUMBERS)), None);
        // Both passes with the new shift: it replays only paths it never keeps.
        let alone =
            |_: usize, pass: &PassSpec| pass.shift().map(|_| FarReconnectedNearDelayed::NUMBERS);
        assert_eq!(p.chain_error_with(alone), None);
        for name in ["delayed", "sequential"] {
            let p = Preset::named(name).unwrap();
            assert!(
                p.chain_error_with(in_temporal(FarReconnectedNearDelayed::NUMBERS))
                    .is_some(),
                "{name}"
            );
        }
        for p in Preset::all() {
            assert_eq!(p.chain_error(), None, "{}", p.name);
        }
    }
}
