//! Blue noise that tiles agree on: Bridson's Poisson-disk sampling run block by block.
//!
//! The world is cut into square blocks of side `3 r` aligned on its −x, −z corner. Blocks are
//! processed in four phases by the parity of their coordinates, so two blocks of one phase
//! never touch and their order within the phase does not matter. A block is sampled with its
//! own generator (seeded by the seed and its coordinates): darts start Bridson's growth,
//! which keeps candidates inside the block at least `r` from every sample, those of the
//! neighbouring blocks of earlier phases included. A block's result thus depends only on its neighbours of earlier
//! phases, whose results depend on theirs: three blocks around a region are enough to sample
//! that region exactly as the whole world would (DESIGN.md §3.8).

use crate::rng::{Rng, hash};

/// A rectangle of the ground, `[min, max)` in x and z.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rect {
    /// The −x, −z corner.
    pub min: [f64; 2],
    /// The +x, +z corner (excluded).
    pub max: [f64; 2],
}

impl Rect {
    /// The rectangle `[min, max)`.
    #[must_use]
    pub fn new(min: [f64; 2], max: [f64; 2]) -> Rect {
        Rect { min, max }
    }

    /// Whether `(x, z)` lies inside (the max edges excluded).
    #[must_use]
    pub fn contains(&self, x: f64, z: f64) -> bool {
        x >= self.min[0] && x < self.max[0] && z >= self.min[1] && z < self.max[1]
    }

    /// The rectangle grown by `d` on every side.
    #[must_use]
    pub fn expand(&self, d: f64) -> Rect {
        Rect {
            min: [self.min[0] - d, self.min[1] - d],
            max: [self.max[0] + d, self.max[1] + d],
        }
    }

    /// Area in square metres.
    #[must_use]
    pub fn area(&self) -> f64 {
        (self.max[0] - self.min[0]).max(0.0) * (self.max[1] - self.min[1]).max(0.0)
    }
}

/// A point of a layout and the cell that made it (its block, and its rank in the block).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// Position along x.
    pub x: f64,
    /// Position along z.
    pub z: f64,
    /// The block (or grid cell) coordinates.
    pub cell: [u32; 2],
    /// Rank of the sample in its cell.
    pub index: u32,
}

/// Candidates tried around an active sample before it retires (Bridson's k).
const CANDIDATES: u32 = 30;
/// Blocks of margin that make a region's samples equal to the whole world's.
pub const MARGIN_BLOCKS: i64 = 3;

/// The side of a block for minimum distance `r`.
#[must_use]
pub fn block_size(r: f64) -> f64 {
    3.0 * r
}

/// The samples of `world` (minimum distance `r`, seed `seed`) in the blocks that meet
/// `region`, in block order (z, then x) and rank. Points where `blocked` is true are never
/// sampled (trunks of earlier layers). More than `cap` samples is an error carrying the
/// count reached.
pub fn poisson(
    world: Rect,
    region: Rect,
    r: f64,
    seed: u64,
    blocked: &dyn Fn(f64, f64) -> bool,
    cap: usize,
) -> Result<Vec<Sample>, usize> {
    let b = block_size(r);
    let nb = [
        ((world.max[0] - world.min[0]) / b).ceil().max(1.0) as i64,
        ((world.max[1] - world.min[1]) / b).ceil().max(1.0) as i64,
    ];
    let block_of = |v: f64, axis: usize| ((v - world.min[axis]) / b).floor() as i64;
    let mut lo = [0i64; 2];
    let mut hi = [0i64; 2];
    for a in 0..2 {
        let r0 = block_of(region.min[a].max(world.min[a]), a);
        let r1 = block_of(region.max[a].min(world.max[a]) - 1e-9, a);
        lo[a] = (r0 - MARGIN_BLOCKS).clamp(0, nb[a] - 1);
        hi[a] = (r1 + MARGIN_BLOCKS).clamp(0, nb[a] - 1);
        if r1 < r0 {
            return Ok(Vec::new());
        }
    }
    let wanted = [
        [
            (block_of(region.min[0].max(world.min[0]), 0)).clamp(0, nb[0] - 1),
            (block_of(region.max[0].min(world.max[0]) - 1e-9, 0)).clamp(0, nb[0] - 1),
        ],
        [
            (block_of(region.min[1].max(world.min[1]), 1)).clamp(0, nb[1] - 1),
            (block_of(region.max[1].min(world.max[1]) - 1e-9, 1)).clamp(0, nb[1] - 1),
        ],
    ];
    let mut s = Sampler::new(world, lo, hi, r, b);
    for phase in 0..4i64 {
        let (px, pz) = (phase & 1, phase >> 1);
        for bz in lo[1]..=hi[1] {
            if bz.rem_euclid(2) != pz {
                continue;
            }
            for bx in lo[0]..=hi[0] {
                if bx.rem_euclid(2) != px {
                    continue;
                }
                s.block(bx, bz, seed, blocked);
                if s.samples.len() > cap.saturating_mul(4).max(cap) {
                    return Err(s.samples.len());
                }
            }
        }
    }
    let mut out = Vec::new();
    for bz in wanted[1][0]..=wanted[1][1] {
        for bx in wanted[0][0]..=wanted[0][1] {
            let (a, e) = s.ranges[s.local(bx, bz)];
            out.extend_from_slice(&s.samples[a as usize..e as usize]);
            if out.len() > cap {
                return Err(out.len());
            }
        }
    }
    Ok(out)
}

