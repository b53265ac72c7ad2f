//! Growth by nutrient transport: the cost of growing a tree to N branches (1,000 to
//! 100,000; the feed is raised with N so the number of feedings stays near 60 and the cost
//! per branch is comparable), and a full stage sequence (10 stages, each meshed) against
//! the final stage alone. Besides criterion's wall-clock times, each size prints its mean
//! CPU time (on Linux). Figures: `benches/README.md`.

use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use glam::DVec3;
use pge_engine::{Algorithm, Location, RunContext};
use pge_growth::{Growth, GrowthParams, TransportParams, TransportTree};

/// Feeds a tree until it has at least `branches` branches; returns feedings taken.
fn grow_to(branches: usize, feed: f64) -> (u32, usize) {
    let params = TransportParams {
        feed,
        ..TransportParams::default()
    };
    let mut t = TransportTree::new(params, &[(DVec3::ZERO, DVec3::Y, 1.0)], 1);
    while t.len() < branches {
        t.feed(usize::MAX).expect("no cap");
    }
    (t.steps(), t.len())
}

/// Whether `feed` grows `branches` branches within 60 feedings.
fn fast_enough(branches: usize, feed: f64) -> bool {
    let params = TransportParams {
        feed,
        ..TransportParams::default()
    };
    let mut t = TransportTree::new(params, &[(DVec3::ZERO, DVec3::Y, 1.0)], 1);
    while t.len() < branches && t.steps() < 60 {
        t.feed(usize::MAX).expect("no cap");
    }
    t.len() >= branches
}

/// The feed that grows `branches` branches in at most 60 feedings (found once, outside the
/// timing): the smallest power of 2 that does.
fn feed_for(branches: usize) -> f64 {
    let mut feed = 1.0;
    while !fast_enough(branches, feed) {
        feed *= 2.0;
    }
    feed
}

/// Nanoseconds this thread has run on a CPU (Linux's schedstat), `None` elsewhere: on a
/// machine busy with other work, wall-clock time counts the waits for a core too.
fn cpu_nanos() -> Option<u64> {
    let stat = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    stat.split_whitespace().next()?.parse().ok()
}

/// Mean CPU milliseconds of growing to `branches` (over enough repetitions to average out
/// the scheduler's tick).
fn cpu_millis(branches: usize, feed: f64) -> Option<f64> {
    let reps = (2_000_000 / branches).clamp(4, 200);
    let start = cpu_nanos()?;
    for _ in 0..reps {
        black_box(grow_to(branches, feed));
    }
    Some((cpu_nanos()? - start) as f64 / 1e6 / reps as f64)
}

fn bench_transport(c: &mut Criterion) {
    let mut group = c.benchmark_group("transport");
    group.sample_size(10);
    for branches in [1_000usize, 3_000, 10_000, 20_000, 30_000, 100_000] {
        let feed = feed_for(branches);
        let (steps, n) = grow_to(branches, feed);
        let cpu = cpu_millis(branches, feed).map_or(String::new(), |ms| {
            format!(
                ", {ms:.2} ms of CPU time, {:.2} us per branch",
                ms * 1e3 / n as f64
            )
        });
        eprintln!("{branches} branches: feed {feed}, {steps} feedings, {n} branches{cpu}");
        group.throughput(Throughput::Elements(n as u64));
        group.bench_with_input(BenchmarkId::from_parameter(branches), &branches, |b, &n| {
            b.iter(|| grow_to(black_box(n), feed))
        });
    }
    group.finish();
}

/// Grows the default tree, meshing it after each stage in `stages`.
fn stages(stages: &[u32]) -> usize {
    let params = GrowthParams {
        steps: stages[stages.len() - 1],
        ..GrowthParams::default()
    };
    let mut g = Growth::new(params, Location::new("bench", 1)).expect("valid");
    let ctx = RunContext::default();
    g.init(&ctx).expect("init");
    let mut taken = 0;
    let mut triangles = 0;
    for &s in stages {
        while taken < s {
            g.step(&ctx).expect("step");
            taken += 1;
        }
        triangles += g.finish(&ctx).expect("model").triangle_count();
    }
    triangles
}

fn bench_stages(c: &mut Criterion) {
    let mut group = c.benchmark_group("stages");
    group.sample_size(10);
    let ten: Vec<u32> = (1..=10).map(|k| k * 20).collect();
    group.bench_function("final stage alone (200)", |b| {
        b.iter(|| stages(black_box(&[200])))
    });
    group.bench_function("10 stages (20, 40, ... 200)", |b| {
        b.iter(|| stages(black_box(&ten)))
    });
    group.finish();
}

criterion_group!(benches, bench_transport, bench_stages);
criterion_main!(benches);
