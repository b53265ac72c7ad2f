//! The small oak's points and growth (`init` and every step, no meshing) in a loop, for
//! profilers (`perf`, `valgrind --tool=callgrind`): `cargo run --release -p pge-spacecol
//! --example oak_growth -- [ROUNDS] [POINTS]`. Prints the iterations and nodes of the last round and
//! the fastest round's `points` and `growth` times, then the fastest of the finish's skeleton
//! (pipe radii and orders, as `finish` makes it) and of the tree's `radii` phase
//! (`prepare_skeleton`: smoothing and straight chains merged) on the last round's tree.

use std::time::Instant;

use glam::Vec3;
use pge_engine::geometry::Skeleton;
use pge_engine::{Algorithm, Location, RunContext, Step};
use pge_spacecol::{Params, Shape, SpaceColonization};

/// The parameters `scripts/species/oak.lua` gives, seeded as `pge run` seeds it.
fn oak(points: u32) -> Params {
    let mut p = Params::new(Shape::Ellipsoid {
        center: Vec3::new(0.0, 6.4, 0.0),
        radii: Vec3::new(5.5, 3.2, 4.95),
    });
    p.points = Some(points);
    p.step = 0.3;
    p.influence = 2.4;
    p.kill = 0.6;
    p.tropism = Vec3::new(0.0, 0.05, 0.0);
    p.tree.mesh.tip_radius = 0.025;
    p.tree.mesh.exponent = 2.2;
    p.tree.mesh.smoothing = 0.5;
    p.tree.mesh.merge_straight = Some(6.0);
    p
}

/// An FNV-1a hash of the skeleton's positions (their bits) and parents: two builds grew the
/// same tree when their checksums agree.
fn checksum(skeleton: &Skeleton) -> u64 {
    let words = skeleton
        .positions
        .iter()
        .flat_map(|p| p.to_array().map(f32::to_bits));
    let parents = skeleton.parents.iter().map(|p| p.map_or(u32::MAX, |q| q));
    words.chain(parents).fold(0xcbf2_9ce4_8422_2325, |h, w| {
        (h ^ u64::from(w)).wrapping_mul(0x0100_0000_01b3)
    })
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let rounds: usize = std::env::args().nth(1).map_or(Ok(100), |s| s.parse())?;
    let points: u32 = std::env::args().nth(2).map_or(Ok(3000), |s| s.parse())?;
    let ctx = RunContext::default();
    let (mut best_points, mut best_growth) = (f64::INFINITY, f64::INFINITY);
    let mut last = (0, 0, 0);
    let mut grown = None;
    for _ in 0..rounds {
        let mut sc = SpaceColonization::new(oak(points), Location::new("oak", 1))?;
        let t = Instant::now();
        sc.init(&ctx)?;
        let points = t.elapsed().as_secs_f64();
        let t = Instant::now();
        while sc.step(&ctx)? == Step::Continue {}
        let growth = t.elapsed().as_secs_f64();
        best_points = best_points.min(points);
        best_growth = best_growth.min(growth);
        let skeleton = sc.skeleton().unwrap_or_default();
        last = (sc.iterations(), skeleton.len(), checksum(&skeleton));
        grown = Some(sc);
    }
    let (mut best_finish, mut best_radii) = (f64::INFINITY, f64::INFINITY);
    let mut prepared = 0;
    if let Some(sc) = grown {
        let mut mesh = sc.params().tree.mesh.clone();
        mesh.radii = pge_tree::RadiiMode::Keep;
        for _ in 0..rounds {
            let t = Instant::now();
            let skeleton = Algorithm::skeleton(&sc).unwrap_or_default();
            best_finish = best_finish.min(t.elapsed().as_secs_f64());
            let t = Instant::now();
            let s = pge_tree::prepare_skeleton(&skeleton, &mesh)?;
            best_radii = best_radii.min(t.elapsed().as_secs_f64());
            prepared = s.len();
        }
    }
    println!(
        "{} iterations, {} nodes (checksum {:016x}); fastest of {rounds}: points {:.3} ms, growth {:.3} ms",
        last.0,
        last.1,
        last.2,
        best_points * 1e3,
        best_growth * 1e3
    );
    println!(
        "finish's skeleton {:.4} ms, radii {:.4} ms ({prepared} nodes prepared)",
        best_finish * 1e3,
        best_radii * 1e3
    );
    Ok(())
}
