//! The growing state: attraction points with their nearest nodes, the nodes grown so far,
//! and the updates a new node makes to the points around it.

use std::sync::atomic::{AtomicUsize, Ordering};

use glam::Vec3;
use pge_engine::geometry::Skeleton;
use rustc_hash::{FxBuildHasher, FxHashMap};

use super::Params;
use crate::grid::PointGrid;

pub(super) const NONE: u32 = u32::MAX;

/// The growing state.
#[derive(Clone)]
pub(super) struct State {
    /// The attraction points, numbered in the grid's order (spatially coherent), not in
    /// the order they were drawn.
    pub(super) points: Vec<Vec3>,
    pub(super) alive: Vec<bool>,
    pub(super) alive_count: usize,
    /// Each point's nearest node within the influence radius and its squared distance to it.
    nearest: Vec<Nearest>,
    /// The live points with a nearest node, one bit each (bit `i % 64` of word `i / 64`):
    /// read in increasing index order, the order pulls are summed in. A point's bit is
    /// cleared as it dies, so the pulls read no `alive` (a mispredicted branch as points
    /// die).
    pulling: Vec<u64>,
    /// The points the last pull kept pulling (alive, with a nearest node that was not
    /// refused).
    pulled: usize,
    /// The points given their first nearest node since the last pull.
    fresh: usize,
    /// The live points: one part, or two whose updates run side by side on the pool.
    parts: Vec<Part>,
    /// Nodes added whose updates to the points are not applied yet (see [`State::flush`]).
    pending: Vec<(u32, Vec3)>,
    pub(super) nodes: Vec<Vec3>,
    pub(super) parents: Vec<Option<u32>>,
    /// Unit direction of each node's segment (zero for a root).
    pub(super) dirs: Vec<Vec3>,
    /// Unit direction each node's branch started in (zero for a root).
    pub(super) headings: Vec<Vec3>,
    /// Whether a node has grown a child.
    pub(super) has_child: Vec<bool>,
    /// Nodes by cell of side `step` (by [`cell_key`]), for the duplicate-growth guard: the
    /// last node added in each cell (a map only probed, never iterated, so its order cannot
    /// leak into the output)...
    node_cells: FxHashMap<u64, u32>,
    /// ... and for each node, the node added before it in its cell ([`NONE`]: none), so
    /// that a cell's nodes are a chain without a list of their own.
    earlier_in_cell: Vec<u32>,
    /// The iteration in which a node's growth was refused (its pullers are dropped next).
    pub(super) refused: Vec<u32>,
    /// Roots still growing their trunk: the trunk's current tip and the length of straight
    /// trunk it must still grow.
    pub(super) trunk_tips: Vec<(u32, f32)>,
    pub(super) iteration: u32,
    // Per-step scratch.
    /// Each node's pull in the current iteration.
    pub(super) pulls: Vec<Pull>,
    pub(super) touched: Vec<u32>,
}

/// A point's nearest node, in one record as the pulls and the updates read it.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Nearest {
    /// The node ([`NONE`]: none yet)...
    node: u32,
    /// ... and the squared distance to it (the point's reach in the grid).
    d2: f32,
}

impl Nearest {
    const NONE: Nearest = Nearest {
        node: NONE,
        d2: f32::INFINITY,
    };
}

/// A node's pull in an iteration: the sum of its points' unit vectors and its closest
/// point ([`NONE`]: not pulled).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Pull {
    pub(super) sum: Vec3,
    pub(super) closest_d2: f32,
    pub(super) closest: u32,
}

impl Pull {
    pub(super) const NONE: Pull = Pull {
        sum: Vec3::ZERO,
        closest_d2: f32::INFINITY,
        closest: NONE,
    };
}

/// The live points numbered from `first` (a multiple of 64) up to the next part's `first`,
/// in a grid of their own. Points are numbered cell by cell along x first, so two parts are
/// two slabs of the crown (sharing at most one layer of cells), and a new node's updates of
/// one part touch nothing of the other's: the parts can be updated side by side, each in
/// the nodes' order, with the bytes of one after the other.
#[derive(Clone)]
struct Part {
    first: usize,
    grid: PointGrid,
    /// Points given their first nearest node by the last updates.
    fresh: usize,
    /// Points killed by the last updates.
    killed: usize,
}

