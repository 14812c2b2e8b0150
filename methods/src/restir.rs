//! `restir:<preset>[/temporal=<shift>][/spatial=<shift>][/cap=<κ>][/spatial-cap=<κ>][/neighbours=<n>][/radius=<clamped|unclamped>][/pairs=<independent|reciprocal>][/duplication=<ignored|divides>][/target=<p̂>][/shade=<selected|all>][/channels=rgb]`:
//! the ReSTIR SSS frame pipeline with a registered preset [001 §5.1] (DESIGN §6). Every frame of
//! the trajectory is rendered (temporal reuse) and the last one is kept; `/temporal=<shift>`
//! swaps the shift of the temporal pass [001 Fig. 10], `/spatial=<shift>` the one shift of the
//! spatial passes (refused for a preset with several), `/cap=<κ>` sets its confidence cap,
//! `/spatial-cap=<κ>` caps every spatial neighbour's confidence at κ × the receiver's,
//! `/neighbours=<n>` sets every spatial pass's neighbour count, `/pairs=reciprocal` makes every
//! spatial pass take its neighbours in reciprocal pairs (`Pairs`), `/target=<p̂>` the target function
//! of every domain (`Target`), `/shade=all` shades with all inputs of the last reuse pass
//! (`Shade::AllInputs`), `/channels=rgb` runs the preset once per channel with that channel as
//! `p̂` and the same seed, and keeps each run's channel ([`Channels`], `restir/channels.rs`:
//! per-channel reservoirs at about three times the cost).
//!
//! The only file of the lab that names presets and shift kinds: when presets move crates, the
//! import below is the one to change.

use engine::{
    Backend, Keep, PassSpec, PipelineError, Preset, RadiusRule, RunConfig, Shade, ShiftKind,
    Stream, Target,
};
use shifts::preset::{Duplication, PRESET_NAMES, Pairs};
use sss::scene::Scene;

use super::estimator::{Entry, Estimator, LastFrame, Method, SampleCounts, Trajectory};

mod channels;

pub use channels::Channels;

pub const ENTRY: Entry = Entry {
    family: "restir",
    usage: "restir:<preset>[/temporal=<shift>][/spatial=<shift>][/cap=<κ>][/spatial-cap=<κ>][/neighbours=<n>][/radius=<clamped|unclamped>][/pairs=<independent|reciprocal>][/duplication=<ignored|divides>][/target=<luminance|mean|l2|red|green|blue>][/shade=<selected|all>][/channels=rgb]",
    about: "ReSTIR SSS with spatiotemporal reuse and the preset's shift mapping [001 §5.1]; \
            `/temporal=<shift>` swaps the temporal pass's shift (001 Fig. 10), \
            `/spatial=<shift>` the spatial passes' one shift (see `reshift shifts`); \
            `/cap=<κ>` sets the temporal confidence cap (default 3; paper 001 uses 20); \
            `/spatial-cap=<κ>` caps spatial neighbours' confidence (default none); \
            `/neighbours=<n>` sets the spatial passes' neighbour count; \
            `/radius=unclamped` drops the spatial disk's [5, 30] px clamp (floor 1 px; CPU only); \
            `/pairs=reciprocal` pairs pixels that take each other as spatial neighbours, so each pair's two shifts serve both (ReSTIR PT Enhanced; CPU only); \
            `/duplication=divides` divides a temporal history's confidence by the number of pixels that held its sample after the previous frame's reuse (ReSTIR PT Enhanced's duplication map; biased, CPU only); \
            `/target=<mean|l2>` sets p̂ to the channel mean or the L2 norm of f (default luminance; CPU only), \
            `/target=<red|green|blue>` to one channel of f (an estimator of that channel alone); \
            `/shade=all` paints the last reuse pass's Rao-Blackwellised value over all its inputs; \
            `/channels=rgb` runs the preset once per channel with that channel as p̂ and the same seed \
            and keeps each run's channel (per-channel reservoirs; about 3× the cost)",
    build: build,
};

