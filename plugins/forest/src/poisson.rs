//! Blue noise that tiles agree on: Poisson-disk sampling run block by block.
//!
//! The world is cut into square blocks of side `3 r` aligned on its −x, −z corner. Blocks are
//! processed in four phases by the parity of their coordinates, so two blocks of one phase
//! never touch: they are sampled in parallel, and their order within the phase does not
//! matter. A block is sampled with its own generator (seeded by the seed and its
//! coordinates): darts start a Bridson growth, which keeps candidates inside the block at
//! least `r` from every sample, those of the neighbouring blocks of earlier phases included.
//! A block's result thus depends only on its neighbours of earlier phases, whose results
//! depend on theirs: three blocks around a region are enough to sample that region exactly
//! as the whole world would (DESIGN.md §3.8).
//!
//! The growth is Bridson's with Roberts' candidates: an active sample tries
//! [`CANDIDATES`] points evenly spaced on the circle of radius `r` around it, from one of 256
//! random directions, which packs denser and retires samples sooner than random candidates in the
//! annulus `[r, 2r]`. Samples live in a flat background grid of `5 x 5` cells per block; a
//! block works on a copy of its `9 x 9` cells neighbourhood, so a neighbour test reads 25
//! cells of one small array.

use pge_engine::math;
use rayon::prelude::*;