/// A part's own ranges of the state's per-point arrays: its points' `alive` and `nearest`
/// records and the words of their bits in `pulling` (a part starts on a word).
struct Own<'a> {
    alive: &'a mut [bool],
    nearest: &'a mut [Nearest],
    pulling: &'a mut [u64],
}

impl Part {
    fn new(first: usize, grid: PointGrid) -> Part {
        Part {
            first,
            grid,
            fresh: 0,
            killed: 0,
        }
    }

    /// Applies the updates of `nodes` (index and position, in order) to the part's points,
    /// for the influence radius and the squared kill distance `k2`.
    fn update(&mut self, nodes: &[(u32, Vec3)], influence: f32, k2: f32, own: Own<'_>) {
        let Part {
            grid,
            fresh,
            killed,
            ..
        } = self;
        let Own {
            alive,
            nearest,
            pulling,
        } = own;
        for &(index, q) in nodes {
            // The grid calls back only for the live points closer to the new node than
            // their reach, their distance to their nearest node.
            grid.update_near(q, influence, |i, d2| {
                let i = i as usize;
                if d2 < k2 {
                    alive[i] = false;
                    pulling[i / 64] &= !(1 << (i % 64));
                    *killed += 1;
                    return None;
                }
                // Without a branch: the point pulls from now on (its bit may be set
                // already), and is fresh when it had no nearest node.
                let point = &mut nearest[i];
                *fresh += usize::from(point.node == NONE);
                pulling[i / 64] |= 1 << (i % 64);
                *point = Nearest { node: index, d2 };
                Some(d2)
            });
        }
    }
}

/// Points below which the updates stay in one part: the pool's hand-over (some 20 us an
/// iteration) and the second grid cost about what the second thread saves (the oak's 3,000
/// points take 39 iterations of some 60 us each).
const PARTS_FROM: usize = 20_000;

/// New nodes below which a flush updates the parts one after the other.
const SIDE_BY_SIDE_FROM: usize = 32;

/// Rounds of waiting for the other parts' updates before the calling thread sleeps (some
/// 0.1-0.5 ms; a 64th of it for parts not started yet).
const SPIN: usize = 1 << 12;

impl State {
    /// The state before any node: every point alive, numbered in the order of a grid of
    /// cells a third of the influence radius wide (the order pulls are summed in), in a
    /// grid of such cells, or of cells two thirds of the influence radius wide where the
    /// points are sparse.
    pub(super) fn new(pts: Vec<Vec3>, influence: f32) -> State {
        let parts = if pts.len() >= PARTS_FROM && rayon::current_num_threads() > 1 {
            2
        } else {
            1
        };
        State::with_parts(pts, influence, parts)
    }

