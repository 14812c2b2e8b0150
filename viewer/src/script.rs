//! Scripted input (`reshift view --script FILE`): one action a line, run one per displayed
//! frame, so a test or a demo drives the window as a person would. Blank lines and `#`
//! comments are skipped.
//!
//! ```text
//! wait 3                      # let 3 frames pass
//! key p                       # a key press (input::key_command)
//! preset delayed              # = method restir:delayed
//! method pt:4                 # any method specification
//! orbit 40 -10                # turn by (dx, dy) input units, as a mouse drag of that many pixels
//! move 0.2 0                  # forward, right, as fractions of the eye–target distance
//! screenshot out/a.png        # what the window shows, as PNG
//! close                       # close the window
//! ```

use std::collections::VecDeque;
use std::path::Path;

use crate::input::{Command, key_command};

/// One line of a script.
#[derive(Clone, Debug, PartialEq)]
pub enum Step {
    /// Let this many displayed frames pass.
    Wait(u32),
    Do(Command),
}

/// The steps left to run.
#[derive(Debug, Default)]
pub struct Script {
    steps: VecDeque<Step>,
}

impl Script {
    /// Reads `path`; a bad line is one error naming the file, line and text.
    pub fn load(path: &Path) -> Result<Script, String> {
        let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
        Script::parse(&text).map_err(|(line, why)| format!("{}:{line}: {why}", path.display()))
    }

    /// Parses script text; an error is `(line number, reason)`.
    pub fn parse(text: &str) -> Result<Script, (usize, String)> {
        let mut steps = VecDeque::new();
        for (i, line) in text.lines().enumerate() {
            let line = line.split('#').next().unwrap_or_default().trim();
            if line.is_empty() {
                continue;
            }
            steps.push_back(step(line).map_err(|why| (i + 1, format!("{line:?}: {why}")))?);
        }
        Ok(Script { steps })
    }

    /// The command of this displayed frame, if any (a `wait` takes its frames first).
    pub fn next(&mut self) -> Option<Command> {
        match self.steps.pop_front()? {
            Step::Wait(0) => self.next(),
            Step::Wait(n) => {
                self.steps.push_front(Step::Wait(n - 1));
                None
            }
            Step::Do(command) => Some(command),
        }
    }

    /// Whether steps are left.
    pub fn pending(&self) -> bool {
        !self.steps.is_empty()
    }
}

/// One non-empty line.
fn step(line: &str) -> Result<Step, String> {
    let (word, rest) = line.split_once(char::is_whitespace).unwrap_or((line, ""));
    let rest = rest.trim();
    let numbers = |count: usize| -> Result<Vec<f32>, String> {
        let values: Vec<f32> = rest
            .split_whitespace()
            .map(|v| v.parse::<f32>().ok().filter(|v| v.is_finite()))
            .collect::<Option<_>>()
            .ok_or("expected numbers")?;
        if values.len() != count {
            return Err(format!("expected {count} numbers"));
        }
        Ok(values)
    };
    let argument = || {
        (!rest.is_empty())
            .then(|| rest.to_string())
            .ok_or("needs an argument")
    };
    Ok(Step::Do(match word {
        "wait" => {
            return rest
                .parse()
                .map(Step::Wait)
                .map_err(|_| "expected a whole number of frames".into());
        }
        "key" => key_command(rest).ok_or("unknown key")?,
        "preset" => Command::Method(format!("restir:{}", argument()?)),
        "method" => Command::Method(argument()?),
        "orbit" => {
            let v = numbers(2)?;
            Command::Turn(v[0], v[1])
        }
        "move" => {
            let v = numbers(2)?;
            Command::Move(v[0], v[1])
        }
        "screenshot" => Command::Screenshot(argument()?.into()),
        "close" => Command::Close,
        _ => {
            return Err(
                "unknown action (wait, key, preset, method, orbit, move, screenshot, close)".into(),
            );
        }
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_script_runs_one_action_per_frame_after_its_waits() {
        let mut script =
            Script::parse("# demo\nwait 2\nkey p\n\npreset delayed # comment\norbit 4 -1\nclose\n")
                .unwrap();
        assert_eq!(script.next(), None);
        assert_eq!(script.next(), None);
        assert_eq!(script.next(), Some(Command::NextPreset));
        assert_eq!(
            script.next(),
            Some(Command::Method("restir:delayed".into()))
        );
        assert_eq!(script.next(), Some(Command::Turn(4.0, -1.0)));
        assert!(script.pending());
        assert_eq!(script.next(), Some(Command::Close));
        assert!(!script.pending());
        assert_eq!(script.next(), None);
    }

    #[test]
    fn a_bad_line_is_named_with_its_number() {
        for (text, line) in [
            ("wait x", 1),
            ("\nkey F13", 2),
            ("orbit 1", 1),
            ("orbit 1 nan", 1),
            ("screenshot", 1),
            ("fly", 1),
        ] {
            let (at, why) = Script::parse(text).expect_err(text);
            assert_eq!(at, line, "{text}: {why}");
        }
    }
}
