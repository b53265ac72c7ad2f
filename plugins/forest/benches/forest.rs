//! Forest benchmarks: Poisson-disk sampling (points per second), the layout of the 1 km²
//! benchmark forest (about 100,000 trees), one 250 m tile of it, each tree's leaf budget
//! for a camera (whole and tile), and writing 100,000 instances to a `.glb` (with and
//! without their leaf counts).

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::Vec3;
use pge_engine::export::{ExportMeta, Instancing, glb_bytes_with};
use pge_engine::geometry::{InstanceGroup, Mesh, Model, PlacementLeaves};
use pge_forest::{
    Camera, Density, FbmOptions, Forest, Layer, Rect, Terrain, VariantLod, instance_leaves,
    poisson, transform,
};
use pge_lod::Budget;

fn big_forest() -> Forest {
    let mut f = Forest::new([1000.0, 1000.0], 7, Some(250.0)).expect("forest");
    f.terrain = Terrain::fbm(
        f.size,
        FbmOptions {
            height: 40.0,
            scale: 400.0,
            octaves: 5,
            ..FbmOptions::default()
        },
        7,
    );
    let mut oak = Layer::new("oak", 9.0);
    oak.altitude = [-100.0, 0.0];
    let mut conifer = Layer::new("conifer", 3.2);
    conifer.altitude = [-5.0, 100.0];
    conifer.slope = [0.0, 35.0];
    let mut bush = Layer::new("bush", 2.6);
    bush.density = Density::Constant(0.8);
    bush.scale = [0.5, 1.0];
    f.layers = vec![oak, conifer, bush];
    f
}

fn sampling(c: &mut Criterion) {
    let world = Rect::new([-250.0, -250.0], [250.0, 250.0]);
    let n = poisson(world, world, 1.0, 1, &|_, _| false, 1 << 24)
        .expect("fits")
        .len();
    let mut g = c.benchmark_group("poisson");
    g.sample_size(10);
    g.throughput(Throughput::Elements(n as u64));
    // Single-threaded, then the blocks of each phase on two threads.
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("thread pool");
        g.bench_function(format!("500m_r1_{threads}thread"), |b| {
            b.iter(|| {
                pool.install(|| poisson(world, world, 1.0, black_box(1), &|_, _| false, 1 << 24))
            })
        });
    }
    g.finish();
}

fn layout(c: &mut Criterion) {
    let f = big_forest();
    let n = f.layout(None).expect("layout").instances.len();
    let mut g = c.benchmark_group("layout");
    g.sample_size(10);
    g.throughput(Throughput::Elements(n as u64));
    g.bench_function("1km2_whole", |b| b.iter(|| f.layout(black_box(None))));
    g.bench_function("250m_tile", |b| {
        b.iter(|| f.layout(black_box(Some((1, 2)))))
    });
    g.finish();
}

fn budget(c: &mut Criterion) {
    let f = big_forest();
    let whole = f.layout(None).expect("layout");
    let tile = f.layout(Some((1, 2))).expect("tile");
    // Eight variants per layer (the default), 2000 to 2700 leaves, 60 at the coarsest.
    let lods: Vec<Vec<Option<VariantLod>>> = (0..3)
        .map(|_| {
            (0..8)
                .map(|v| {
                    Some(VariantLod {
                        leaves: 2000 + 100 * v,
                        roots: 60,
                    })
                })
                .collect()
        })
        .collect();
    let camera = Camera {
        position: [0.0, 2.0, -500.0],
        budget: Budget {
            near: 10.0,
            far: 300.0,
            total: 2_000_000,
        },
    };
    let mut g = c.benchmark_group("budget");
    g.sample_size(10);
    g.throughput(Throughput::Elements(whole.instances.len() as u64));
    g.bench_function("1km2_whole", |b| {
        b.iter(|| instance_leaves(&f, black_box(&whole), None, &lods, &camera))
    });
    g.bench_function("250m_tile", |b| {
        b.iter(|| instance_leaves(&f, black_box(&tile), Some((1, 2)), &lods, &camera))
    });
    g.finish();
}

fn export(c: &mut Criterion) {
    let tri =
        Mesh::from_triangles(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![0, 1, 2]).expect("mesh");
    let mut model = Model::from_mesh(tri);
    model.groups.push(InstanceGroup {
        name: "tree/0".into(),
        meshes: vec![0],
        transforms: (0..100_000)
            .map(|i| transform([i as f32 * 0.01, 0.0, (i % 317) as f32], i as f32, 1.0))
            .collect(),
        leaves: None,
    });
    let mut g = c.benchmark_group("export");
    g.sample_size(10);
    g.throughput(Throughput::Elements(100_000));
    g.bench_function("100k_gpu", |b| {
        b.iter(|| glb_bytes_with(&model, &ExportMeta::default(), Instancing::Gpu))
    });
    g.bench_function("100k_nodes", |b| {
        b.iter(|| glb_bytes_with(&model, &ExportMeta::default(), Instancing::Nodes))
    });
    model.groups[0].leaves = Some(PlacementLeaves {
        roots: 60,
        counts: (0..100_000).map(|i| 60 + i % 2000).collect(),
    });
    g.bench_function("100k_gpu_leaves", |b| {
        b.iter(|| glb_bytes_with(&model, &ExportMeta::default(), Instancing::Gpu))
    });
    g.finish();
}

criterion_group!(benches, sampling, layout, budget, export);
criterion_main!(benches);