/// `restir:<arg>`: [`Restir`] of [`preset`], or with `/channels=rgb` [`Channels`] of the preset
/// the other modifiers make (its target must be the luminance, which each channel's run
/// replaces), named `arg`.
fn build(arg: Option<&str>) -> Result<Method, String> {
    let arg = arg.ok_or("needs a preset, e.g. restir:hybrid")?;
    let mut parts = arg.split('/');
    let name = parts.next().unwrap_or_default();
    let (per_channel, others): (Vec<&str>, Vec<&str>) = parts.partition(|m| *m == "channels=rgb");
    if per_channel.is_empty() {
        return Ok(Method::new(Restir(preset(Some(arg))?)));
    }
    let spec: Vec<&str> = std::iter::once(name).chain(others).collect();
    let mut preset = preset(Some(&spec.join("/")))?;
    if preset.target != Target::Luminance {
        return Err(format!(
            "channels=rgb sets p̂ to each channel in turn; it cannot be combined with target={}",
            preset.target.name()
        ));
    }
    preset.name = arg.to_string();
    Ok(Method::new(Channels(preset)))
}

/// The frame pipeline with `0`'s passes.
#[derive(Clone, Debug, PartialEq)]
pub struct Restir(pub Preset);

/// The preset of `restir:<preset>[/modifier=value]…`: a registered preset, optionally modified by
/// `/temporal=<shift>` (the temporal pass's shift becomes the [`ShiftKind`] named `<shift>`),
/// `/spatial=<shift>` (the same for the spatial passes' one shift, [`Preset::with_spatial_shift`]),
/// `/cap=<κ>` (the temporal confidence cap, finite and > 0), `/spatial-cap=<κ>` (every spatial
/// pass's cap), `/neighbours=<n>` (every spatial pass's count), `/radius=<clamped|unclamped>`
/// (every spatial pass's [`RadiusRule`]), `/duplication=<ignored|divides>` ([`Duplication`]),
/// `/pairs=<independent|reciprocal>` (every spatial
/// pass's [`Pairs`]), `/target=<p̂>` (the [`Target`] named `p̂`) and
/// `/shade=<selected|all>` ([`Shade`]). A modified preset is named `arg`. `/channels=rgb` is
/// refused: it makes a method of three runs ([`Channels`]), not a preset.
pub fn preset(arg: Option<&str>) -> Result<Preset, String> {
    let arg = arg.ok_or("needs a preset, e.g. restir:hybrid")?;
    let mut parts = arg.split('/');
    let name = parts.next().unwrap_or_default();
    let mut preset = Preset::named(name).ok_or_else(|| {
        format!(
            "unknown preset {name:?}; known: {}",
            PRESET_NAMES.join(", ")
        )
    })?;
    for modifier in parts {
        preset = match modifier.split_once('=') {
            Some(("temporal", wanted)) => with_temporal_shift(preset, shift_named(wanted)?),
            Some(("spatial", wanted)) => preset.with_spatial_shift(shift_named(wanted)?)?,
            Some(("cap", value)) => preset.with_temporal_cap(positive(value)?),
            Some(("spatial-cap", value)) => preset.with_spatial_cap(positive(value)?),
            Some(("neighbours", value)) => {
                let count = value
                    .parse::<u32>()
                    .map_err(|_| format!("neighbours {value:?} is not a whole number"))?;
                preset.with_neighbours(count)
            }
            Some(("duplication", value)) => preset.with_duplication(
                Duplication::named(value)
                    .ok_or_else(|| format!("duplication {value:?} is not ignored or divides"))?,
            ),
            Some(("pairs", value)) => preset.with_pairs(
                Pairs::named(value)
                    .ok_or_else(|| format!("pairs {value:?} is not {}", PAIRS.join(" or ")))?,
            ),
            Some(("radius", value)) => preset.with_radius(
                RadiusRule::named(value)
                    .ok_or_else(|| format!("radius {value:?} is not clamped or unclamped"))?,
            ),
            Some(("target", value)) => Preset {
                target: Target::named(value)
                    .ok_or_else(|| format!("target {value:?} is not one of {TARGETS}"))?,
                ..preset
            },
            Some(("shade", "selected")) => Preset {
                shade: Shade::Selected,
                ..preset
            },
            Some(("shade", "all")) => Preset {
                shade: Shade::AllInputs,
                ..preset
            },
            Some(("channels", "rgb")) => {
                return Err("channels=rgb runs the preset once per channel: a method \
                            (restir:<preset>/channels=rgb), not one preset"
                    .into());
            }
            Some(("channels", value)) => {
                return Err(format!("channels {value:?} is not rgb"));
            }
            _ => {
                return Err(format!("unknown modifier {modifier:?}; known: {MODIFIERS}"));
            }
        };
    }
    preset.name = arg.to_string();
    // The method's spec names the preset already.
    preset
        .validate()
        .map_err(|e| format!("pass {}: {}", e.pass, e.reason))?;
    Ok(preset)
}

