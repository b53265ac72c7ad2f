//! The growing state: attraction points with their nearest nodes, the nodes grown so far,
//! and the updates a new node makes to the points around it.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

use glam::Vec3;
use pge_engine::geometry::Skeleton;

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
    /// Each point's nearest node within the influence radius ([`NONE`]: none yet)...
    pub(super) nearest: Vec<u32>,
    /// ... and its squared distance to it (its reach in the grid).
    pub(super) nearest_d2: Vec<f32>,
    /// Points with a nearest node, in increasing index order (some may have died since).
    active: Vec<u32>,
    /// Points given their first nearest node since `active` was last read, in any order.
    fresh: Vec<u32>,
    /// The buffer the next `active` is built in.
    spare: Vec<u32>,
    /// The live points.
    grid: PointGrid,
    pub(super) nodes: Vec<Vec3>,
    pub(super) parents: Vec<Option<u32>>,
    /// Unit direction of each node's segment (zero for a root).
    pub(super) dirs: Vec<Vec3>,
    /// Unit direction each node's branch started in (zero for a root).
    pub(super) headings: Vec<Vec3>,
    /// Whether a node has grown a child.
    pub(super) has_child: Vec<bool>,
    /// Nodes by cell of side `step`, for the duplicate-growth guard: the last node added
    /// in each cell...
    node_cells: HashMap<[i32; 3], u32, BuildHasherDefault<CellHasher>>,
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
    pub(super) sum: Vec<Vec3>,
    pub(super) count: Vec<u32>,
    pub(super) closest: Vec<(f32, u32)>,
    pub(super) touched: Vec<u32>,
}

