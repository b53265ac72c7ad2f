//! Marching cubes at 128³ over a single ball and over a coral-like cloud of 400 particles.

use criterion::{Criterion, criterion_group, criterion_main};
use glam::Vec3;
use pge_metaballs::{MarchOptions, MarchingCubes, Metaballs};

fn cloud() -> Metaballs {
    let mut field = Metaballs::new(0.5);
    let mut s = 7u32;
    let mut next = || {
        s = s.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        (s >> 8) as f32 / (1u32 << 24) as f32
    };
    // A random walk, like a coral branch traced by an L-system.
    let mut p = Vec3::ZERO;
    for _ in 0..400 {
        p += (Vec3::new(next(), next(), next()) - 0.5) * 0.4;
        field
            .add_particle(p, 1.0, Some(0.3 + 0.3 * next()))
            .expect("valid particle");
    }
    field
}

fn bench(c: &mut Criterion) {
    let mc = MarchingCubes::new(MarchOptions {
        resolution: 128,
        ..MarchOptions::default()
    })
    .expect("valid options");
    let mut ball = Metaballs::new(1.0);
    ball.add_particle(Vec3::ZERO, 1.0, None)
        .expect("valid particle");
    let cloud = cloud();
    let mut group = c.benchmark_group("marching_cubes_128");
    group.sample_size(10);
    group.bench_function("one_ball", |b| {
        b.iter(|| mc.polygonize(&ball, &mut || false))
    });
    group.bench_function("cloud_400", |b| {
        b.iter(|| mc.polygonize(&cloud, &mut || false))
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
