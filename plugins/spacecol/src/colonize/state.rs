//! The growing state: attraction points with their nearest nodes, the nodes grown so far,
//! and the updates a new node makes to the points around it.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

use glam::Vec3;
use pge_engine::geometry::Skeleton;

use super::Params;
use crate::points::PointGrid;

pub(super) const NONE: u32 = u32::MAX;

/// The growing state.
#[derive(Clone)]
pub(super) struct State {
    pub(super) points: Vec<Vec3>,
    pub(super) alive: Vec<bool>,
    pub(super) alive_count: usize,
    pub(super) nearest: Vec<u32>,
    pub(super) nearest_d2: Vec<f32>,
    /// Points with a nearest node within reach (some may be dead; filtered each step).
    pub(super) active: Vec<u32>,
    pub(super) grid: PointGrid,
    pub(super) dead_since_grid: usize,
    pub(super) nodes: Vec<Vec3>,
    pub(super) parents: Vec<Option<u32>>,
    /// Unit direction of each node's segment (zero for a root).
    pub(super) dirs: Vec<Vec3>,
    /// Unit direction each node's branch started in (zero for a root).
    pub(super) headings: Vec<Vec3>,
    /// Whether a node has grown a child.
    pub(super) has_child: Vec<bool>,
    /// Nodes by cell of side `step`, for the duplicate-growth guard.
    node_cells: HashMap<[i32; 3], Vec<u32>, BuildHasherDefault<CellHasher>>,
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
    /// The state before any node: every point alive, in a grid of cells a third of the
    /// influence radius wide.
    pub(super) fn new(pts: Vec<Vec3>, influence: f32) -> State {
        let n = pts.len();
        let alive = vec![true; n];
        let grid = PointGrid::new(&pts, &alive, influence / 3.0);
        State {
            points: pts,
            alive,
            alive_count: n,
            nearest: vec![NONE; n],
            nearest_d2: vec![f32::INFINITY; n],
            active: Vec::new(),
            grid,
            dead_since_grid: 0,
            nodes: Vec::new(),
            parents: Vec::new(),
            dirs: Vec::new(),
            headings: Vec::new(),
            has_child: Vec::new(),
            node_cells: HashMap::default(),
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
        self.node_cells
            .entry(cell_of(position, p.step))
            .or_default()
            .push(index);
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
            active,
            dead_since_grid,
            ..
        } = self;
        grid.update_near(position, p.influence, |i, d2| {
            let i = i as usize;
            if !alive[i] {
                return 0.0;
            }
            if d2 < k2 {
                alive[i] = false;
                *alive_count -= 1;
                *dead_since_grid += 1;
                return 0.0;
            }
            if d2 < nearest_d2[i] {
                if nearest[i] == NONE {
                    active.push(i as u32);
                }
                nearest[i] = index;
                nearest_d2[i] = d2;
            }
            nearest_d2[i]
        });
        index
    }

    /// Whether a live point lies within the influence radius of `q` (and outside the kill
    /// distance, as after a node at `q` was added).
    pub(super) fn in_range(&self, q: Vec3, p: &Params) -> bool {
        let k2 = p.kill * p.kill;
        let mut found = false;
        self.grid.for_each_near(q, p.influence, |i, _, d2| {
            found |= d2 >= k2 && self.alive[i as usize];
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
        let k2 = p.kill * p.kill;
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
                dead_since_grid,
                ..
            } = self;
            grid.for_each_near(position, p.kill, |j, _, d2| {
                let j = j as usize;
                if alive[j] && d2 < k2 {
                    alive[j] = false;
                    *alive_count -= 1;
                    *dead_since_grid += 1;
                }
            });
        }
    }

    /// Whether a node stands within `eps` of `q`.
    pub(super) fn occupied(&self, q: Vec3, eps: f32, step: f32) -> bool {
        let c = cell_of(q, step);
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    if let Some(list) = self.node_cells.get(&[c[0] + dx, c[1] + dy, c[2] + dz])
                        && list
                            .iter()
                            .any(|n| self.nodes[*n as usize].distance_squared(q) < eps * eps)
                    {
                        return true;
                    }
                }
            }
        }
        false
    }

    pub(super) fn kill(&mut self, i: usize) {
        if self.alive[i] {
            self.alive[i] = false;
            self.alive_count -= 1;
            self.dead_since_grid += 1;
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

pub(super) fn cell_of(p: Vec3, step: f32) -> [i32; 3] {
    let c = (p / step).floor();
    [c.x as i32, c.y as i32, c.z as i32]
}
