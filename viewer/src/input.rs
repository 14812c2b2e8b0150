//! What the viewer can be told to do ([`Command`]), from the keyboard ([`key_command`]), the
//! panel or a script: one set of commands, so a scripted `key` is the key press itself.

use std::path::PathBuf;

/// Input units of a turn per arrow-key press (a unit is a pixel of mouse drag).
const KEY_TURN: f32 = 10.0;

/// A move per key press, as a fraction of the eye–target distance.
const KEY_STEP: f32 = 0.1;

/// One thing the viewer does.
#[derive(Clone, Debug, PartialEq)]
pub enum Command {
    /// Turn by `(dx, dy)` input units (orbit round the target, or look about the eye).
    Turn(f32, f32),
    /// Move `(forward, right)` as fractions of the eye–target distance (orbit: dolly).
    Move(f32, f32),
    /// Switch between orbit and fly controls.
    ToggleMode,
    /// Show the false-colour error against the progressive reference instead of the image.
    ToggleError,
    /// Denoise displayed frames (SVGF over the window).
    ToggleDenoise,
    /// Render with this method specification (`reshift methods`).
    Method(String),
    /// The next registered ReSTIR preset (from a ReSTIR method; else the first).
    NextPreset,
    /// Write what the window shows to this PNG.
    Screenshot(PathBuf),
    /// Close the window (as its close button does).
    Close,
}

/// The command of the key named `name` (winit's logical key name or a letter, any case):
/// arrows turn, W/S move forward/back, A/D sideways, M switches orbit/fly, E the error view, N
/// the denoiser, P the next preset, Q or Escape close.
pub fn key_command(name: &str) -> Option<Command> {
    Some(match name.to_ascii_lowercase().as_str() {
        "arrowleft" | "left" => Command::Turn(-KEY_TURN, 0.0),
        "arrowright" | "right" => Command::Turn(KEY_TURN, 0.0),
        "arrowup" | "up" => Command::Turn(0.0, -KEY_TURN),
        "arrowdown" | "down" => Command::Turn(0.0, KEY_TURN),
        "w" => Command::Move(KEY_STEP, 0.0),
        "s" => Command::Move(-KEY_STEP, 0.0),
        "a" => Command::Move(0.0, -KEY_STEP),
        "d" => Command::Move(0.0, KEY_STEP),
        "m" => Command::ToggleMode,
        "e" => Command::ToggleError,
        "n" => Command::ToggleDenoise,
        "p" => Command::NextPreset,
        "q" | "escape" => Command::Close,
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_map_to_commands_in_any_case_and_unknown_keys_to_none() {
        assert_eq!(
            key_command("ArrowLeft"),
            Some(Command::Turn(-KEY_TURN, 0.0))
        );
        assert_eq!(key_command("P"), key_command("p"));
        assert_eq!(key_command("Escape"), Some(Command::Close));
        assert_eq!(key_command("F13"), None);
    }
}