use pge_engine::random::{SplitMix64, hash_words};

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

    /// The part of this rectangle inside `other` (empty, of area 0, when they do not meet).
    #[must_use]
    pub fn intersection(&self, other: &Rect) -> Rect {
        Rect {
            min: [self.min[0].max(other.min[0]), self.min[1].max(other.min[1])],
            max: [self.max[0].min(other.max[0]), self.max[1].min(other.max[1])],
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

/// Candidates tried around an active sample before it retires, evenly spaced on a circle.
const CANDIDATES: usize = 8;
/// Darts in a row that must miss before a block is full.
const MISSES: u32 = 4;
/// Blocks of margin that make a region's samples equal to the whole world's.
pub const MARGIN_BLOCKS: i64 = 3;
/// Background grid cells along a block's side: a cell is `0.6 r`, its diagonal below `r`,
/// so a cell holds one sample at most and a neighbour test reads the cells within two.
const CELLS: usize = 5;
/// Cells along a block's neighbourhood: the block and two cells on every side.
const WINDOW: usize = CELLS + 4;
/// An empty cell: a point infinitely far, so the distance test needs no branch.
const EMPTY: [f64; 2] = [f64::INFINITY, f64::INFINITY];

/// The candidates' radius, a hair above the tested distance.
const RADIUS: f64 = 1.0 + 1e-5;
/// The distance tested, a hair above `r`: the window's single precision (relative to the
/// block, a few `r` wide) then never lets two samples closer than `r`.
const TESTED: f64 = 1.0 + 2e-6;

/// The side of a block for minimum distance `r`.
#[must_use]
pub fn block_size(r: f64) -> f64 {
    3.0 * r
}

/// The samples of `world` (minimum distance `r`, seed `seed`) in the blocks that meet
/// `region`, in block order (z, then x) and rank. Points where `blocked` is true are never
/// sampled (trunks of earlier layers). More than `cap` samples is an error carrying the
/// count reached. The result is the same for any number of rayon threads.
pub fn poisson(
    world: Rect,
    region: Rect,
    r: f64,
    seed: u64,
    blocked: &(dyn Fn(f64, f64) -> bool + Sync),
    cap: usize,
) -> Result<Vec<Sample>, usize> {
    poisson_until(world, region, r, seed, blocked, cap, &|| false)
}

/// [`poisson`], cut short when `stopped` says so (checked between the phases of the
/// sampling and its rows of blocks; the caller then reports its limit: what is returned is
/// incomplete).
pub(crate) fn poisson_until(
    world: Rect,
    region: Rect,
    r: f64,
    seed: u64,
    blocked: &(dyn Fn(f64, f64) -> bool + Sync),
    cap: usize,
    stopped: &dyn Fn() -> bool,
) -> Result<Vec<Sample>, usize> {
    let b = block_size(r);
    let nb = [
        ((world.max[0] - world.min[0]) / b).ceil().max(1.0) as i64,
        ((world.max[1] - world.min[1]) / b).ceil().max(1.0) as i64,
    ];
    let block_of = |v: f64, axis: usize| ((v - world.min[axis]) / b).floor() as i64;
    let mut lo = [0i64; 2];
    let mut hi = [0i64; 2];
    let mut wanted = [[0i64; 2]; 2];
    for a in 0..2 {
        let r0 = block_of(region.min[a].max(world.min[a]), a);
        let r1 = block_of(region.max[a].min(world.max[a]) - 1e-9, a);
        if r1 < r0 {
            return Ok(Vec::new());
        }
        // Saturating: a minimum distance tiny against the world puts r1 at i64::MAX (the
        // float's cast saturates), where adding the margin would wrap to a single block.
        lo[a] = r0.saturating_sub(MARGIN_BLOCKS).clamp(0, nb[a] - 1);
        hi[a] = r1.saturating_add(MARGIN_BLOCKS).clamp(0, nb[a] - 1);
        wanted[a] = [r0.clamp(0, nb[a] - 1), r1.clamp(0, nb[a] - 1)];
    }
    // The grid holds 25 cells per block: more blocks than the cap allows samples is refused
    // before it is allocated (a block holds about 6.6 samples).
    let blocks = (hi[0] - lo[0] + 1).saturating_mul(hi[1] - lo[1] + 1) as usize;
    if blocks > cap {
        return Err(blocks.saturating_mul(6));
    }
    let mut grid = Grid::new(world, lo, hi, r);
    let mut total = 0usize;
    for phase in 0..4i64 {
        if stopped() {
            return Ok(Vec::new());
        }
        let (px, pz) = (phase & 1, phase >> 1);
        let blocks: Vec<(i64, i64)> = (lo[1]..=hi[1])
            .filter(|bz| bz.rem_euclid(2) == pz)
            .flat_map(|bz| {
                (lo[0]..=hi[0])
                    .filter(|bx| bx.rem_euclid(2) == px)
                    .map(move |bx| (bx, bz))
            })
            .collect();
        let mut sampled: Vec<Vec<Sample>> = Vec::with_capacity(blocks.len());
        for chunk in blocks.chunks(1 << 12) {
            if stopped() {
                return Ok(Vec::new());
            }
            sampled.par_extend(
                chunk
                    .par_iter()
                    .map(|&(bx, bz)| grid.sample_block(bx, bz, seed, blocked)),
            );
        }
        for ((bx, bz), samples) in blocks.into_iter().zip(sampled) {
            total += samples.len();
            grid.insert(bx, bz, samples);
        }
        if total > cap.saturating_mul(4).max(cap) {
            return Err(total);
        }
    }
    let mut out = Vec::new();
    for bz in wanted[1][0]..=wanted[1][1] {
        for bx in wanted[0][0]..=wanted[0][1] {
            out.extend_from_slice(&grid.samples[grid.block_index(bx, bz)]);
            if out.len() > cap {
                return Err(out.len());
            }
        }
    }
    Ok(out)
}

/// The background grid over the blocks `lo..=hi` and their samples.
struct Grid {
    world: Rect,
    lo: [i64; 2],
    r: f64,
    b: f64,
    /// One over a cell's side.
    per_cell: f64,
    /// The first candidate's direction `(cos, sin)`, one of 256 around the circle.
    directions: Vec<(f64, f64)>,
    /// Blocks along x and z.
    blocks: [usize; 2],
    /// Cells along x (the row stride).
    stride: usize,
    /// One point per cell, [`EMPTY`] for none.
    cells: Vec<[f64; 2]>,
    /// Each block's samples, in rank order.
    samples: Vec<Vec<Sample>>,
}

/// Floats per window row: a test reads eight cells from the point's cell minus two (the
/// three beyond the five that matter hold points farther than `r`, harmless to test), so
/// rows are padded to the last cell such a read can reach.
const ROW: usize = WINDOW + 3;

/// A block's neighbourhood of `WINDOW x WINDOW` cells, points relative to the block's
/// corner in single precision (x and z apart, so a row's test is two vector ops).
struct Window {
    origin: [f64; 2],
    r2: f32,
    xs: [[f32; ROW]; WINDOW],
    zs: [[f32; ROW]; WINDOW],
}

impl Window {
    fn new(origin: [f64; 2], r: f64) -> Window {
        Window {
            origin,
            r2: ((r * TESTED) * (r * TESTED)) as f32,
            xs: [[f32::INFINITY; ROW]; WINDOW],
            zs: [[f32::INFINITY; ROW]; WINDOW],
        }
    }

    /// Sets window cell `(wx, wz)` to the point `(x, z)` (an infinite point leaves it empty).
    fn put(&mut self, wx: usize, wz: usize, x: f64, z: f64) {
        self.xs[wz][wx] = (x - self.origin[0]) as f32;
        self.zs[wz][wx] = (z - self.origin[1]) as f32;
    }

    /// Whether `(x, z)`, in the block's cell `(cx, cz)`, is at least `r` from every point of
    /// the cells within two of its own. The middle rows go first: they hit most often.
    fn free(&self, cx: usize, cz: usize, x: f64, z: f64) -> bool {
        let (x, z) = ((x - self.origin[0]) as f32, (z - self.origin[1]) as f32);
        [2, 1, 3, 0, 4].into_iter().all(|dz| {
            let (Some(xs), Some(zs)) = (
                self.xs[cz + dz][cx..].first_chunk::<8>(),
                self.zs[cz + dz][cx..].first_chunk::<8>(),
            ) else {
                return true;
            };
            let mut near = [false; 8];
            for k in 0..8 {
                let (dx, dz) = (xs[k] - x, zs[k] - z);
                near[k] = dx * dx + dz * dz < self.r2;
            }
            !near.contains(&true)
        })
    }
}

impl Grid {
    fn new(world: Rect, lo: [i64; 2], hi: [i64; 2], r: f64) -> Grid {
        let b = block_size(r);
        let blocks = [(hi[0] - lo[0] + 1) as usize, (hi[1] - lo[1] + 1) as usize];
        let stride = blocks[0] * CELLS;
        Grid {
            world,
            lo,
            r,
            b,
            per_cell: CELLS as f64 / b,
            directions: (0..256)
                .map(|k| {
                    let (s, c) = math::sin_cos(f64::from(k) * std::f64::consts::TAU / 256.0);
                    (c, s)
                })
                .collect(),
            blocks,
            stride,
            cells: vec![EMPTY; stride * blocks[1] * CELLS],
            samples: vec![Vec::new(); blocks[0] * blocks[1]],
        }
    }

    fn block_index(&self, bx: i64, bz: i64) -> usize {
        (bz - self.lo[1]) as usize * self.blocks[0] + (bx - self.lo[0]) as usize
    }

    /// The block's ground, clipped to the world.
    fn rect(&self, bx: i64, bz: i64) -> Rect {
        let w = &self.world;
        Rect {
            min: [w.min[0] + bx as f64 * self.b, w.min[1] + bz as f64 * self.b],
            max: [
                (w.min[0] + (bx + 1) as f64 * self.b).min(w.max[0]),
                (w.min[1] + (bz + 1) as f64 * self.b).min(w.max[1]),
            ],
        }
    }

    /// The cell of `(x, z)` inside its block `rect`, `0..CELLS` per axis.
    fn cell_in_block(&self, rect: &Rect, x: f64, z: f64) -> (usize, usize) {
        let c = |v: f64, min: f64| (((v - min) * self.per_cell) as usize).min(CELLS - 1);
        (c(x, rect.min[0]), c(z, rect.min[1]))
    }

    /// Samples block `(bx, bz)` against the samples already in the grid (blocks of earlier
    /// phases); reads the grid only.
    fn sample_block(
        &self,
        bx: i64,
        bz: i64,
        seed: u64,
        blocked: &(dyn Fn(f64, f64) -> bool + Sync),
    ) -> Vec<Sample> {
        let rect = self.rect(bx, bz);
        // The block's cells and two around them, copied from the grid.
        let mut window = Window::new(rect.min, self.r);
        let gx0 = (bx - self.lo[0]) * CELLS as i64 - 2;
        let gz0 = (bz - self.lo[1]) * CELLS as i64 - 2;
        let rows = (self.blocks[1] * CELLS) as i64;
        for wz in 0..WINDOW {
            let gz = gz0 + wz as i64;
            if gz < 0 || gz >= rows {
                continue;
            }
            let row = gz as usize * self.stride;
            for wx in 0..WINDOW {
                let gx = gx0 + wx as i64;
                if gx >= 0 && (gx as usize) < self.stride {
                    let [x, z] = self.cells[row + gx as usize];
                    window.put(wx, wz, x, z);
                }
            }
        }
        let mut rng = SplitMix64::new(hash_words(&[seed, 0xb10c, bx as u64, bz as u64]));
        let cell = [bx as u32, bz as u32];
        let mut samples: Vec<Sample> = Vec::new();
        let mut active: Vec<(f64, f64)> = Vec::new();
        let (step_sin, step_cos) = math::sin_cos(std::f64::consts::TAU / CANDIDATES as f64);
        let radius = self.r * RADIUS;
        let fits = |window: &Window, x: f64, z: f64| {
            rect.contains(x, z) && {
                let (cx, cz) = self.cell_in_block(&rect, x, z);
                window.free(cx, cz, x, z) && !blocked(x, z)
            }
        };
        let accept = |window: &mut Window, samples: &mut Vec<Sample>, x: f64, z: f64| {
            let (cx, cz) = self.cell_in_block(&rect, x, z);
            window.put(cx + 2, cz + 2, x, z);
            samples.push(Sample {
                x,
                z,
                cell,
                index: samples.len() as u32,
            });
        };
        // Darts thrown into the block start the growth, which fills the block up to the
        // samples of the neighbours of earlier phases; a new dart follows each growth, until
        // MISSES darts in a row fail.
        let mut misses = 0;
        while misses < MISSES {
            let (x, z) = (
                rng.range(rect.min[0], rect.max[0]),
                rng.range(rect.min[1], rect.max[1]),
            );
            if !fits(&window, x, z) {
                misses += 1;
                continue;
            }
            misses = 0;
            accept(&mut window, &mut samples, x, z);
            active.push((x, z));
            while !active.is_empty() {
                let i = rng.below(active.len() as u32) as usize;
                let (px, pz) = active[i];
                let (mut c, mut s) = self.directions[(rng.next_u64() >> 56) as usize];
                let mut found = false;
                for _ in 0..CANDIDATES {
                    let (x, z) = (px + radius * c, pz + radius * s);
                    if fits(&window, x, z) {
                        accept(&mut window, &mut samples, x, z);
                        active.push((x, z));
                        found = true;
                        break;
                    }
                    (c, s) = (c * step_cos - s * step_sin, s * step_cos + c * step_sin);
                }
                if !found {
                    active.swap_remove(i);
                }
            }
        }
        samples
    }

    /// Stores block `(bx, bz)`'s samples in the grid.
    fn insert(&mut self, bx: i64, bz: i64, samples: Vec<Sample>) {
        let rect = self.rect(bx, bz);
        let gx0 = (bx - self.lo[0]) as usize * CELLS;
        let gz0 = (bz - self.lo[1]) as usize * CELLS;
        for s in &samples {
            let (cx, cz) = self.cell_in_block(&rect, s.x, s.z);
            self.cells[(gz0 + cz) * self.stride + gx0 + cx] = [s.x, s.z];
        }
        let k = self.block_index(bx, bz);
        self.samples[k] = samples;
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
    fn a_minimum_distance_tiny_against_the_world_is_refused_by_the_cap() {
        // Found by the forest_options fuzz target: 1.3e9 m over minDistance = 8e-137 puts the
        // last block at i64::MAX; its margin wrapped the block range to one block, and the
        // wanted blocks were read past it (an index out of bounds).
        let world = Rect::new([-6.7e8, -6.7e8], [6.7e8, 6.7e8]);
        let region = Rect::new([-6.7e8, -6.7e8], [-6.6e8, -6.6e8]);
        for (r, region) in [(8e-137, world), (8e-137, region), (1e-300, world)] {
            let got = poisson(world, region, r, 7, &|_, _| false, 10_000_000);
            assert!(
                got.is_err(),
                "{r} over {region:?}: {:?}",
                got.map(|p| p.len())
            );
        }
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
        // No hole wider than 2 r: every point of the world is within 2 r of a sample.
        for k in 0..2000 {
            let (x, z) = (
                -50.0 + (k % 50) as f64 * 2.0 + 0.5,
                -40.0 + (k / 50) as f64 * 2.0 + 0.5,
            );
            let near = pts
                .iter()
                .any(|p| (p.x - x).powi(2) + (p.z - z).powi(2) < 16.0);
            assert!(near, "hole at ({x}, {z})");
        }
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
    fn one_and_two_threads_sample_alike() {
        let world = Rect::new([-40.0, -30.0], [40.0, 30.0]);
        let run = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("pool")
                .install(|| poisson(world, world, 1.0, 5, &|x, z| x * z > 300.0, 1 << 20))
                .expect("fits")
        };
        let one = run(1);
        assert!(one.len() > 1000);
        assert_eq!(one, run(2));
    }

    #[test]
    fn blocked_points_are_avoided_and_the_cap_is_an_error() {
        let world = Rect::new([0.0, 0.0], [30.0, 30.0]);
        let pts = poisson(world, world, 1.0, 1, &|x, _| x < 10.0, 1 << 20).expect("fits");
        assert!(pts.iter().all(|p| p.x >= 10.0));
        assert!(poisson(world, world, 1.0, 1, &|_, _| false, 10).is_err());
    }
}
