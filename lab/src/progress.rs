//! How long jobs report progress and learn that they should stop: the caller implements
//! [`Progress`] (the CLI draws bars and reads its Ctrl-C flag); [`Silent`] does nothing.
//! A job that sees [`Progress::stop_requested`] finishes its current unit of work (a replica,
//! a reference batch) and returns what it has.

/// Progress of a job made of phases of counted steps.
pub trait Progress {
    /// A phase of `total` steps called `what` begins, `done` of them already finished.
    fn begin(&mut self, what: &str, total: u64, done: u64) {
        let _ = (what, total, done);
    }

    /// The item the next steps belong to (a method's name).
    fn item(&mut self, name: &str) {
        let _ = name;
    }

    /// One step of the phase is finished.
    fn step(&mut self) {}

    /// The phase is over.
    fn end(&mut self) {}

    /// Whether the caller asked the job to stop after the current step.
    fn stop_requested(&self) -> bool {
        false
    }
}

/// No output, never stops.
pub struct Silent;

impl Progress for Silent {}
