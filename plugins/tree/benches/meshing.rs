//! Meshing throughput: a random binary tree of branches turned into bark (triangles per
//! second, on every core and on one thread), and a complete tree of about 20,000 triangles
//! with leaves built end to end.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::Vec3;
use pge_engine::geometry::Skeleton;
use pge_tree::{LeafOptions, MeshOptions, TreeOptions, append_bark, build_tree, pipe_radii};
use std::hint::black_box;

/// A deterministic branching skeleton: each node continues, and every `fork_every`-th node
/// also starts a lateral branch, until `nodes` nodes exist.
fn skeleton(nodes: usize, fork_every: usize) -> Skeleton {
    let mut s = Skeleton::new();
    s.push(Vec3::ZERO, None, 0.0, 0);
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut rand = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f32 / (1u64 << 53) as f32 - 0.5
    };
    let mut frontier = vec![0u32];
    let mut i = 0;
    while s.len() < nodes {
        let slot = i % frontier.len();
        let parent = frontier[slot];
        let p = s.positions[parent as usize];
        let dir = Vec3::new(rand(), 1.0, rand()).normalize();
        let child = s.push(p + dir * 0.2, Some(parent), 0.0, 0);
        frontier[slot] = child;
        if s.len().is_multiple_of(fork_every) {
            frontier.push(child);
        }
        i += 1;
    }
    pipe_radii(&mut s, 0.01, 2.3);
    s
}

fn bench_meshing(c: &mut Criterion) {
    let s = skeleton(20_000, 7);
    let mut mesh = pge_engine::geometry::Mesh::default();
    append_bark(&s, &MeshOptions::default(), &mut mesh);
    let triangles = mesh.triangle_count() as u64;
    let mut group = c.benchmark_group("bark");
    group.throughput(Throughput::Elements(triangles));
    group.bench_function(
        format!("append_bark {} nodes, {triangles} triangles", s.len()),
        |b| {
            b.iter(|| {
                mesh.positions.clear();
                mesh.normals.clear();
                mesh.uvs.clear();
                mesh.indices.clear();
                append_bark(black_box(&s), &MeshOptions::default(), &mut mesh);
                black_box(mesh.indices.len())
            })
        },
    );
    // The same on one thread (the row above uses every core): the 2-thread speed-up.
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a thread pool");
    group.bench_function(
        format!(
            "append_bark {} nodes, {triangles} triangles, 1 thread",
            s.len()
        ),
        |b| {
            b.iter(|| {
                mesh.positions.clear();
                mesh.normals.clear();
                mesh.uvs.clear();
                mesh.indices.clear();
                one.install(|| append_bark(black_box(&s), &MeshOptions::default(), &mut mesh));
                black_box(mesh.indices.len())
            })
        },
    );
    group.finish();
}

fn bench_tree(c: &mut Criterion) {
    // About 20,000 triangles: 1,350 nodes of 6-sided bark and leaves at the tips.
    let s = skeleton(1350, 6);
    let options = TreeOptions {
        mesh: MeshOptions {
            sides: 6,
            ..MeshOptions::default()
        },
        leaves: Some(LeafOptions {
            per_tip: (4, 6),
            ..LeafOptions::default()
        }),
        lod: None,
    };
    let model = build_tree(&s, &options, 1).expect("builds");
    let name = format!("build_tree {} triangles", model.triangle_count());
    c.bench_function(&name, |b| {
        b.iter(|| build_tree(black_box(&s), &options, 1).expect("builds"))
    });
}

criterion_group!(benches, bench_meshing, bench_tree);
criterion_main!(benches);
