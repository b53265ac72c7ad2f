//! The simplifier's driver: the state kept per leaf label, the loop that pops the cheapest
//! pair and collapses it when its new leaf keeps the area bounds, and the grid's upkeep.

use glam::Vec3;

use super::grid::{EMPTY, Grid};
use super::queue::Queue;
use super::search::{RETRIES, Search};
use super::{Axis, Selection, Weights};
use crate::leaf::Leaf;

/// One simplification under way: the leaves made so far, what each label knows of its
/// partners, the grid and the queue.
pub(super) struct Simplifier {
    pub(super) leaves: Vec<Leaf>,
    pub(super) children: Vec<[u32; 2]>,
    pub(super) alive: Vec<bool>,
    pub(super) alive_count: usize,
    pub(super) searches: Vec<Search>,
    pub(super) grid: Grid,
    pub(super) built_with: usize,
    /// Scratch list of the living labels, for laying out the grid.
    pub(super) living: Vec<u32>,
    pub(super) queue: Queue,
    pub(super) weights: Weights,
    pub(super) max_distance: f32,
    pub(super) min_cos: f32,
    pub(super) max_growth: f32,
    pub(super) min_density: f32,
    pub(super) max_overhang: f32,
    pub(super) axis: Axis,
    pub(super) inv_crown: f32,
}

impl Simplifier {
    pub(super) fn new(leaves: &[Leaf], selection: &Selection) -> Simplifier {
        let axis = selection
            .axis
            .unwrap_or_else(|| Axis::through_crown(leaves));
        let crown = leaves
            .iter()
            .map(|l| axis.distance(l.center))
            .fold(0.0f32, f32::max);
        // A chain has at most 2|O| - 1 leaves: everything per label is allocated once.
        let capacity = 2 * leaves.len();
        let mut all = Vec::with_capacity(capacity);
        all.extend_from_slice(leaves);
        let mut s = Simplifier {
            leaves: all,
            children: Vec::with_capacity(leaves.len()),
            alive: Vec::with_capacity(capacity),
            alive_count: leaves.len(),
            searches: Vec::with_capacity(capacity),
            grid: Grid::default(),
            built_with: 0,
            living: Vec::with_capacity(leaves.len()),
            queue: Queue::with_capacity(capacity),
            weights: selection.weights,
            max_distance: selection.bounds.max_distance.max(0.0),
            max_growth: selection.bounds.max_growth,
            min_density: selection.bounds.min_density,
            max_overhang: selection.bounds.max_overhang,
            min_cos: selection
                .bounds
                .max_angle
                .clamp(0.0, 90.0)
                .to_radians()
                .cos()
                - 1e-6,
            axis,
            inv_crown: if crown > 0.0 { 1.0 / crown } else { 0.0 },
        };
        s.alive.resize(leaves.len(), true);
        s.searches.resize(leaves.len(), Search::FRESH);
        s.rebuild_grid();
        s
    }

    /// Pops the cheapest candidate pair until none is left. A pair with a dead partner moves
    /// its leaf on to its next candidate; a living pair is collapsed if the new leaf keeps
    /// the bounds, otherwise its leaf moves on too. A leaf whose list is used up searches
    /// again, for partners it has not consumed yet.
    pub(super) fn run(&mut self) {
        // The first searches go cell by cell, so neighbouring searches share the cells they
        // read (the queue pops by key alone, so the order of pushes does not matter).
        let order: Vec<u32> = self.grid.traits.iter().map(|t| t.label).collect();
        for i in order {
            if i != EMPTY
                && let Some(item) = self.search(i, false)
            {
                self.queue.push(item);
            }
        }
        while let Some(&(key, a)) = self.queue.peek() {
            let b = key as u32;
            // Both leaves are read first: their loads (random accesses into a large array)
            // overlap with the work on the queue.
            let (la, lb) = (self.leaves[a as usize], self.leaves[b as usize]);
            if !self.alive[a as usize] {
                self.queue.pop();
                continue;
            }
            let dead = !self.alive[b as usize];
            if !dead && self.searches[a as usize].refused_by != b {
                let new = Leaf::collapse(&la, &lb);
                if self.allowed(a, b, &new) {
                    let next = self.collapse(a, b, new);
                    self.replace_top(next);
                    continue;
                }
                self.searches[b as usize].refused_by = a;
            }
            let next = match self.advance(a, key, dead) {
                Some(next) => Some((next, a)),
                None => self.retry(a),
            };
            self.replace_top(next);
        }
    }

    /// The pair on top of the queue is consumed: what comes of it (`a`'s next candidate,
    /// or the first of a new search) takes its place, in one sift-down from the top (short:
    /// its key is close to the least) instead of a pop and a push. Nothing else touches the
    /// queue in between and it holds one entry per leaf, all distinct, so the pops come in
    /// the same order.
    fn replace_top(&mut self, next: Option<(u64, u32)>) {
        match next {
            Some(item) => self.queue.replace_top(item),
            None => {
                self.queue.pop();
            }
        }
    }