/// The modifiers [`preset`] knows, for its error message.
const MODIFIERS: &str = "temporal=<shift>, spatial=<shift>, cap=<κ>, spatial-cap=<κ>, neighbours=<n>, radius=<clamped|unclamped>, pairs=<independent|reciprocal>, duplication=<ignored|divides>, target=<luminance|mean|l2|red|green|blue>, shade=<selected|all>, channels=rgb";

/// The choices `/pairs=` knows ([`Pairs::ALL`]), for its error message.
const PAIRS: [&str; Pairs::ALL.len()] = {
    let mut names = [""; Pairs::ALL.len()];
    let mut i = 0;
    while i < names.len() {
        names[i] = Pairs::ALL[i].name();
        i += 1;
    }
    names
};

/// The targets `/target=` knows, for its error message.
const TARGETS: &str = "luminance, mean, l2, red, green, blue";

/// A confidence cap: a finite number > 0.
fn positive(value: &str) -> Result<f32, String> {
    value
        .parse::<f32>()
        .ok()
        .filter(|c| c.is_finite() && *c > 0.0)
        .ok_or_else(|| format!("cap {value:?} is not a number > 0"))
}

/// The registered [`ShiftKind`] named `wanted`.
fn shift_named(wanted: &str) -> Result<ShiftKind, String> {
    ShiftKind::named(wanted).ok_or_else(|| {
        let known: Vec<&str> = ShiftKind::ALL.iter().map(|k| k.name()).collect();
        format!("unknown shift {wanted:?}; known: {}", known.join(", "))
    })
}

/// `preset` with the shift of its temporal pass replaced by `kind`.
fn with_temporal_shift(mut preset: Preset, kind: ShiftKind) -> Preset {
    for pass in &mut preset.passes {
        if let PassSpec::Temporal { shift, .. } = pass {
            *shift = kind;
        }
    }
    preset
}

/// Every registered preset as a method.
pub fn all() -> Vec<Method> {
    Preset::all()
        .into_iter()
        .map(|p| Method::new(Restir(p)))
        .collect()
}

impl Estimator for Restir {
    fn name(&self) -> String {
        format!("restir:{}", self.0.name)
    }

    /// One BSSRDF candidate per pixel and frame.
    fn spp(&self) -> u32 {
        1
    }

    fn with_spp(&self, _spp: u32) -> Option<Method> {
        None
    }

    /// Streams pose the scene at each frame and evaluate temporal reuse's history in the
    /// previous frame's pose (`engine::reuse::Previous`).
    fn renders_motion(&self) -> bool {
        true
    }

    /// A stream of `frames` frames that keeps only the last image: memory does not grow with
    /// the frame count.
    fn render(
        &self,
        backend: &Backend,
        scene: &Scene,
        frames: u32,
        seed: u64,
    ) -> Result<LastFrame, PipelineError> {
        streamed(&self.0, backend, scene, frames, seed, Keep::Last)?.last_frame()
    }

    /// [`Estimator::render`]'s stream, ended early once `stop` says yes.
    fn render_until(
        &self,
        backend: &Backend,
        scene: &Scene,
        frames: u32,
        seed: u64,
        stop: &dyn Fn() -> bool,
    ) -> Result<(LastFrame, Option<SampleCounts>), PipelineError> {
        let run = streamed_until(&self.0, backend, scene, frames, seed, Keep::Last, stop)?;
        Ok((run.last_frame()?, None))
    }

    /// A stream of `frames` frames, every one kept.
    fn render_trajectory(
        &self,
        backend: &Backend,
        scene: &Scene,
        frames: u32,
        seed: u64,
    ) -> Result<Trajectory, PipelineError> {
        streamed(&self.0, backend, scene, frames, seed, Keep::Every)
    }
}

/// `frames` frames of `preset`'s stream for replica `seed`, keeping the images `keep` says.
fn streamed(
    preset: &Preset,
    backend: &Backend,
    scene: &Scene,
    frames: u32,
    seed: u64,
    keep: Keep,
) -> Result<Trajectory, PipelineError> {
    streamed_until(preset, backend, scene, frames, seed, keep, &|| false)
}

