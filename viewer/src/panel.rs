//! The control panel (egui): the method picker and its specification, the ReSTIR preset's
//! per-pass options the method grammar has (`/temporal=`, `/spatial=`, `/neighbours=`,
//! `/shade=all`), the camera mode, the error-view and denoiser toggles, and what the displayed
//! frame cost (per pass for ReSTIR) with its running MSE. It returns [`Command`]s, like the
//! keyboard, and changes nothing itself.

use engine::{Preset, ShiftKind};
use methods::{REGISTRY, restir as restir_method};

use crate::input::Command;
use crate::session::Frame;

/// Width of the panel in points.
pub const PANEL_WIDTH: f32 = 300.0;

/// What the panel shows besides its own state.
pub struct Status<'a> {
    pub scene: &'a str,
    pub backend: String,
    pub presenter: &'a str,
    pub method: String,
    pub frame: Option<&'a Frame>,
    pub mse: Option<f64>,
    pub reference_spp: u32,
    pub mode: &'static str,
    pub error_view: bool,
    pub denoise: bool,
    /// The last failure (a method the backend cannot run, …), one line.
    pub message: Option<&'a str>,
}

/// The panel's own state: the specification being edited.
pub struct Panel {
    spec: String,
    preset: String,
    temporal: Option<ShiftKind>,
    spatial: Option<ShiftKind>,
    /// Spatial neighbours; 0: the preset's.
    neighbours: u32,
    shade_all: bool,
}

/// Every method the picker offers: each family with its default argument, and every registered
/// ReSTIR preset.
pub fn choices() -> Vec<String> {
    let mut out = Vec::new();
    for entry in REGISTRY {
        if entry.family == restir_method::ENTRY.family {
            out.extend(Preset::all().iter().map(|p| format!("restir:{}", p.name)));
        } else if let Ok(method) = (entry.build)(None) {
            out.push(method.name());
        }
    }
    out
}

impl Panel {
    pub fn new(spec: &str) -> Panel {
        let preset = spec
            .strip_prefix("restir:")
            .and_then(|s| s.split('/').next())
            .unwrap_or("hybrid")
            .to_string();
        Panel {
            spec: spec.to_string(),
            preset,
            temporal: None,
            spatial: None,
            neighbours: 0,
            shade_all: false,
        }
    }

    /// Follows a method chosen elsewhere (a key, a script).
    pub fn follow(&mut self, spec: &str) {
        *self = Panel::new(spec);
    }

    /// `restir:<preset>` with the chosen per-pass modifiers.
    fn restir_spec(&self) -> String {
        let mut spec = format!("restir:{}", self.preset);
        if let Some(k) = self.temporal {
            spec += &format!("/temporal={}", k.name());
        }
        if let Some(k) = self.spatial {
            spec += &format!("/spatial={}", k.name());
        }
        if self.neighbours > 0 {
            spec += &format!("/neighbours={}", self.neighbours);
        }
        if self.shade_all {
            spec += "/shade=all";
        }
        spec
    }

    /// Draws the panel into `ui`; the commands its widgets gave.
    pub fn show(&mut self, ui: &mut egui::Ui, status: &Status) -> Vec<Command> {
        let mut commands = Vec::new();
        ui.heading("reshift view");
        ui.label(format!("scene {} on {}", status.scene, status.backend));
        ui.label(format!("window on {}", status.presenter));
        ui.separator();
        egui::ComboBox::from_label("method")
            .selected_text(&status.method)
            .show_ui(ui, |ui| {
                for choice in choices() {
                    if ui
                        .selectable_label(choice == status.method, &choice)
                        .clicked()
                    {
                        commands.push(Command::Method(choice));
                    }
                }
            });
        ui.horizontal(|ui| {
            ui.add(egui::TextEdit::singleline(&mut self.spec).desired_width(PANEL_WIDTH - 80.0));
            if ui.button("apply").clicked() {
                commands.push(Command::Method(self.spec.clone()));
            }
        });
        if status.method.starts_with("restir:") {
            self.restir_options(ui, &mut commands);
        }
        ui.separator();
        ui.horizontal(|ui| {
            ui.label(format!("camera: {} (M)", status.mode));
            let mut error = status.error_view;
            if ui.checkbox(&mut error, "error (E)").changed() {
                commands.push(Command::ToggleError);
            }
            let mut denoise = status.denoise;
            if ui.checkbox(&mut denoise, "SVGF (N)").changed() {
                commands.push(Command::ToggleDenoise);
            }
        });
        ui.separator();
        self.stats(ui, status);
        commands
    }

