//! The cost of a session of the batteries-included engine (issue 14, the whole oak: what
//! `pge run` spends besides the phases): `Engine::session` (a Lua state, its libraries and
//! every plugin's tables), and a session that runs the oak's script (the `script` phase), in
//! CPU time of the benchmarking thread (`/proc/thread-self/schedstat`: hardly inflated by
//! other processes on a loaded machine; it advances in scheduler ticks, so each sample runs
//! hundreds of sessions).

use criterion::measurement::{Measurement, ValueFormatter, WallTime};
use criterion::{Criterion, SamplingMode, criterion_group, criterion_main};
use std::hint::black_box;

/// CPU time of the calling thread in nanoseconds (0 where Linux's schedstat is missing).
struct ThreadCpu;

/// The formatter of the wall time: nanoseconds shown as a duration.
static WALL: WallTime = WallTime;

impl ThreadCpu {
    fn now() -> u64 {
        std::fs::read_to_string("/proc/thread-self/schedstat")
            .ok()
            .and_then(|s| s.split_whitespace().next()?.parse().ok())
            .unwrap_or(0)
    }
}

impl Measurement for ThreadCpu {
    type Intermediate = u64;
    type Value = u64;

    fn start(&self) -> u64 {
        ThreadCpu::now()
    }
    fn end(&self, start: u64) -> u64 {
        ThreadCpu::now().saturating_sub(start)
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

fn session(c: &mut Criterion<ThreadCpu>) {
    let engine = pge::default_engine().build().expect("engine");
    let mut group = c.benchmark_group("session");
    // The thread's CPU time advances in scheduler ticks: every sample runs many sessions.
    group.sampling_mode(SamplingMode::Flat).sample_size(20);
    group.bench_function("new", |b| {
        b.iter(|| black_box(engine.session(Default::default()).expect("session")));
    });
    let oak = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/species/oak.lua");
    group.bench_function("new and the oak's script", |b| {
        b.iter(|| {
            let session = engine.session(Default::default()).expect("session");
            let value = session.run_script(&oak).expect("the oak's script runs");
            black_box((value, session))
        });
    });
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().with_measurement(ThreadCpu);
    targets = session
}
criterion_main!(benches);