    /// [`State::new`] with the points in `parts` parts (1 or 2).
    fn with_parts(pts: Vec<Vec3>, influence: f32, parts: usize) -> State {
        let n = pts.len();
        let alive = vec![true; n];
        // Points that a query reads together then lie together in memory.
        let renumbered =
            |order: Vec<u32>| -> Vec<Vec3> { order.iter().map(|i| pts[*i as usize]).collect() };
        let (points, grid) = match PointGrid::unsplit_order(&pts, &alive, influence / 3.0) {
            // Sparse points (a small tree's crown: a few to a cell, no sub-cells): in larger
            // cells a query reads fewer cells, empty or skipped, for a few more points. Two
            // thirds of the radius rather than a half: the oak's growth 0.90x of the
            // instructions and 0.80x of the mispredicted branches (a ball spans at most four
            // cells a side instead of five).
            Some(order) => (renumbered(order), None),
            None => {
                let mut grid = PointGrid::new(&pts, &alive, influence / 3.0);
                (renumbered(grid.renumber()), Some(grid))
            }
        };
        let cell = if grid.is_some() {
            influence / 3.0
        } else {
            influence / 1.5
        };
        let parts = if parts > 1 {
            // On a word of the pulling bits, which each part then owns whole.
            let half = n / 2 / 64 * 64;
            vec![
                Part::new(0, PointGrid::new(&points[..half], &alive[..half], cell)),
                Part::new(half, PointGrid::new(&points[half..], &alive[half..], cell)),
            ]
        } else {
            vec![Part::new(
                0,
                grid.unwrap_or_else(|| PointGrid::new(&points, &alive, cell)),
            )]
        };
        State {
            points,
            alive,
            alive_count: n,
            nearest: vec![Nearest::NONE; n],
            pulling: vec![0; n.div_ceil(64)],
            pulled: 0,
            fresh: 0,
            parts,
            pending: Vec::new(),
            nodes: Vec::new(),
            parents: Vec::new(),
            dirs: Vec::new(),
            headings: Vec::new(),
            has_child: Vec::new(),
            // A sparse crown grows about one node for two points: its map is made once
            // (denser crowns, and their larger maps, grow theirs as they go).
            node_cells: FxHashMap::with_capacity_and_hasher((n / 2).min(4096), FxBuildHasher),
            earlier_in_cell: Vec::new(),
            refused: Vec::new(),
            trunk_tips: Vec::new(),
            iteration: 0,
            pulls: Vec::new(),
            touched: Vec::new(),
        }
    }

    /// Appends a node (its per-node scratch and its cell) without touching the points.
    pub(super) fn push_node(&mut self, position: Vec3, parent: Option<u32>, p: &Params) -> u32 {
        let index = self.nodes.len() as u32;
        let dir = parent.map_or(Vec3::ZERO, |q| {
            (position - self.nodes[q as usize]).normalize_or_zero()
        });
        // The first child continues its parent's branch, later ones start their own.
        let heading = match parent.map(|q| q as usize) {
            Some(q) if !self.has_child[q] && self.headings[q] != Vec3::ZERO => self.headings[q],
            _ => dir,
        };
        if let Some(q) = parent {
            self.has_child[q as usize] = true;
        }
        self.nodes.push(position);
        self.parents.push(parent);
        self.dirs.push(dir);
        self.headings.push(heading);
        self.has_child.push(false);
        self.refused.push(NONE);
        self.pulls.push(Pull::NONE);
        let cell = cell_key(cell_of(position, 1.0 / p.step));
        let earlier = self.node_cells.insert(cell, index);
        self.earlier_in_cell.push(earlier.unwrap_or(NONE));
        index
    }

    /// Adds a node; the points it changes are updated at the next [`State::flush`]: those
    /// within the kill distance die, those within the influence radius that are closer to
    /// it than to their nearest node take it as their nearest.
    pub(super) fn add_node(&mut self, position: Vec3, parent: Option<u32>, p: &Params) -> u32 {
        let index = self.push_node(position, parent, p);
        self.pending.push((index, position));
        index
    }

