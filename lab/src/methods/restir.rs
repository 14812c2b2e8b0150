//! `restir:<preset>[/temporal=<shift>]`: the ReSTIR SSS frame pipeline with a registered preset
//! [001 §5.1] (DESIGN §6). Every frame of the trajectory is rendered (temporal reuse) and the
//! last one is kept; `/temporal=<shift>` swaps the shift of the temporal pass [001 Fig. 10].
//!
//! The only file of the lab that names presets and shift kinds: when presets move crates, the
//! import below is the one to change.

use engine::{Backend, PassSpec, PipelineError, Preset, RunConfig, ShiftKind};
use shifts::preset::PRESET_NAMES;
use sss::scene::Scene;

use super::estimator::{Entry, Estimator, Frame, Method};

pub const ENTRY: Entry = Entry {
    family: "restir",
    usage: "restir:<reconnection|delayed|hybrid|sequential|sequential-exact>[/temporal=<shift>]",
    about: "ReSTIR SSS with spatiotemporal reuse and the preset's shift mapping [001 §5.1]; \
            `/temporal=<shift>` swaps the temporal pass's shift (001 Fig. 10)",
    build: |arg| Ok(Method::new(Restir(preset(arg)?))),
};

/// The frame pipeline with `0`'s passes.
#[derive(Clone, Debug, PartialEq)]
pub struct Restir(pub Preset);

/// The preset of `restir:<arg>`: a registered preset, optionally with the shift of its temporal
/// pass replaced by the [`ShiftKind`] named after `/temporal=` (the preset is then named `arg`).
pub fn preset(arg: Option<&str>) -> Result<Preset, String> {
    let arg = arg.ok_or("needs a preset, e.g. restir:hybrid")?;
    let (name, temporal) = match arg.split_once("/temporal=") {
        Some((name, shift)) => (name, Some(shift)),
        None => (arg, None),
    };
    let mut preset = Preset::named(name).ok_or_else(|| {
        format!(
            "unknown preset {name:?}; known: {}",
            PRESET_NAMES.join(", ")
        )
    })?;
    if let Some(wanted) = temporal {
        let kind = ShiftKind::ALL
            .into_iter()
            .find(|k| k.name() == wanted)
            .ok_or_else(|| {
                let known: Vec<&str> = ShiftKind::ALL.iter().map(|k| k.name()).collect();
                format!("unknown shift {wanted:?}; known: {}", known.join(", "))
            })?;
        for pass in &mut preset.passes {
            if let PassSpec::Temporal { shift, .. } = pass {
                *shift = kind;
            }
        }
        preset.name = arg.to_string();
        preset.validate().map_err(|e| e.to_string())?;
    }
    Ok(preset)
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

    fn render(
        &self,
        backend: &Backend,
        scene: &Scene,
        frames: u32,
        seed: u64,
    ) -> Result<Frame, PipelineError> {
        let config = RunConfig {
            seed,
            frames,
            collect_diagnostics: false,
        };
        let mut result = backend.run(scene, &self.0, &config)?;
        let image = result
            .frames
            .pop()
            .ok_or_else(|| PipelineError::Config("the run returned no frame".into()))?;
        Ok(Frame {
            image,
            frames_rendered: frames,
            nonfinite: result.nan_count,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_preset_parses_and_the_temporal_shift_swaps() {
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
        for bad in [
            "restir:sequential/temporal=nope",
            "restir:nope/temporal=delayed",
            "restir:sequential/temporal=reconnection",
        ] {
            assert_eq!(Method::parse(bad).expect_err(bad).spec, bad);
        }
    }
}