struct Sampler {
    world: Rect,
    lo: [i64; 2],
    hi: [i64; 2],
    r: f64,
    b: f64,
    cell: f64,
    origin: [f64; 2],
    dims: [usize; 2],
    /// Background grid: sample index + 1, 0 for none (one sample per cell at most).
    grid: Vec<u32>,
    samples: Vec<Sample>,
    ranges: Vec<(u32, u32)>,
    active: Vec<(f64, f64)>,
}

impl Sampler {
    fn new(world: Rect, lo: [i64; 2], hi: [i64; 2], r: f64, b: f64) -> Sampler {
        let cell = r / std::f64::consts::SQRT_2;
        let origin = [
            world.min[0] + lo[0] as f64 * b,
            world.min[1] + lo[1] as f64 * b,
        ];
        let dims = [
            (((hi[0] - lo[0] + 1) as f64 * b) / cell).ceil() as usize + 1,
            (((hi[1] - lo[1] + 1) as f64 * b) / cell).ceil() as usize + 1,
        ];
        let blocks = ((hi[0] - lo[0] + 1) * (hi[1] - lo[1] + 1)) as usize;
        Sampler {
            world,
            lo,
            hi,
            r,
            b,
            cell,
            origin,
            dims,
            grid: vec![0; dims[0] * dims[1]],
            samples: Vec::new(),
            ranges: vec![(0, 0); blocks],
            active: Vec::new(),
        }
    }

    fn local(&self, bx: i64, bz: i64) -> usize {
        ((bz - self.lo[1]) * (self.hi[0] - self.lo[0] + 1) + (bx - self.lo[0])) as usize
    }

    fn cell_of(&self, x: f64, z: f64) -> (usize, usize) {
        (
            (((x - self.origin[0]) / self.cell) as usize).min(self.dims[0] - 1),
            (((z - self.origin[1]) / self.cell) as usize).min(self.dims[1] - 1),
        )
    }

    fn free(&self, x: f64, z: f64) -> bool {
        let (cx, cz) = self.cell_of(x, z);
        let r2 = self.r * self.r;
        for gz in cz.saturating_sub(2)..=(cz + 2).min(self.dims[1] - 1) {
            let row = gz * self.dims[0];
            for gx in cx.saturating_sub(2)..=(cx + 2).min(self.dims[0] - 1) {
                let k = self.grid[row + gx];
                if k != 0 {
                    let s = &self.samples[k as usize - 1];
                    let (dx, dz) = (s.x - x, s.z - z);
                    if dx * dx + dz * dz < r2 {
                        return false;
                    }
                }
            }
        }
        true
    }

    fn add(&mut self, x: f64, z: f64, cell: [u32; 2], index: u32) {
        let (cx, cz) = self.cell_of(x, z);
        self.samples.push(Sample { x, z, cell, index });
        self.grid[cz * self.dims[0] + cx] = self.samples.len() as u32;
    }

