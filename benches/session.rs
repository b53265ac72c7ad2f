//! The cost of a session of the batteries-included engine (for the whole-oak row of
//! benches/README.md: what `pge run` spends besides the phases): `Engine::session` (a Lua
//! state, its libraries and every plugin's tables), and a session that runs the oak's script
//! (the `script` phase), in CPU time of the process (`/proc/self/task/*/schedstat`: hardly
//! inflated by other processes on a loaded machine; it advances in scheduler ticks, so each
//! sample runs hundreds of sessions).

// The process's CPU time, the measurement the tree crate's benches use too: a session runs
// on the calling thread alone, so this is that thread's time.
#[path = "../crates/pge-tree/benches/common/cpu.rs"]
mod cpu;

use cpu::ProcessCpu;
use criterion::{Criterion, SamplingMode, criterion_group, criterion_main};
use std::hint::black_box;

fn session(c: &mut Criterion<ProcessCpu>) {
    let engine = pge::default_engine().build().expect("engine");
    let mut group = c.benchmark_group("session");
    // The CPU time advances in scheduler ticks: every sample runs many sessions.
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
    config = Criterion::default().with_measurement(ProcessCpu);
    targets = session
}
criterion_main!(benches);
