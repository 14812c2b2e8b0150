//! The CPU backend's clock ([`engine::clock`]) measured in a process of its own: process CPU
//! time counts every thread of the process, so tests running beside it in one binary would be
//! counted too. One test, its two checks in sequence, for the same reason.
#![cfg(unix)]

use std::time::Duration;

use engine::Backend;
use engine::clock::{Clock, Stopwatch};

/// Waiting advances the wall clock and not the process's CPU time; work on rayon's threads
/// is counted (a spin of 0.1 s of CPU time on every worker reads at least that many times
/// 0.1 s), however many other processes share the cores.
#[test]
fn process_cpu_time_counts_the_workers_and_not_the_waiting() {
    assert_eq!(Clock::of(&Backend::Cpu), Clock::ProcessCpu);
    let watch = Stopwatch::start(&Backend::Cpu);
    std::thread::sleep(Duration::from_millis(200));
    let t = watch.read();
    assert_eq!(t.clock, Clock::ProcessCpu);
    assert!(t.wall_seconds >= 0.2, "{t:?}");
    // The test harness's own threads idle; 20 ms is generous for what they use.
    assert!(t.seconds < 0.02, "{t:?}");

    let threads = rayon::current_num_threads();
    let watch = Stopwatch::start(&Backend::Cpu);
    rayon::broadcast(|_| spin_cpu(Duration::from_millis(100)));
    let t = watch.read();
    assert!(
        t.seconds >= 0.1 * threads as f64,
        "{threads} threads: {t:?}"
    );
}

/// Spins until the calling thread has used `cpu` of CPU time.
fn spin_cpu(cpu: Duration) {
    let thread_time = || {
        let mut now = libc::timespec {
            tv_sec: 0,
            tv_nsec: 0,
        };
        // SAFETY: `now` is a valid, writable timespec.
        unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut now) };
        Duration::new(now.tv_sec as u64, now.tv_nsec as u32)
    };
    let start = thread_time();
    while thread_time() - start < cpu {}
}
