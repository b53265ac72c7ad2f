//! The USD text layer against the glb on equal work: the benchmark forest
//! (`scripts/forests/big.lua`, about 100,000 trees of 24 variants over a terrain) generated
//! once, then exported to glb bytes and to the `.usda` text (with its textures' paths) in the
//! same run.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use pge_engine::SessionOptions;
use pge_engine::export::{ExportMeta, Instancing, glb_bytes_with, usd_files};

fn forest(c: &mut Criterion) {
    let engine = pge::default_engine().build().expect("engine");
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/scripts/forests/big.lua");
    let session = engine.session(SessionOptions::default()).expect("session");
    let model = session
        .generate(path.as_ref(), &mut |_, _| {})
        .expect("generates")
        .model;
    let placements: usize = model.groups.iter().map(|g| g.transforms.len()).sum();
    eprintln!(
        "big.lua: {placements} placements, {} meshes",
        model.meshes.len()
    );
    let meta = ExportMeta::default();
    let mut group = c.benchmark_group("forest_100k");
    group.sample_size(10);
    group.bench_function("glb", |b| {
        b.iter(|| black_box(glb_bytes_with(&model, &meta, Instancing::Gpu).expect("glb")));
    });
    group.bench_function("usda", |b| {
        b.iter(|| black_box(usd_files(&model, &meta, "big").expect("usda")));
    });
    group.finish();
}

criterion_group!(benches, forest);
criterion_main!(benches);