/// [`streamed`], ended early once `stop` says yes ([`Stream::run_until`]).
fn streamed_until(
    preset: &Preset,
    backend: &Backend,
    scene: &Scene,
    frames: u32,
    seed: u64,
    keep: Keep,
    stop: &dyn Fn() -> bool,
) -> Result<Trajectory, PipelineError> {
    let config = RunConfig {
        seed,
        frames,
        collect_diagnostics: false,
    };
    let run = Stream::new(backend, scene, preset, &config)?.run_until(frames, keep, stop)?;
    Ok(Trajectory {
        frames: run.frames,
        frames_rendered: run.frames_rendered,
        nonfinite: run.nan_count,
        counts: None,
        passes: run.timings,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A `restir` render whose stop check says yes on its third ask ends after 3 of 12 frames
    /// and returns, flagged as stopped, frame 2 bit for bit as a 3-frame render does. Controls:
    /// a check that never says yes gives the 12-frame render, unflagged; a path tracer, which is
    /// not streamed, ignores the check.
    #[test]
    fn a_stopped_stream_returns_the_last_frame_it_finished() {
        let mut scene = Scene::builtin("bumpy").unwrap();
        scene.camera = scene.camera.with_resolution(16, 12);
        let asks = std::cell::Cell::new(0);
        let third = || {
            asks.set(asks.get() + 1);
            asks.get() >= 3
        };
        let restir = Method::parse("restir:hybrid").unwrap();
        let stopped = restir
            .render_until(&Backend::Cpu, &scene, 12, 5, &third)
            .unwrap();
        let three = restir.render(&scene, 3, 5).unwrap();
        assert_eq!((stopped.stopped, stopped.frames_rendered), (true, 3));
        assert_eq!(stopped.image.bits(), three.image.bits());
        let never = restir
            .render_until(&Backend::Cpu, &scene, 12, 5, &|| false)
            .unwrap();
        let whole = restir.render(&scene, 12, 5).unwrap();
        assert_eq!((never.stopped, never.frames_rendered), (false, 12));
        assert_eq!(never.image.bits(), whole.image.bits());
        let pt = Method::parse("pt:1")
            .unwrap()
            .render_until(&Backend::Cpu, &scene, 12, 5, &|| true)
            .unwrap();
        assert_eq!((pt.stopped, pt.frames_rendered), (false, 1));
    }

    #[test]
    fn every_preset_parses_and_the_modifiers_apply() {
        for name in PRESET_NAMES {
            let method = Method::parse(&format!("restir:{name}")).unwrap();
            assert_eq!(method.name(), format!("restir:{name}"));
            assert_eq!(Method::parse(&method.name()).unwrap(), method);
        }
        assert_eq!(all().len(), PRESET_NAMES.len());
        let swapped = preset(Some("sequential/temporal=delayed")).unwrap();
        assert_eq!(swapped.name, "sequential/temporal=delayed");
        let temporal: Vec<_> = swapped
            .passes
            .iter()
            .filter_map(|p| match p {
                PassSpec::Temporal { shift, .. } => Some(*shift),
                _ => None,
            })
            .collect();
        assert_eq!(temporal, [ShiftKind::DelayedReconnection]);
        let parsed = Method::parse("restir:sequential/temporal=delayed").unwrap();
        assert_eq!(parsed.name(), "restir:sequential/temporal=delayed");
        let seed_001 = preset(Some("hybrid/cap=20")).unwrap();
        assert_eq!(seed_001.name, "hybrid/cap=20");
        assert_eq!(
            seed_001.passes,
            Preset::named("hybrid")
                .unwrap()
                .with_temporal_cap(20.0)
                .passes
        );
        let far = preset(Some("hybrid/spatial=distant-reconnection")).unwrap();
        assert_eq!(
            far.passes,
            Preset::named("hybrid")
                .unwrap()
                .with_spatial_shift(ShiftKind::DistantReconnection)
                .unwrap()
                .passes
        );
        let both = preset(Some("sequential/temporal=delayed/cap=1.5")).unwrap();
        assert_eq!(both.passes, swapped.with_temporal_cap(1.5).passes);
        let shaded = preset(Some("hybrid/shade=all/cap=20")).unwrap();
        assert_eq!(shaded.shade, Shade::AllInputs);
        assert_eq!(shaded.passes, seed_001.passes);
        assert_eq!(
            preset(Some("hybrid/shade=selected")).unwrap().shade,
            Shade::Selected
        );
        let ablated = preset(Some("hybrid/spatial-cap=2/neighbours=8")).unwrap();
        assert_eq!(
            ablated.passes,
            Preset::named("hybrid")
                .unwrap()
                .with_spatial_cap(2.0)
                .with_neighbours(8)
                .passes
        );
        let paired = preset(Some("sequential/pairs=reciprocal/neighbours=3")).unwrap();
        assert_eq!(
            paired.passes,
            Preset::named("sequential")
                .unwrap()
                .with_pairs(Pairs::Reciprocal)
                .with_neighbours(3)
                .passes
        );
        assert_eq!(
            preset(Some("hybrid/pairs=independent")).unwrap().passes,
            Preset::named("hybrid").unwrap().passes
        );
        let wide = Method::parse("restir:sequential/radius=unclamped").unwrap();
        assert_eq!(wide.name(), "restir:sequential/radius=unclamped");
        assert_eq!(
            preset(Some("sequential/radius=unclamped")).unwrap().passes,
            Preset::named("sequential")
                .unwrap()
                .with_radius(RadiusRule::Unclamped)
                .passes
        );
        assert_eq!(
            preset(Some("hybrid/radius=clamped")).unwrap().passes,
            Preset::named("hybrid").unwrap().passes
        );
        for target in Target::ALL {
            let spec = format!("hybrid/target={}", target.name());
            let p = preset(Some(&spec)).unwrap();
            assert_eq!(
                (p.target, &p.passes),
                (target, &Preset::named("hybrid").unwrap().passes)
            );
        }
        assert_eq!(preset(Some("hybrid")).unwrap().target, Target::Luminance);
        for spec in [
            "hybrid/channels=rgb/shade=all",
            "hybrid/shade=all/channels=rgb",
        ] {
            let method = Method::parse(&format!("restir:{spec}")).unwrap();
            assert_eq!(method.name(), format!("restir:{spec}"));
            let channels = Channels(Preset {
                name: spec.into(),
                ..preset(Some("hybrid/shade=all")).unwrap()
            });
            assert_eq!(format!("{method:?}"), format!("{channels:?}"));
            assert_eq!(channels.0.target, Target::Luminance);
        }
        let not_a_preset = preset(Some("hybrid/channels=rgb")).expect_err("channels=rgb");
        assert!(not_a_preset.contains("channels=rgb"), "{not_a_preset}");
        let mixed = Method::parse("restir:hybrid/channels=rgb/target=red").expect_err("mixed");
        assert!(mixed.to_string().contains("target=red"), "{mixed}");
        assert!(!mixed.to_string().contains('\n'), "{mixed}");
        let refused = Method::parse("restir:hybrid/radius=wide").expect_err("radius=wide");
        assert!(!refused.to_string().contains('\n'), "{refused}");
        assert!(refused.to_string().contains("wide"), "{refused}");
        for bad in [
            "restir:hybrid/spatial-cap=0",
            "restir:hybrid/neighbours=0",
            "restir:hybrid/neighbours=2.5",
            "restir:hybrid/neighbours=99",
            "restir:hybrid/shade=some",
            "restir:hybrid/radius=",
            "restir:hybrid/pairs=",
            "restir:hybrid/pairs=mirrored",
            "restir:hybrid/radius=Unclamped",
            "restir:hybrid/target=max",
            "restir:hybrid/channels=rg",
            "restir:hybrid/channels=",
            "restir:hybrid/channels=rgb/target=mean",
            "restir:hybrid/target=",
            "restir:hybrid/cap=0",
            "restir:hybrid/cap=-1",
            "restir:hybrid/cap=nan",
            "restir:hybrid/cap=inf",
            "restir:hybrid/nope=1",
            "restir:hybrid/cap",
            "restir:sequential/temporal=nope",
            "restir:nope/temporal=delayed",
            "restir:sequential/temporal=reconnection",
            "restir:hybrid/spatial=nope",
            "restir:sequential/spatial=delayed",
            "restir:delayed/spatial=reconnection",
        ] {
            assert_eq!(Method::parse(bad).expect_err(bad).spec, bad);
        }
    }
}