    /// Applies the updates of the nodes added since the last flush, in the order they were
    /// added. The grid skips every point a node does not change without reading it (a
    /// point's reach is its squared distance to its nearest node). With two parts and a few
    /// nodes, the second part is updated on the pool beside the first.
    pub(super) fn flush(&mut self, p: &Params) {
        if self.pending.is_empty() {
            return;
        }
        let (nodes, r, k2) = (&self.pending[..], p.influence, p.kill * p.kill);
        // Each part with its own ranges of the per-point arrays, the first part last.
        let mut work = Vec::with_capacity(self.parts.len());
        let (mut alive, mut nearest) = (&mut self.alive[..], &mut self.nearest[..]);
        let mut pulling = &mut self.pulling[..];
        for part in self.parts.iter_mut().rev() {
            let (below, own_alive) = alive.split_at_mut(part.first);
            let (below_nearest, own_nearest) = nearest.split_at_mut(part.first);
            let (below_pulling, own_pulling) = pulling.split_at_mut(part.first / 64);
            (alive, nearest, pulling) = (below, below_nearest, below_pulling);
            let own = Own {
                alive: own_alive,
                nearest: own_nearest,
                pulling: own_pulling,
            };
            work.push((part, own));
        }
        if work.len() > 1 && nodes.len() >= SIDE_BY_SIDE_FROM {
            let others = work.len() - 1;
            let (started, ended) = (AtomicUsize::new(0), AtomicUsize::new(0));
            rayon::in_place_scope(|scope| {
                let mine = work.pop();
                for (part, own) in work {
                    let (started, ended) = (&started, &ended);
                    scope.spawn(move |_| {
                        started.fetch_add(1, Ordering::Relaxed);
                        part.update(nodes, r, k2, own);
                        ended.fetch_add(1, Ordering::Release);
                    });
                }
                if let Some((part, own)) = mine {
                    part.update(nodes, r, k2, own);
                }
                // Parts running on the pool usually end within microseconds: waiting for
                // them here spares the calling thread a sleep and its wake-up (some 10 us).
                // Parts not started (a busy pool) are left to the scope, which runs them
                // itself on a pool thread.
                for round in 0..SPIN {
                    let waiting = ended.load(Ordering::Acquire) < others;
                    if !waiting || (round >= SPIN / 64 && started.load(Ordering::Relaxed) < others)
                    {
                        break;
                    }
                    std::hint::spin_loop();
                }
            });
        } else {
            for (part, own) in work {
                part.update(nodes, r, k2, own);
            }
        }
        for part in &mut self.parts {
            self.alive_count -= part.killed;
            part.killed = 0;
            self.fresh += std::mem::take(&mut part.fresh);
        }
        self.pending.clear();
    }

    /// Pulls: each live point with a nearest node, in increasing index order (the order in
    /// which the pulls are summed), adds its unit direction to its nearest node's pull's
    /// `sum` (and may be its `closest`), and the pulled nodes are listed in `touched`. A tip
    /// only perceives the points whose direction has a cosine of at least `perceive` with
    /// its own. Points whose node was refused at the last iteration are dropped as
    /// unreachable.
    ///
    /// One pass over the bits of the live points with a nearest node: no list to sort or
    /// merge.
    pub(super) fn pull(&mut self, iteration: u32, perceive: Option<f32>) {
        let mut pulled = 0;
        for w in 0..self.pulling.len() {
            let mut word = self.pulling[w];
            let mut bits = word;
            while bits != 0 {
                let bit = bits & bits.wrapping_neg();
                bits ^= bit;
                // A point's bit is cleared as it dies: every point read here is alive.
                let i = w * 64 + bit.trailing_zeros() as usize;
                let Nearest { node, d2 } = self.nearest[i];
                let n = node as usize;
                if self.refused[n] == iteration - 1 {
                    // The node could not grow toward these points last time: unreachable.
                    word ^= bit;
                    self.kill(i);
                    continue;
                }
                pulled += 1;
                let to = (self.points[i] - self.nodes[n]) / d2.sqrt();
                if let Some(cos) = perceive
                    && !self.has_child[n]
                    && self.dirs[n] != Vec3::ZERO
                    && to.dot(self.dirs[n]) < cos
                {
                    continue;
                }
                let pull = &mut self.pulls[n];
                if pull.closest == NONE {
                    self.touched.push(n as u32);
                }
                pull.sum += to;
                if d2 < pull.closest_d2 {
                    (pull.closest_d2, pull.closest) = (d2, i as u32);
                }
            }
            self.pulling[w] = word;
        }
        self.pulled = pulled;
        self.fresh = 0;
    }

    /// Whether no point pulled at the last iteration nor was given a nearest node since.
    pub(super) fn none_active(&self) -> bool {
        self.fresh == 0 && self.pulled == 0
    }

    /// Whether a live point lies within the influence radius of `q` (and outside the kill
    /// distance, as after a node at `q` was added).
    pub(super) fn in_range(&self, q: Vec3, p: &Params) -> bool {
        let k2 = p.kill * p.kill;
        let mut found = false;
        for part in &self.parts {
            part.grid.for_each_near(q, p.influence, |_, _, d2| {
                found |= d2 >= k2;
            });
        }
        found
    }