    /// The preset's passes and the per-pass options the grammar has.
    fn restir_options(&mut self, ui: &mut egui::Ui, commands: &mut Vec<Command>) {
        let before = self.restir_spec();
        egui::ComboBox::from_label("preset")
            .selected_text(&self.preset)
            .show_ui(ui, |ui| {
                for p in Preset::all() {
                    ui.selectable_value(&mut self.preset, p.name.clone(), &p.name);
                }
            });
        for (label, slot) in [
            ("temporal shift", &mut self.temporal),
            ("spatial shift", &mut self.spatial),
        ] {
            egui::ComboBox::from_label(label)
                .selected_text(slot.map_or("the preset's", |k| k.name()))
                .show_ui(ui, |ui| {
                    ui.selectable_value(slot, None, "the preset's");
                    for k in ShiftKind::ALL {
                        ui.selectable_value(slot, Some(k), k.name());
                    }
                });
        }
        ui.horizontal(|ui| {
            ui.add(egui::DragValue::new(&mut self.neighbours).range(0..=32));
            ui.label("neighbours (0: the preset's)");
        });
        ui.checkbox(&mut self.shade_all, "shade with all inputs");
        let after = self.restir_spec();
        if after != before {
            self.spec = after.clone();
            commands.push(Command::Method(after));
        }
        if let Ok(preset) = restir_method::preset(self.spec.strip_prefix("restir:")) {
            ui.small(preset.describe());
        }
    }

    /// Frame time (per pass for ReSTIR) and the running MSE.
    fn stats(&self, ui: &mut egui::Ui, status: &Status) {
        if let Some(frame) = status.frame {
            for (label, seconds) in &frame.timings {
                ui.monospace(format!("{:8.2} ms  {label}", 1e3 * seconds));
            }
            ui.monospace(format!(
                "{:8.2} ms  wall, {} frames",
                1e3 * frame.wall_seconds,
                frame.window
            ));
            if let Some(live) = frame.live {
                ui.monospace(format!(
                    "live frame {}, mean confidence {:.2}",
                    live.index, live.confidence
                ));
            }
            if frame.nonfinite > 0 {
                ui.label(format!("{} non-finite values", frame.nonfinite));
            }
        }
        let mse = status.mse.map_or("—".into(), |m| format!("{m:.3e}"));
        ui.monospace(format!(
            "MSE {mse} vs reference of {} spp",
            status.reference_spp
        ));
        if let Some(message) = status.message {
            ui.colored_label(egui::Color32::LIGHT_RED, message);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use methods::Method;

    #[test]
    fn every_choice_is_a_method_and_every_preset_is_offered() {
        let choices = choices();
        for choice in &choices {
            assert_eq!(&Method::parse(choice).unwrap().name(), choice);
        }
        for preset in Preset::all() {
            assert!(choices.contains(&format!("restir:{}", preset.name)));
        }
        assert!(choices.contains(&"pt:1".to_string()));
    }

    #[test]
    fn the_per_pass_options_compose_a_specification_the_parser_takes() {
        let mut panel = Panel::new("restir:sequential/cap=2");
        assert_eq!(panel.preset, "sequential");
        panel.temporal = Some(ShiftKind::DelayedReconnection);
        panel.neighbours = 3;
        panel.shade_all = true;
        let spec = panel.restir_spec();
        assert_eq!(Method::parse(&spec).unwrap().name(), spec);
        assert!(spec.contains("/temporal=") && spec.ends_with("/neighbours=3/shade=all"));
    }
}