    fn block(&mut self, bx: i64, bz: i64, seed: u64, blocked: &dyn Fn(f64, f64) -> bool) {
        let rect = Rect {
            min: [
                self.world.min[0] + bx as f64 * self.b,
                self.world.min[1] + bz as f64 * self.b,
            ],
            max: [
                (self.world.min[0] + (bx + 1) as f64 * self.b).min(self.world.max[0]),
                (self.world.min[1] + (bz + 1) as f64 * self.b).min(self.world.max[1]),
            ],
        };
        let mut rng = Rng::new(hash(&[seed, 0xb10c, bx as u64, bz as u64]));
        let start = self.samples.len() as u32;
        let cell = [bx as u32, bz as u32];
        // Darts thrown into the block start Bridson's growth, which fills the block up to
        // the samples of the neighbours of earlier phases (they are in the grid); a new
        // round of darts starts after each growth, until four darts in a row fail.
        self.active.clear();
        let mut index = 0u32;
        let r2 = self.r * self.r;
        let mut misses = 0;
        while misses < 4 {
            let (x, z) = (
                rng.range(rect.min[0], rect.max[0]),
                rng.range(rect.min[1], rect.max[1]),
            );
            if !(rect.contains(x, z) && self.free(x, z) && !blocked(x, z)) {
                misses += 1;
                continue;
            }
            misses = 0;
            self.add(x, z, cell, index);
            index += 1;
            self.active.push((x, z));
            while !self.active.is_empty() {
                let i = rng.below(self.active.len() as u32) as usize;
                let (px, pz) = self.active[i];
                let mut found = false;
                for _ in 0..CANDIDATES {
                    let angle = rng.uniform() * std::f64::consts::TAU;
                    let d = (r2 * (1.0 + 3.0 * rng.uniform())).sqrt();
                    let (x, z) = (px + d * angle.cos(), pz + d * angle.sin());
                    if rect.contains(x, z) && self.free(x, z) && !blocked(x, z) {
                        self.add(x, z, cell, index);
                        index += 1;
                        self.active.push((x, z));
                        found = true;
                        break;
                    }
                }
                if !found {
                    self.active.swap_remove(i);
                }
            }
        }
        let l = self.local(bx, bz);
        self.ranges[l] = (start, self.samples.len() as u32);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn min_distance(points: &[Sample]) -> f64 {
        let mut best = f64::INFINITY;
        for (i, a) in points.iter().enumerate() {
            for b in &points[i + 1..] {
                best = best.min(((a.x - b.x).powi(2) + (a.z - b.z).powi(2)).sqrt());
            }
        }
        best
    }

    #[test]
    fn samples_keep_the_minimum_distance_and_fill_the_world() {
        let world = Rect::new([-50.0, -40.0], [50.0, 40.0]);
        let pts = poisson(world, world, 2.0, 7, &|_, _| false, 1 << 20).expect("fits");
        assert!(min_distance(&pts) >= 2.0);
        assert!(pts.iter().all(|p| world.contains(p.x, p.z)));
        // Maximal Poisson-disk sets hold between ~0.55 and 0.9 points per r².
        let per_r2 = pts.len() as f64 / (world.area() / 4.0);
        assert!(per_r2 > 0.55 && per_r2 < 0.95, "{per_r2}");
    }

    #[test]
    fn a_region_is_sampled_exactly_as_the_whole_world_samples_it() {
        let world = Rect::new([-60.0, -60.0], [60.0, 60.0]);
        let whole = poisson(world, world, 1.5, 3, &|_, _| false, 1 << 20).expect("fits");
        let tiles = [
            Rect::new([-60.0, -60.0], [0.0, 0.0]),
            Rect::new([0.0, -60.0], [60.0, 0.0]),
            Rect::new([-60.0, 0.0], [0.0, 60.0]),
            Rect::new([0.0, 0.0], [60.0, 60.0]),
        ];
        let mut union = Vec::new();
        for t in tiles {
            let pts = poisson(world, t, 1.5, 3, &|_, _| false, 1 << 20).expect("fits");
            union.extend(pts.into_iter().filter(|p| t.contains(p.x, p.z)));
        }
        let key = |p: &Sample| (p.cell[1], p.cell[0], p.index);
        union.sort_by_key(key);
        let mut whole_sorted = whole.clone();
        whole_sorted.sort_by_key(key);
        assert_eq!(union, whole_sorted);
    }

    #[test]
    fn blocked_points_are_avoided_and_the_cap_is_an_error() {
        let world = Rect::new([0.0, 0.0], [30.0, 30.0]);
        let pts = poisson(world, world, 1.0, 1, &|x, _| x < 10.0, 1 << 20).expect("fits");
        assert!(pts.iter().all(|p| p.x >= 10.0));
        assert!(poisson(world, world, 1.0, 1, &|_, _| false, 10).is_err());
    }
}