    /// Seeds the nodes from a start skeleton (`start = skeleton`): every node in order;
    /// the tips attract points as grown nodes do, the other nodes only remove the points
    /// within the kill distance (they are wood already, not buds).
    pub(super) fn seed_from(&mut self, start: &Skeleton, p: &Params) {
        let mut is_tip = vec![true; start.len()];
        for q in start.parents.iter().flatten() {
            is_tip[*q as usize] = false;
        }
        for (i, &tip) in is_tip.iter().enumerate() {
            let position = start.positions[i];
            if tip {
                self.add_node(position, start.parents[i], p);
                self.flush(p);
                continue;
            }
            self.push_node(position, start.parents[i], p);
            let State {
                parts,
                alive,
                alive_count,
                pulling,
                ..
            } = self;
            // A live point's reach is at least the kill distance (a point that close to a
            // node died), so the grid calls back for every point within it.
            for part in parts {
                let first = part.first;
                part.grid.update_near(position, p.kill, |j, _| {
                    let i = first + j as usize;
                    alive[i] = false;
                    pulling[i / 64] &= !(1 << (i % 64));
                    *alive_count -= 1;
                    None
                });
            }
        }
    }

    /// Whether a node stands within `eps` of `q`: only the cells that the box of half-side
    /// `eps` (widened a little above rounding) around `q` overlaps can hold one (the cells
    /// are numbered by a rounded-down product, which only grows with the coordinate).
    pub(super) fn occupied(&self, q: Vec3, eps: f32, step: f32) -> bool {
        let wide = eps * 1.01 + 1e-6 * q.abs().max_element();
        let inv_step = 1.0 / step;
        let (lo, hi) = (cell_of(q - wide, inv_step), cell_of(q + wide, inv_step));
        for x in lo[0]..=hi[0] {
            for y in lo[1]..=hi[1] {
                for z in lo[2]..=hi[2] {
                    let cell = cell_key([x, y, z]);
                    let mut n = self.node_cells.get(&cell).copied().unwrap_or(NONE);
                    while n != NONE {
                        if self.nodes[n as usize].distance_squared(q) < eps * eps {
                            return true;
                        }
                        n = self.earlier_in_cell[n as usize];
                    }
                }
            }
        }
        false
    }

    /// The part holding point `i`.
    fn part_of(&mut self, i: usize) -> &mut Part {
        let k = self.parts.partition_point(|part| part.first <= i) - 1;
        &mut self.parts[k]
    }

    /// Removes point `i` (nothing if it is dead already).
    pub(super) fn kill(&mut self, i: usize) {
        if self.alive[i] {
            self.alive[i] = false;
            self.alive_count -= 1;
            self.pulling[i / 64] &= !(1 << (i % 64));
            let part = self.part_of(i);
            part.grid.remove((i - part.first) as u32);
        }
    }
}

/// The cell holding `p` among cells of side `1 / inv_step` (numbered by the rounded-down
/// product with `inv_step`, the same for the guard's writes and reads).
pub(super) fn cell_of(p: Vec3, inv_step: f32) -> [i32; 3] {
    let c = p * inv_step;
    [floor_i32(c.x), floor_i32(c.y), floor_i32(c.z)]
}

/// A cell's key in the guard's map: the low 21 bits of each coordinate. Cells 2^21 apart
/// share a key, and so a chain, which only adds nodes for `occupied` to measure.
fn cell_key([x, y, z]: [i32; 3]) -> u64 {
    let bits = |c: i32| u64::from(c as u32) & ((1 << 21) - 1);
    (bits(x) << 42) | (bits(y) << 21) | bits(z)
}

/// `x.floor() as i32` without the call to `floor` (a libm call on the baseline x86-64
/// target): the cast rounds toward zero, one less below zero off the integers. Where the
/// cast saturates, so does `floor`'s; NaN gives 0 both ways; and beyond 2^24 every float is
/// an integer, so the comparison is exact.
fn floor_i32(x: f32) -> i32 {
    let t = x as i32;
    if (t as f32) > x {
        t.saturating_sub(1)
    } else {
        t
    }
}

#[cfg(test)]
mod tests;