    /// Joins `a` and `b` into `new`, which searches for its own partners: the first of them
    /// is returned, to queue.
    fn collapse(&mut self, a: u32, b: u32, new: Leaf) -> Option<(u64, u32)> {
        let label = self.leaves.len() as u32;
        for old in [a, b] {
            self.alive[old as usize] = false;
            self.grid.remove(old, self.leaves[old as usize].center);
        }
        // The thesis' figure 2.3 keeps the lower label on the left.
        self.children.push([a.min(b), a.max(b)]);
        self.leaves.push(new);
        self.alive.push(true);
        self.searches.push(Search::FRESH);
        self.alive_count -= 1;
        if self.alive_count * 2 <= self.built_with {
            self.rebuild_grid();
        } else if !self.grid.insert(label, &new) {
            // The new leaf's cell is full: the same cells laid out again, with new room.
            self.collect_living();
            self.grid.fill(&self.leaves, &self.living);
        }
        self.search(label, false)
    }

    /// `a`'s candidate `consumed` is `dead` or refused: its next living candidate not
    /// refused already, to queue; `None` when its list is used up.
    fn advance(&mut self, a: u32, consumed: u64, dead: bool) -> Option<u64> {
        let s = &mut self.searches[a as usize];
        s.floor = s.floor.max(consumed);
        s.died |= dead;
        while s.next < s.len {
            let key = s.list[s.next as usize];
            s.next += 1;
            let b = key as u32;
            if !self.alive[b as usize] {
                s.floor = s.floor.max(key);
                s.died = true;
            } else if s.refused_by == b {
                // Refused from `b`'s side already: consumed without queueing it.
                s.floor = s.floor.max(key);
            } else {
                return Some(key);
            }
        }
        None
    }

    /// `a`'s list is used up: it searches again when one of its candidates had died, and
    /// a list whose every candidate was refused by the bounds looks farther only `RETRIES`
    /// times, then retires its leaf (new leaves near it still find it). The first
    /// candidate found is returned, to queue.
    fn retry(&mut self, a: u32) -> Option<(u64, u32)> {
        let s = &mut self.searches[a as usize];
        if s.died || s.refused < RETRIES {
            s.refused += u8::from(!s.died);
            self.search(a, true)
        } else {
            None
        }
    }

    /// Whether the new leaf of `a` and `b` keeps the area bounds: it grows the pair's area by
    /// at most `max_growth`, its leaves cover at least `min_density` of it, and its corners
    /// stay within `max_overhang` of the box around the original leaves it stands for.
    fn allowed(&self, a: u32, b: u32, new: &Leaf) -> bool {
        let (la, lb) = (&self.leaves[a as usize], &self.leaves[b as usize]);
        let area = new.area();
        let slack = (new.hi - new.lo) * self.max_overhang;
        let (lo, hi) = (new.lo - slack, new.hi + slack);
        area <= self.max_growth * (la.area() + lb.area())
            && new.leaf_area >= self.min_density * area
            && new
                .corners()
                .iter()
                .all(|c| c.cmpge(lo).all() && c.cmple(hi).all())
    }

    /// The living labels, in increasing order, into `self.living`.
    fn collect_living(&mut self) {
        self.living.clear();
        let alive = self.alive.iter().enumerate().filter(|(_, a)| **a);
        self.living.extend(alive.map(|(i, _)| i as u32));
    }

    /// A grid of the living leaves with about three leaves per occupied cell, so that the
    /// nearest partners of a leaf are found in its cell and the next ring or two.
    fn rebuild_grid(&mut self) {
        self.collect_living();
        let mut lo = Vec3::splat(f32::MAX);
        let mut hi = Vec3::splat(f32::MIN);
        let mut radii = 0.0f64;
        for &i in &self.living {
            let leaf = &self.leaves[i as usize];
            lo = lo.min(leaf.center);
            hi = hi.max(leaf.center);
            radii += f64::from(leaf.radius());
        }
        let living = self.living.len();
        let mean_radius = (radii / living.max(1) as f64) as f32;
        // Cells as wide as the reach of a leaf of the mean size, narrower while the occupied
        // ones hold more than three leaves each (and the grid has at most a cell per leaf).
        let mut cell = self.max_distance * 2.0 * mean_radius;
        let mut grid = std::mem::take(&mut self.grid);
        loop {
            grid.shape(lo, hi, cell, living);
            let occupied = grid.occupied(&self.leaves, &self.living);
            let finer = grid.cell_count() * 8 <= living;
            if occupied * 3 >= living || !finer {
                break;
            }
            cell = grid.cell * 0.5;
        }
        grid.fill(&self.leaves, &self.living);
        self.grid = grid;
        self.built_with = living;
    }
}
