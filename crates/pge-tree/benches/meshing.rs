//! Meshing throughput: a random binary tree of branches turned into bark (triangles per
//! second, on every core and on one thread), a complete tree of about 20,000 triangles
//! with leaves built end to end, and the small oak of `scripts/species/oak.lua` (its
//! colonized skeleton in `oak_skeleton.txt`) meshed as `pge run` meshes it: bark, leaves and
//! the search for unusable triangles, on every core and on one thread, in CPU time (of all
//! threads: the 2-thread figure shows what fanning out costs, not the wall time saved).

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::Vec3;
use pge_engine::geometry::Skeleton;
use pge_tree::{
    Flare, LeafOptions, LeafShape, MeshOptions, RadiiMode, TreeOptions, append_bark, build_tree,
    pipe_radii,
};
use std::hint::black_box;

#[path = "common/cpu.rs"]
mod cpu;
use cpu::ProcessCpu;

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

/// The skeleton `scripts/species/oak.lua` colonizes at its defaults and seed 1, with its
/// pipe-model radii and orders: one node a line, `parent x y z radius order` (parents from
/// 1, 0 for a root).
fn oak_skeleton() -> Skeleton {
    let mut s = Skeleton::new();
    for line in include_str!("oak_skeleton.txt").lines() {
        let f: Vec<f32> = line
            .split_whitespace()
            .map(|x| x.parse().expect("a number"))
            .collect();
        let parent = (f[0] > 0.0).then(|| f[0] as u32 - 1);
        s.push(Vec3::new(f[1], f[2], f[3]), parent, f[4], f[5] as u32);
    }
    s
}

/// The oak's tree options (`scripts/species/oak.lua`), radii kept as the colonization gives
/// them.
fn oak_options() -> TreeOptions {
    TreeOptions {
        mesh: MeshOptions {
            sides: 10,
            merge_straight: Some(6.0),
            smoothing: 0.5,
            radii: RadiiMode::Keep,
            bark_depth: 1.3,
            flare: Some(Flare {
                roots: 5,
                spread: 0.9,
                height: 1.0,
            }),
            ..MeshOptions::default()
        },
        leaves: Some(LeafOptions {
            per_tip: (6, 9),
            size: 0.38,
            max_depth: 3,
            shape: LeafShape::Lobed,
            translucency: 0.25,
            ..LeafOptions::default()
        }),
        lod: None,
    }
}

fn bench_oak(c: &mut Criterion<ProcessCpu>) {
    let s = oak_skeleton();
    let options = oak_options();
    let mesh = |s: &Skeleton| {
        let mut model = build_tree(s, &options, 1).expect("builds");
        model.remove_unusable_triangles();
        model
    };
    let name = format!("oak {} triangles", mesh(&s).triangle_count());
    c.bench_function(&name, |b| b.iter(|| mesh(black_box(&s))));
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a thread pool");
    c.bench_function(&format!("{name}, 1 thread"), |b| {
        b.iter(|| one.install(|| mesh(black_box(&s))))
    });
}

criterion_group!(benches, bench_meshing, bench_tree);
criterion_group! {
    name = oak;
    config = Criterion::default().with_measurement(ProcessCpu);
    targets = bench_oak
}
criterion_main!(benches, oak);