impl State {
    /// The state before any node: every point alive, numbered in the order of a grid of
    /// cells a third of the influence radius wide (the order pulls are summed in), in a
    /// grid of such cells, or of cells half the influence radius wide where the points are
    /// sparse.
    pub(super) fn new(pts: Vec<Vec3>, influence: f32) -> State {
        let n = pts.len();
        let alive = vec![true; n];
        // Points that a query reads together then lie together in memory.
        let renumbered =
            |order: Vec<u32>| -> Vec<Vec3> { order.iter().map(|i| pts[*i as usize]).collect() };
        let (points, grid) = match PointGrid::unsplit_order(&pts, &alive, influence / 3.0) {
            // Sparse points (a small tree's crown: a few to a cell, no sub-cells): in larger
            // cells a query reads fewer cells, empty or skipped, for a few more points.
            Some(order) => {
                let points = renumbered(order);
                let grid = PointGrid::new(&points, &alive, influence / 2.0);
                (points, grid)
            }
            None => {
                let mut grid = PointGrid::new(&pts, &alive, influence / 3.0);
                (renumbered(grid.renumber()), grid)
            }
        };
        State {
            points,
            alive,
            alive_count: n,
            nearest: vec![NONE; n],
            nearest_d2: vec![f32::INFINITY; n],
            active: Vec::new(),
            fresh: Vec::new(),
            spare: Vec::new(),
            grid,
            nodes: Vec::new(),
            parents: Vec::new(),
            dirs: Vec::new(),
            headings: Vec::new(),
            has_child: Vec::new(),
            node_cells: HashMap::default(),
            earlier_in_cell: Vec::new(),
            refused: Vec::new(),
            trunk_tips: Vec::new(),
            iteration: 0,
            sum: Vec::new(),
            count: Vec::new(),
            closest: Vec::new(),
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
        self.sum.push(Vec3::ZERO);
        self.count.push(0);
        self.closest.push((f32::INFINITY, NONE));
        let earlier = self.node_cells.insert(cell_of(position, p.step), index);
        self.earlier_in_cell.push(earlier.unwrap_or(NONE));
        index
    }

    /// Adds a node and updates the points it changes: those within the kill distance die,
    /// those within the influence radius that are closer to it than to their nearest node
    /// take it as their nearest. The grid skips every other point without reading it (a
    /// point's reach is its squared distance to its nearest node).
    pub(super) fn add_node(&mut self, position: Vec3, parent: Option<u32>, p: &Params) -> u32 {
        let index = self.push_node(position, parent, p);
        let k2 = p.kill * p.kill;
        let State {
            grid,
            alive,
            alive_count,
            nearest,
            nearest_d2,
            fresh,
            ..
        } = self;
        // The grid calls back only for the live points closer to the new node than their
        // reach, their distance to their nearest node.
        grid.update_near(position, p.influence, |i, d2| {
            let i = i as usize;
            if d2 < k2 {
                alive[i] = false;
                *alive_count -= 1;
                return None;
            }
            if nearest[i] == NONE {
                fresh.push(i as u32);
            }
            nearest[i] = index;
            nearest_d2[i] = d2;
            Some(d2)
        });
        index
    }

    /// Pulls: each live point with a nearest node, in increasing index order (the order in
    /// which the pulls are summed), adds its unit direction to its nearest node's `sum`
    /// (and counts itself, and may be its `closest`), and the pulled nodes are listed in
    /// `touched`. A tip only perceives the points whose direction has a cosine of at least
    /// `perceive` with its own. Points whose node was refused at the last iteration are
    /// dropped as unreachable.
    ///
    /// One pass: the points pulling since before merged with those given their first
    /// nearest node since (each list in increasing order), the dead skipped, and the
    /// points still pulling kept, in order, for the next iteration.
    pub(super) fn pull(&mut self, iteration: u32, perceive: Option<f32>) {
        let old = std::mem::take(&mut self.active);
        let mut fresh = std::mem::take(&mut self.fresh);
        fresh.sort_unstable();
        let mut kept = std::mem::take(&mut self.spare);
        kept.clear();
        kept.reserve(old.len() + fresh.len());
        let (mut a, mut b) = (0, 0);
        while a < old.len() || b < fresh.len() {
            let i = if b == fresh.len() || (a < old.len() && old[a] < fresh[b]) {
                a += 1;
                old[a - 1]
            } else {
                b += 1;
                fresh[b - 1]
            } as usize;
            if !self.alive[i] {
                continue;
            }
            let n = self.nearest[i] as usize;
            if self.refused[n] == iteration - 1 {
                // The node could not grow toward these points last time: unreachable.
                self.kill(i);
                continue;
            }
            kept.push(i as u32);
            let d2 = self.nearest_d2[i];
            let to = (self.points[i] - self.nodes[n]) / d2.sqrt();
            if let Some(cos) = perceive
                && !self.has_child[n]
                && self.dirs[n] != Vec3::ZERO
                && to.dot(self.dirs[n]) < cos
            {
                continue;
            }
            if self.count[n] == 0 {
                self.touched.push(n as u32);
            }
            self.sum[n] += to;
            self.count[n] += 1;
            if d2 < self.closest[n].0 {
                self.closest[n] = (d2, i as u32);
            }
        }
        fresh.clear();
        self.fresh = fresh;
        self.active = kept;
        self.spare = old;
    }

    /// Whether no point pulled at the last iteration nor was given a nearest node since.
    pub(super) fn none_active(&self) -> bool {
        self.fresh.is_empty() && self.active.is_empty()
    }

    /// Whether a live point lies within the influence radius of `q` (and outside the kill
    /// distance, as after a node at `q` was added).
    pub(super) fn in_range(&self, q: Vec3, p: &Params) -> bool {
        let k2 = p.kill * p.kill;
        let mut found = false;
        self.grid.for_each_near(q, p.influence, |_, _, d2| {
            found |= d2 >= k2;
        });
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
                continue;
            }
            self.push_node(position, start.parents[i], p);
            let State {
                grid,
                alive,
                alive_count,
                ..
            } = self;
            // A live point's reach is at least the kill distance (a point that close to a
            // node died), so the grid calls back for every point within it.
            grid.update_near(position, p.kill, |j, _| {
                alive[j as usize] = false;
                *alive_count -= 1;
                None
            });
        }
    }

    /// Whether a node stands within `eps` of `q`: only the cells that the box of half-side
    /// `eps` (widened a little above rounding) around `q` overlaps can hold one.
    pub(super) fn occupied(&self, q: Vec3, eps: f32, step: f32) -> bool {
        let wide = eps * 1.01 + 1e-6 * q.abs().max_element();
        let (lo, hi) = (cell_of(q - wide, step), cell_of(q + wide, step));
        for x in lo[0]..=hi[0] {
            for y in lo[1]..=hi[1] {
                for z in lo[2]..=hi[2] {
                    let mut n = self.node_cells.get(&[x, y, z]).copied().unwrap_or(NONE);
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

    /// Removes point `i` (nothing if it is dead already).
    pub(super) fn kill(&mut self, i: usize) {
        if self.alive[i] {
            self.alive[i] = false;
            self.alive_count -= 1;
            self.grid.remove(i as u32);
        }
    }
}

/// A fast hasher for integer cell keys (multiply-rotate, as rustc's FxHasher); the cell map
/// is only probed, never iterated, so its order cannot leak into the output.
#[derive(Default)]
struct CellHasher(u64);

impl Hasher for CellHasher {
    fn finish(&self) -> u64 {
        self.0
    }

    fn write(&mut self, bytes: &[u8]) {
        for chunk in bytes.chunks(4) {
            let mut word = [0u8; 4];
            word[..chunk.len()].copy_from_slice(chunk);
            self.write_u64(u64::from(u32::from_le_bytes(word)));
        }
    }

    fn write_i32(&mut self, i: i32) {
        self.write_u64(i as u32 as u64);
    }

    fn write_u64(&mut self, i: u64) {
        self.0 = (self.0.rotate_left(5) ^ i).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
}

/// The cell of side `step` holding `p`.
pub(super) fn cell_of(p: Vec3, step: f32) -> [i32; 3] {
    let c = p / step;
    [floor_i32(c.x), floor_i32(c.y), floor_i32(c.z)]
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
mod tests {
    use super::floor_i32;

    #[test]
    fn floor_i32_is_floor_cast() {
        let mut xs = vec![
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            -1.5,
            2.999_999_8,
            -2.000_000_2,
            16_777_217.0,
            -16_777_215.5,
            2.5e9,
            -2.5e9,
            -2_147_483_648.0,
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::MIN_POSITIVE,
            -f32::MIN_POSITIVE,
        ];
        xs.extend((-2000..2000).map(|k| k as f32 * 0.173));
        for x in xs {
            assert_eq!(floor_i32(x), x.floor() as i32, "{x}");
        }
    }
}
