//! Export speed: a 500,000-triangle grid mesh to glb bytes, and a script run end to end.

use std::sync::Arc;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::{Vec2, Vec3};
use pge_engine::export::{ExportMeta, glb_bytes};
use pge_engine::geometry::{Mesh, Model};
use pge_engine::{Engine, SessionOptions};

fn grid(n: u32) -> Mesh {
    let mut positions = Vec::new();
    let mut uvs = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            positions.push(Vec3::new(i as f32, ((i * j) as f32).sin(), j as f32));
            uvs.push(Vec2::new(i as f32 / n as f32, j as f32 / n as f32));
        }
    }
    let mut indices = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let a = j * (n + 1) + i;
            indices.extend_from_slice(&[a, a + n + 1, a + 1, a + 1, a + n + 1, a + n + 2]);
        }
    }
    let mut mesh = Mesh::from_triangles(positions, indices).expect("valid grid");
    mesh.uvs = uvs;
    mesh
}

fn export(c: &mut Criterion) {
    let model = Model::from_mesh(Arc::new(grid(500)));
    let mut g = c.benchmark_group("export");
    g.throughput(Throughput::Elements(model.triangle_count() as u64));
    g.bench_function("glb_500k_triangles", |b| {
        b.iter(|| glb_bytes(&model, &ExportMeta::default()).expect("exports"))
    });
    g.finish();
}

fn script(c: &mut Criterion) {
    let engine = Engine::builder()
        .library(concat!(env!("CARGO_MANIFEST_DIR"), "/../scripts"))
        .build()
        .expect("engine");
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../scripts/examples/terrain.lua"
    );
    c.bench_function("terrain_script_to_model", |b| {
        b.iter(|| {
            let session = engine.session(SessionOptions::default()).expect("session");
            session
                .generate(path.as_ref(), &mut |_, _| {})
                .expect("generates")
        })
    });
}

criterion_group!(benches, export, script);
criterion_main!(benches);
