//! The CPU time of the whole process as a criterion measurement, for the benches of this
//! crate that run on a loaded machine.

use criterion::measurement::{Measurement, ValueFormatter, WallTime};

/// CPU time of the whole process (every thread's, from `/proc/self/task/*/schedstat`), in
/// nanoseconds: unlike the wall time, hardly inflated by other processes on a loaded
/// machine. Time spent in threads that ended is not counted, so this is for work on
/// long-lived threads (rayon's pool, the bench's own). Shown as times, like the wall time.
pub struct ProcessCpu;

/// The formatter of the wall time: nanoseconds shown as a duration.
static WALL: WallTime = WallTime;

impl ProcessCpu {
    /// The process's CPU time so far in nanoseconds (0 where Linux's schedstat is missing).
    fn now() -> u64 {
        let Ok(tasks) = std::fs::read_dir("/proc/self/task") else {
            return 0;
        };
        tasks
            .filter_map(|t| std::fs::read_to_string(t.ok()?.path().join("schedstat")).ok())
            .filter_map(|s| s.split_whitespace().next()?.parse::<u64>().ok())
            .sum()
    }
}

impl Measurement for ProcessCpu {
    type Intermediate = u64;
    type Value = u64;

    fn start(&self) -> u64 {
        ProcessCpu::now()
    }
    fn end(&self, start: u64) -> u64 {
        ProcessCpu::now().saturating_sub(start)
    }
    fn add(&self, a: &u64, b: &u64) -> u64 {
        a + b
    }
    fn zero(&self) -> u64 {
        0
    }
    fn to_f64(&self, value: &u64) -> f64 {
        *value as f64
    }
    fn formatter(&self) -> &dyn ValueFormatter {
        WALL.formatter()
    }
}
