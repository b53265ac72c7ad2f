//! Seed 000's jittered grid: one sample per cell, moved by up to `jitter` of the cell.

use crate::poisson::{Rect, Sample};
use pge_engine::random::{SplitMix64, hash_words};

/// Seed 000's jittered grid over the cells of `world` that meet `region`; cut short (the
/// caller then reports its limit) when `stopped` says so, checked at each row.
pub(crate) fn jittered(
    world: Rect,
    region: Rect,
    cell: f64,
    jitter: f64,
    seed: u64,
    blocked: &(dyn Fn(f64, f64) -> bool + Sync),
    stopped: &dyn Fn() -> bool,
) -> Vec<Sample> {
    let n = [
        ((world.max[0] - world.min[0]) / cell).ceil() as i64,
        ((world.max[1] - world.min[1]) / cell).ceil() as i64,
    ];
    let range = |axis: usize| {
        let a = ((region.min[axis] - world.min[axis]) / cell).floor() as i64;
        let b = ((region.max[axis] - world.min[axis]) / cell).ceil() as i64;
        (a.clamp(0, n[axis]), b.clamp(0, n[axis]))
    };
    let (x0, x1) = range(0);
    let (z0, z1) = range(1);
    let mut out = Vec::new();
    for cz in z0..z1 {
        if stopped() {
            break;
        }
        for cx in x0..x1 {
            let mut rng = SplitMix64::new(hash_words(&[seed, 0x9a1d, cx as u64, cz as u64]));
            let x = world.min[0] + cell * (cx as f64 + 0.5 + jitter * (2.0 * rng.uniform() - 1.0));
            let z = world.min[1] + cell * (cz as f64 + 0.5 + jitter * (2.0 * rng.uniform() - 1.0));
            if world.contains(x, z) && !blocked(x, z) {
                out.push(Sample {
                    x,
                    z,
                    cell: [cx as u32, cz as u32],
                    index: 0,
                });
            }
        }
    }
    out
}
