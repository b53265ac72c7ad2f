//! Foliage LOD benchmarks: simplifying 100,000 leaves (target: under 1 s on one core), V and
//! the table (linear), and the budget for 100,000 instances (target: under 5 ms).

use criterion::{Criterion, criterion_group, criterion_main};
use glam::Vec3;
use pge_lod::{Budget, Chain, Leaf, LodTable, Selection, assign, assign_into, simplify};
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

/// FNV-1a over the chain's children and every leaf's fields: equal hashes, same chain.
fn chain_hash(chain: &Chain) -> u64 {
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    let mut eat = |x: u32| {
        for b in x.to_le_bytes() {
            h = (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
        }
    };
    for pair in &chain.children {
        pair.iter().for_each(|&c| eat(c));
    }
    for l in &chain.leaves {
        let v = [l.center, l.normal, l.axis, l.lo, l.hi];
        v.iter()
            .flat_map(|v| v.to_array())
            .for_each(|f| eat(f.to_bits()));
        [l.half_length, l.half_width, l.leaf_area]
            .iter()
            .for_each(|f| eat(f.to_bits()));
        eat(l.count);
    }
    h
}

/// The chain's quality: the mean weighted distance of its collapses (seed 003 §2.4.1 with
/// the default weights, the vertical axis through the centre of the leaves' box, as
/// `simplify` takes it) and the mean relative area error of the coarsest level's leaves
/// (`|area - represented leaf area| / represented leaf area`).
fn quality(chain: &Chain) -> (f64, f64) {
    let originals = &chain.leaves[..chain.originals];
    let (lo, hi) = originals.iter().fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(lo, hi), l| (lo.min(l.center), hi.max(l.center)),
    );
    let mid = (lo + hi) * 0.5;
    let axis = |p: Vec3| Vec3::new(p.x - mid.x, 0.0, p.z - mid.z).length();
    let crown = originals
        .iter()
        .map(|l| axis(l.center))
        .fold(0.0f32, f32::max);
    let w = pge_lod::Weights::default();
    let mut cost = 0.0f64;
    for &[a, b] in &chain.children {
        let (a, b) = (&chain.leaves[a as usize], &chain.leaves[b as usize]);
        let cos = a.normal.dot(b.normal).abs().min(1.0);
        let (na, nb) = (a.count as f32, b.count as f32);
        let (aa, ab) = (a.area(), b.area());
        let c = w.distance * a.center.distance(b.center) / (a.radius() + b.radius())
            + w.coplanarity * (1.0 - cos)
            + w.count * (na - nb).abs() / (na + nb)
            + w.area * (aa - ab).abs() / (aa + ab)
            + w.interiority * axis((a.center + b.center) * 0.5) / crown;
        cost += f64::from(c);
    }
    let roots = chain.roots();
    let error: f64 = roots
        .iter()
        .map(|&r| {
            let l = &chain.leaves[r as usize];
            f64::from((l.area() - l.leaf_area).abs() / l.leaf_area)
        })
        .sum();
    (
        cost / chain.children.len().max(1) as f64,
        error / roots.len().max(1) as f64,
    )
}

/// CPU time this thread has run, in nanoseconds (`/proc/thread-self/schedstat`; 0 where
/// there is none): under load, wall time counts the time other processes hold the core.
fn cpu_ns() -> u64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse().ok())
        .unwrap_or(0)
}

/// The CPU time of a call of `f` in milliseconds: the least, over 3 batches of `calls`, of
/// the batch's time over `calls` (the kernel updates the count at scheduler ticks, so a
/// batch should last well over a tick).
fn cpu_ms<T>(calls: usize, mut f: impl FnMut() -> T) -> f64 {
    (0..3)
        .map(|_| {
            let start = cpu_ns();
            for _ in 0..calls {
                std::hint::black_box(f());
            }
            (cpu_ns() - start) as f64 * 1e-6 / calls as f64
        })
        .fold(f64::INFINITY, f64::min)
}

fn bench(c: &mut Criterion) {
    let leaves = crown(100_000);
    let mut g = c.benchmark_group("lod");
    g.sample_size(10);
    g.bench_function("simplify 100k leaves", |b| {
        b.iter(|| simplify(&leaves, &Selection::default()))
    });
    let chain = simplify(&leaves, &Selection::default());
    let (cost, error) = quality(&chain);
    eprintln!(
        "100k leaves: {} collapses, {} roots, chain hash {:016x}; mean collapse cost {cost:.4}, \
         coarsest level's mean area error {error:.4}",
        chain.children.len(),
        chain.roots().len(),
        chain_hash(&chain)
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
    let mut counts = Vec::new();
    eprintln!(
        "CPU time per call (least of 3 batches; schedstat): simplify 100k leaves {:.0} ms; budget 100k \
         instances {:.2} ms, reused buffers {:.2} ms",
        cpu_ms(1, || simplify(&leaves, &Selection::default())),
        cpu_ms(200, || assign(&distances, 5000, 40, &budget)),
        cpu_ms(200, || assign_into(
            &distances,
            5000,
            40,
            &budget,
            &mut counts
        )),
    );
    g.bench_function("budget 100k instances, reused buffers", |b| {
        b.iter(|| assign_into(&distances, 5000, 40, &budget, &mut counts).expect("budget"))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
