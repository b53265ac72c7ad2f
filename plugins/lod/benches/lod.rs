//! Foliage LOD benchmarks: simplifying 100,000 leaves (target: under 1 s on one core), V and
//! the table (linear), and the budget for 100,000 instances (target: under 5 ms).

use criterion::{Criterion, criterion_group, criterion_main};
use glam::Vec3;
use pge_lod::{Budget, Leaf, LodTable, Selection, assign, simplify};
use rand_mt::Mt64;

/// `n` leaves of a round crown: random points in a spherical shell, random orientations.
fn crown(n: usize) -> Vec<Leaf> {
    let mut rng = Mt64::new(7);
    let mut u = move || ((rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64) as f32;
    let radius = 0.04 * (n as f32).sqrt();
    (0..n)
        .map(|_| {
            let dir = loop {
                let v = Vec3::new(u() * 2.0 - 1.0, u() * 2.0 - 1.0, u() * 2.0 - 1.0);
                if let Some(d) = v.try_normalize().filter(|_| v.length() <= 1.0) {
                    break d;
                }
            };
            let center = Vec3::new(0.0, radius * 1.5, 0.0) + dir * radius * (0.7 + 0.3 * u());
            let normal = (dir + Vec3::new(u() - 0.5, u() - 0.5, u() - 0.5)).normalize();
            let corners = [(-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)].map(|(x, y)| {
                let (e1, e2) = normal.any_orthonormal_pair();
                center + (e1 * x + e2 * y) * 0.3
            });
            Leaf::from_quad(corners, Some(normal)).expect("leaf")
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let leaves = crown(100_000);
    let mut g = c.benchmark_group("lod");
    g.sample_size(10);
    g.bench_function("simplify 100k leaves", |b| {
        b.iter(|| simplify(&leaves, &Selection::default()))
    });
    let chain = simplify(&leaves, &Selection::default());
    eprintln!(
        "100k leaves: {} collapses, {} roots",
        chain.children.len(),
        chain.roots().len()
    );
    g.bench_function("V and table, 100k leaves", |b| {
        b.iter(|| LodTable::new(&chain))
    });
    let distances: Vec<f32> = (0..100_000u32)
        .map(|i| (i.wrapping_mul(2_654_435_761) % 100_000) as f32 * 0.01)
        .collect();
    let budget = Budget {
        near: 50.0,
        far: 900.0,
        total: 20_000_000,
    };
    g.bench_function("budget 100k instances", |b| {
        b.iter(|| assign(&distances, 5000, 40, &budget).expect("budget"))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
