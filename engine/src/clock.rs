//! The clock work on a backend is timed with, so that equal-time figures do not depend on who
//! else uses the machine: on the CPU backend the process's CPU time
//! (`clock_gettime(CLOCK_PROCESS_CPUTIME_ID)`: user + system time of every thread of the
//! process), on a Vulkan device the wall clock. A [`Stopwatch`] reads both, so a report shows
//! the wall time beside the clock its equal-time figures count.
//!
//! Process CPU time is the render's own threads' time because nothing else in the process works
//! while a render runs: the calling thread blocks in rayon until the frame is done, and rayon's
//! workers do the render's work. It counts rayon's idle spinning (a worker that runs out of
//! work yields up to 33 times before it sleeps, `rayon-core` 1.13 `sleep/mod.rs`) and the CLI's
//! progress-bar tick (a redraw every 250 ms), both small; it does not count the time other
//! processes take from the cores, which is what wall time is most sensitive to on a shared
//! machine. A Vulkan device's work is not the process's CPU time on a GPU (on lavapipe it would
//! be, its threads being in the process), so one clock serves every Vulkan device: the wall
//! clock, with the read-back included.

use std::time::{Duration, Instant};

use crate::Backend;

/// What [`Timing::seconds`] counts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Clock {
    /// CPU time of the process's threads (the CPU backend).
    ProcessCpu,
    /// Elapsed real time (a Vulkan device, or a platform without a process CPU clock).
    Wall,
}

impl Clock {
    /// The clock work on `backend` is timed with.
    pub fn of(backend: &Backend) -> Clock {
        match backend {
            Backend::Cpu if process_cpu_time().is_some() => Clock::ProcessCpu,
            _ => Clock::Wall,
        }
    }

    /// How reports name it.
    pub fn name(self) -> &'static str {
        match self {
            Clock::ProcessCpu => "process CPU time",
            Clock::Wall => "wall time",
        }
    }
}

/// Seconds of some work on its backend's [`Clock`], and the wall-clock seconds beside them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Timing {
    pub clock: Clock,
    /// Seconds on `clock`: the figure equal-time budgets and efficiencies count.
    pub seconds: f64,
    /// Wall-clock seconds.
    pub wall_seconds: f64,
}

impl Timing {
    /// Both figures divided by `n` (at least 1): the time per frame of `n` frames.
    pub fn per(self, n: u32) -> Timing {
        let n = n.max(1) as f64;
        Timing {
            seconds: self.seconds / n,
            wall_seconds: self.wall_seconds / n,
            ..self
        }
    }
}

/// Times work on one backend from [`Stopwatch::start`] to [`Stopwatch::read`].
pub struct Stopwatch {
    clock: Clock,
    wall: Instant,
    cpu: Option<Duration>,
}

impl Stopwatch {
    /// Starts timing work on `backend`.
    pub fn start(backend: &Backend) -> Stopwatch {
        let clock = Clock::of(backend);
        Stopwatch {
            clock,
            cpu: (clock == Clock::ProcessCpu)
                .then(process_cpu_time)
                .flatten(),
            wall: Instant::now(),
        }
    }

    /// The time since [`Stopwatch::start`].
    pub fn read(&self) -> Timing {
        let wall_seconds = self.wall.elapsed().as_secs_f64();
        let cpu = self
            .cpu
            .zip(process_cpu_time())
            .map(|(start, now)| now.saturating_sub(start).as_secs_f64());
        Timing {
            clock: self.clock,
            seconds: cpu.unwrap_or(wall_seconds),
            wall_seconds,
        }
    }
}

/// CPU time of the process (`CLOCK_PROCESS_CPUTIME_ID`, nanosecond resolution), `None` where
/// the platform has none.
#[cfg(unix)]
fn process_cpu_time() -> Option<Duration> {
    let mut now = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `now` is a valid, writable timespec.
    let status = unsafe { libc::clock_gettime(libc::CLOCK_PROCESS_CPUTIME_ID, &mut now) };
    (status == 0).then(|| Duration::new(now.tv_sec as u64, now.tv_nsec as u32))
}

#[cfg(not(unix))]
fn process_cpu_time() -> Option<Duration> {
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn timing_per_frame() {
        let t = Timing {
            clock: Clock::Wall,
            seconds: 2.0,
            wall_seconds: 4.0,
        };
        let p = t.per(4);
        assert_eq!(
            (p.seconds, p.wall_seconds, p.clock),
            (0.5, 1.0, Clock::Wall)
        );
        assert_eq!(t.per(0), t, "no frames: the whole time");
    }
}
