//! Space colonization's growth phase (every step after `init`, no meshing) from 1,000 to
//! 1,000,000 attraction points in the same ellipsoid crown, and a complete small tree from
//! script to glb bytes in memory, and the small oak's points and growth (its script's
//! parameters).
//!
//! The growth phase should cost time linear in the points: the per-point figure
//! (criterion's throughput) stays about flat along the curve.

use std::hint::black_box;
use std::path::Path;

use criterion::{
    BatchSize, BenchmarkId, Criterion, SamplingMode, Throughput, criterion_group, criterion_main,
};
use glam::Vec3;
use pge_engine::{Algorithm, Engine, Location, RunContext, SessionOptions, Step};
use pge_spacecol::{Params, Shape, SpaceColonization, SpaceColonizationPlugin};

fn crown(points: u32) -> Params {
    let mut p = Params::new(Shape::Ellipsoid {
        center: Vec3::new(0.0, 7.0, 0.0),
        radii: Vec3::new(4.0, 3.5, 4.0),
    });
    p.points = Some(points);
    p.step = 0.2;
    p.influence = 1.6;
    p.kill = 0.4;
    p
}

/// A colonization of `points` points, initialised (its points drawn).
fn initialised(points: u32) -> SpaceColonization {
    let mut sc = SpaceColonization::new(crown(points), Location::new("bench", 1)).expect("valid");
    sc.init(&RunContext::default()).expect("init");
    sc
}

/// Grows to the end without meshing; returns the node count.
fn grow(mut sc: SpaceColonization) -> usize {
    let ctx = RunContext::default();
    while sc.step(&ctx).expect("step") == Step::Continue {}
    sc.skeleton().map_or(0, |s| s.len())
}

fn bench_colonize(c: &mut Criterion) {
    let mut group = c.benchmark_group("colonize growth");
    // Criterion's minimum: ten runs, one growth each (a million points take seconds).
    group.sample_size(10);
    group.sampling_mode(SamplingMode::Flat);
    for points in [1_000u32, 10_000, 100_000, 1_000_000] {
        group.throughput(Throughput::Elements(u64::from(points)));
        group.bench_with_input(BenchmarkId::from_parameter(points), &points, |b, &n| {
            b.iter_batched(
                || initialised(black_box(n)),
                |sc| black_box(grow(sc)),
                BatchSize::PerIteration,
            )
        });
    }
    group.finish();
}

/// The parameters `scripts/species/oak.lua` gives (3,000 points in a wide, flattened
/// crown above the root, a slight upward tropism), seeded as `pge run` seeds it.
fn oak() -> Params {
    let mut p = Params::new(Shape::Ellipsoid {
        center: Vec3::new(0.0, 6.4, 0.0),
        radii: Vec3::new(5.5, 3.2, 4.95),
    });
    p.points = Some(3000);
    p.step = 0.3;
    p.influence = 2.4;
    p.kill = 0.6;
    p.tropism = Vec3::new(0.0, 0.05, 0.0);
    p
}

/// The small oak's points and growth (`init` and every step, no meshing): the `points` and
/// `growth` phases of `pge run scripts/species/oak.lua --stats`.
fn bench_oak(c: &mut Criterion) {
    let params = oak();
    let ctx = RunContext::default();
    let run = || {
        let mut sc =
            SpaceColonization::new(params.clone(), Location::new("oak", 1)).expect("valid");
        sc.init(&ctx).expect("init");
        while sc.step(&ctx).expect("step") == Step::Continue {}
        sc.iterations()
    };
    let iterations = run();
    c.bench_function(&format!("colonize oak: {iterations} iterations"), |b| {
        b.iter(|| black_box(run()))
    });
}

fn bench_script_to_glb(c: &mut Criterion) {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/small_tree.lua");
    let engine = Engine::builder()
        .plugin(SpaceColonizationPlugin)
        .build()
        .expect("engine");
    let run = || {
        let session = engine.session(SessionOptions::default()).expect("session");
        let generated = session
            .generate(&script, &mut |_, _| {})
            .expect("generates");
        let glb =
            pge_engine::export::glb_bytes(&generated.model, &Default::default()).expect("glb");
        (generated.model.triangle_count(), glb.len())
    };
    let (triangles, bytes) = run();
    c.bench_function(
        &format!("script to glb: {triangles} triangles, {bytes} bytes"),
        |b| b.iter(run),
    );
}

criterion_group!(benches, bench_colonize, bench_oak, bench_script_to_glb);
criterion_main!(benches);
