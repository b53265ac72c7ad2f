//! Leaf-collapse simplification (seed 003, §2.4.1 "Criterio de selección", after the FSA of
//! Remolar et al.): repeatedly collapse the pair of leaves that minimises a weighted
//! distance, within bounds that forbid far or differently oriented pairs, until no pair is
//! allowed. The result is the collapse forest ([`Chain`]).
//!
//! The thesis evaluates every pair at every step (cubic in the number of leaves). Here a
//! leaf's candidates come from a dense uniform grid (rebuilt coarser each time half the
//! leaves have merged): the living leaves no larger than it within the distance bound, of
//! which it keeps the eight cheapest in a list. A priority queue holds one entry per leaf,
//! its cheapest unconsumed candidate, and is updated lazily: a popped pair whose partner has
//! gone, or whose new leaf would break the area bounds, moves its leaf on to its next
//! candidate; a leaf whose list is used up searches again (for partners made since, or
//! beyond the ones it consumed), and a new leaf searches for its own. Costs never change
//! while both leaves live and the bounds are checked on the new leaf only when its pair is
//! the cheapest in the queue, which then becomes the new leaf itself. Nothing is allocated
//! per collapse; the result is deterministic (ties go to the lower label).
//!
//! The search is bound by memory latency, so its data is laid out to be read in runs: the
//! grid's cells lie one after the other in two arrays (centres and radii, then what the cost
//! needs), each with room for new leaves; the queue is a 4-ary heap (half the levels of a
//! binary one); and a refused pair is remembered by the partner, whose own attempt at the
//! same pair (refusal is symmetric) is then skipped without building the new leaf again.

use std::ops::Range;

use glam::{Vec3, Vec4};

use crate::leaf::Leaf;

/// Weights of the collapse distance's terms (seed 003 §2.4.1). Every term is dimensionless,
/// so the weights compare directly; a weight of 0 switches its term off.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Weights {
    /// Euclidean distance between the centres, divided by the sum of both leaves' radii.
    pub distance: f32,
    /// Coplanarity: `1 - |cos|` of the angle between the normals (0 for parallel planes).
    pub coplanarity: f32,
    /// Difference of represented-leaf counts, `|na - nb| / (na + nb)`: balanced collapses.
    pub count: f32,
    /// Difference of areas, `|Aa - Ab| / (Aa + Ab)`: large leaves do not swallow small ones.
    pub area: f32,
    /// Interiority: distance from the pair's midpoint to the tree's axis over the crown's
    /// radius, so inner leaves (least visible from afar) collapse first.
    pub interiority: f32,
}

impl Default for Weights {
    fn default() -> Self {
        Weights {
            distance: 1.0,
            coplanarity: 0.5,
            count: 0.5,
            area: 0.25,
            interiority: 0.25,
        }
    }
}

/// The bounds that forbid a pair whatever its distance (seed 003 §2.4.1: "valores frontera
/// ... previene el emparejamiento de hojas muy alejadas ... u orientadas en direcciones muy
/// diferentes").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    /// Largest centre distance, in units of the sum of both leaves' radii.
    pub max_distance: f32,
    /// Largest angle between the two leaves' planes, in degrees (0..=90; leaves are
    /// double-sided, so a normal and its opposite are the same plane).
    pub max_angle: f32,
    /// Largest area of the new leaf over the pair's summed areas: the thesis sets the new
    /// area halfway between the summed and the bounding area "to avoid a large increase";
    /// this refuses the pairs whose bounding quad is mostly empty (a large leaf swallowing a
    /// small one across its diagonal would otherwise grow without end).
    pub max_growth: f32,
    /// Smallest density (represented leaf area over the new leaf's area) of a new leaf:
    /// coarse leaves may thin out, but not into empty quads.
    pub min_density: f32,
    /// How far a new leaf's corners may reach past the box around the original leaves it
    /// represents, as a fraction of that box's size per axis: coarse leaves stay within the
    /// crown instead of compounding the bounding quads' slack level after level.
    pub max_overhang: f32,
}

impl Default for Bounds {
    fn default() -> Self {
        Bounds {
            max_distance: 1.5,
            max_angle: 75.0,
            max_growth: 2.0,
            min_density: 0.1,
            max_overhang: 0.1,
        }
    }
}

/// The vertical line the interiority term measures from: the tree's main axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Axis {
    /// A point on the axis (the trunk's base).
    pub origin: Vec3,
    /// Its unit direction.
    pub direction: Vec3,
}

impl Axis {
    /// Distance from `p` to the axis.
    #[must_use]
    pub fn distance(&self, p: Vec3) -> f32 {
        let d = p - self.origin;
        (d - self.direction * d.dot(self.direction)).length()
    }
}

/// The collapse forest (seed 003 §2.5.1, figure 2.3): the original leaves `0..originals`,
/// then each new leaf in the order it was made, with the two leaves it replaced.
#[derive(Clone, Debug, PartialEq)]
pub struct Chain {
    /// Every leaf of the chain (the thesis' M), labelled by position.
    pub leaves: Vec<Leaf>,
    /// How many of `leaves` are original (the thesis' |O|).
    pub originals: usize,
    /// For new leaf `originals + k`, the labels of the two leaves it replaced.
    pub children: Vec<[u32; 2]>,
}

impl Chain {
    /// A chain without collapses.
    #[must_use]
    pub fn flat(leaves: Vec<Leaf>) -> Chain {
        Chain {
            originals: leaves.len(),
            leaves,
            children: Vec::new(),
        }
    }

    /// For every label, the leaf that replaced it (`None` for a root).
    #[must_use]
    pub fn parents(&self) -> Vec<Option<u32>> {
        let mut parents = vec![None; self.leaves.len()];
        for (k, pair) in self.children.iter().enumerate() {
            for &c in pair {
                parents[c as usize] = Some((self.originals + k) as u32);
            }
        }
        parents
    }

    /// The roots (leaves never collapsed, the thesis' R), by increasing label.
    #[must_use]
    pub fn roots(&self) -> Vec<u32> {
        self.parents()
            .iter()
            .enumerate()
            .filter(|(_, p)| p.is_none())
            .map(|(i, _)| i as u32)
            .collect()
    }
}

/// Everything the selection needs besides the leaves.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Selection {
    /// The distance's weights.
    pub weights: Weights,
    /// The bounds.
    pub bounds: Bounds,
    /// The tree's axis; `None`: the vertical through the centre of the leaves' bounding box.
    pub axis: Option<Axis>,
}

/// Simplifies `leaves` into a collapse chain: until no allowed pair is left, collapse the
/// pair minimising the weighted distance of [`Weights`] within [`Bounds`] into
/// [`Leaf::collapse`]. Leaves must be finite with positive areas ([`Leaf::from_quad`]
/// builds such leaves).
#[must_use]
pub fn simplify(leaves: &[Leaf], selection: &Selection) -> Chain {
    let mut s = Simplifier::new(leaves, selection);
    s.run();
    Chain {
        leaves: s.leaves,
        originals: leaves.len(),
        children: s.children,
    }
}

/// How many candidate partners a leaf remembers between searches (its nearest by cost).
const CANDIDATES: usize = 8;

/// How many times a leaf whose candidates were all refused looks farther.
const RETRIES: u8 = 1;

/// A candidate's sort key: the cost's bits (non-negative floats order like their bits)
/// above the partner's label, so ties go to the lower label.
fn key(cost: f32, label: u32) -> u64 {
    (u64::from(cost.to_bits()) << 32) | u64::from(label)
}

/// What the simplifier keeps per leaf label besides the leaf: its candidate list (the
/// `CANDIDATES` cheapest allowed-by-angle partners of its last search, by key), how far it
/// has been consumed, the largest key consumed and the first label its last search did not
/// see.
#[derive(Clone, Copy)]
struct Search {
    len: u8,
    next: u8,
    /// Whether a candidate of the list was found dead (the search is worth repeating).
    died: bool,
    /// Searches repeated although every candidate had been refused.
    refused: u8,
    floor: u64,
    seen_below: u32,
}

impl Search {
    const FRESH: Search = Search {
        len: 0,
        next: 0,
        died: false,
        refused: 0,
        floor: 0,
        seen_below: 0,
    };
}

struct Simplifier {
    leaves: Vec<Leaf>,
    children: Vec<[u32; 2]>,
    alive: Vec<bool>,
    alive_count: usize,
    /// Per label, the last partner whose pair with it was refused by the area bounds
    /// (`EMPTY`: none). Refusal is symmetric and final while both leaves live, so the
    /// partner's own attempt at the pair is skipped instead of building the new leaf again.
    refused_by: Vec<u32>,
    /// `CANDIDATES` keys per label (only the first `len` of each are meaningful).
    candidates: Vec<u64>,
    searches: Vec<Search>,
    grid: Grid,
    built_with: usize,
    /// Scratch list of the living labels, for laying out the grid.
    living: Vec<u32>,
    queue: Queue,
    weights: Weights,
    max_distance: f32,
    min_cos: f32,
    max_growth: f32,
    min_density: f32,
    max_overhang: f32,
    axis: Axis,
    inv_crown: f32,
}

impl Simplifier {
    fn new(leaves: &[Leaf], selection: &Selection) -> Simplifier {
        let axis = selection.axis.unwrap_or_else(|| {
            let (lo, hi) = leaves.iter().fold(
                (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
                |(lo, hi), l| (lo.min(l.center), hi.max(l.center)),
            );
            let mid = (lo + hi) * 0.5;
            Axis {
                origin: Vec3::new(mid.x, lo.y, mid.z),
                direction: Vec3::Y,
            }
        });
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
            refused_by: Vec::with_capacity(capacity),
            candidates: Vec::with_capacity(capacity * CANDIDATES),
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
        s.refused_by.resize(leaves.len(), EMPTY);
        s.candidates.resize(leaves.len() * CANDIDATES, 0);
        s.searches.resize(leaves.len(), Search::FRESH);
        s.rebuild_grid();
        s
    }

    /// Pops the cheapest candidate pair until none is left. A pair with a dead partner moves
    /// its leaf on to its next candidate; a living pair is collapsed if the new leaf keeps
    /// the bounds, otherwise its leaf moves on too. A leaf whose list is used up searches
    /// again, for partners it has not consumed yet.
    fn run(&mut self) {
        // The first searches go cell by cell, so neighbouring searches share the cells they
        // read (the queue pops by key alone, so the order of pushes does not matter).
        let order: Vec<u32> = self.grid.traits.iter().map(|t| t.label).collect();
        for i in order {
            if i != EMPTY {
                self.search(i, false);
            }
        }
        while let Some((key, a)) = self.queue.pop() {
            if !self.alive[a as usize] {
                continue;
            }
            let b = key as u32;
            let dead = !self.alive[b as usize];
            if !dead && self.refused_by[a as usize] != b {
                let new = Leaf::collapse(&self.leaves[a as usize], &self.leaves[b as usize]);
                if self.allowed(a, b, &new) {
                    self.collapse(a, b, new);
                    continue;
                }
                self.refused_by[b as usize] = a;
            }
            self.advance(a, key, dead);
        }
    }

    /// Joins `a` and `b` into `new`, which searches for its own partners.
    fn collapse(&mut self, a: u32, b: u32, new: Leaf) {
        let label = self.leaves.len() as u32;
        for old in [a, b] {
            self.alive[old as usize] = false;
            self.grid.remove(old, self.leaves[old as usize].center);
        }
        // The thesis' figure 2.3 keeps the lower label on the left.
        self.children.push([a.min(b), a.max(b)]);
        self.leaves.push(new);
        self.alive.push(true);
        self.refused_by.push(EMPTY);
        self.candidates.extend_from_slice(&[0; CANDIDATES]);
        self.searches.push(Search::FRESH);
        self.alive_count -= 1;
        if self.alive_count * 2 <= self.built_with {
            self.rebuild_grid();
        } else if !self.grid.insert(label, &new) {
            // The new leaf's cell is full: the same cells laid out again, with new room.
            self.collect_living();
            self.grid.fill(&self.leaves, &self.living);
        }
        self.search(label, false);
    }

    /// `a`'s candidate `consumed` is `dead` or refused: queue its next living candidate, or
    /// search again when the list is used up and one of its candidates had died.
    fn advance(&mut self, a: u32, consumed: u64, dead: bool) {
        let s = &mut self.searches[a as usize];
        s.floor = s.floor.max(consumed);
        s.died |= dead;
        let base = a as usize * CANDIDATES;
        while s.next < s.len {
            let key = self.candidates[base + s.next as usize];
            s.next += 1;
            let b = key as u32;
            if !self.alive[b as usize] {
                s.floor = s.floor.max(key);
                s.died = true;
            } else if self.refused_by[a as usize] == b {
                // Refused from `b`'s side already: consumed without queueing it.
                s.floor = s.floor.max(key);
            } else {
                self.queue.push((key, a));
                return;
            }
        }
        // A list whose every candidate was refused by the bounds looks farther only
        // `RETRIES` times, then retires its leaf; new leaves near it still find it.
        if s.died || s.refused < RETRIES {
            s.refused += u8::from(!s.died);
            self.search(a, true);
        }
    }

    /// Fills `a`'s candidate list with its `CANDIDATES` nearest partners allowed by the
    /// distance and angle bounds, cheapest first, and queues the first. The grid is searched
    /// in rings of cells around `a` until the ring is farther than the farthest of them, or
    /// than the distance bound to a partner as large as `a`. A repeated search (`again`)
    /// skips the partners consumed before (keys up to the floor) unless they were made after
    /// the last search.
    fn search(&mut self, a: u32, again: bool) {
        let me = Traits::of(a, &self.leaves[a as usize]);
        let (floor, seen_below) = {
            let s = &self.searches[a as usize];
            (s.floor, s.seen_below)
        };
        let centre_of_me = me.center;
        // The distance bound to partners no larger than `a`: larger ones find `a` in their
        // own searches.
        let reach = self.max_distance * 2.0 * me.radius;
        // The nearest allowed partners: (distance squared, key), by distance.
        let mut near = [(f32::MAX, u64::MAX); CANDIDATES];
        let mut len = 0usize;
        let centre = self.grid.coords(centre_of_me);
        let grid = &self.grid;
        let mut ring = 0i32;
        loop {
            grid.ring(centre, ring, |slots| {
                // Only the centre and radius are read for the distance test (16 bytes a
                // slot, contiguous); the rest only for the pairs within the bound.
                for (i, sphere) in slots.clone().zip(&grid.spheres[slots]) {
                    let d2 = centre_of_me.distance_squared(sphere.truncate());
                    let limit = self.max_distance * (me.radius + sphere.w);
                    if d2 > limit * limit || (len == CANDIDATES && d2 >= near[CANDIDATES - 1].0) {
                        continue;
                    }
                    let other = &grid.traits[i];
                    if other.label == a {
                        continue;
                    }
                    let Some(cost) = self.cost(&me, other) else {
                        continue;
                    };
                    let k = key(cost, other.label);
                    if again && k <= floor && other.label < seen_below {
                        continue;
                    }
                    // Insertion into the sorted, bounded list.
                    let mut i = len.min(CANDIDATES - 1);
                    while i > 0 && near[i - 1].0 > d2 {
                        near[i] = near[i - 1];
                        i -= 1;
                    }
                    near[i] = (d2, k);
                    len = (len + 1).min(CANDIDATES);
                }
            });
            // Every point of the rings beyond is at least `ring` cells away.
            let beyond = ring as f32 * grid.cell;
            if (len == CANDIDATES && beyond * beyond >= near[len - 1].0)
                || beyond >= reach
                || !grid.has_ring(centre, ring + 1)
            {
                break;
            }
            ring += 1;
        }
        let mut best = near.map(|(_, k)| k);
        best[..len].sort_unstable();
        let base = a as usize * CANDIDATES;
        self.candidates[base..base + CANDIDATES].copy_from_slice(&best);
        let s = &mut self.searches[a as usize];
        s.died = false;
        s.len = len as u8;
        s.next = u8::from(len > 0);
        s.seen_below = self.leaves.len() as u32;
        if len > 0 {
            self.queue.push((best[0], a));
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

    /// The weighted distance of seed 003 §2.4.1 between two leaves within the distance
    /// bound, or `None` when the angle bound forbids the pair.
    fn cost(&self, a: &Traits, b: &Traits) -> Option<f32> {
        let cos = a.normal.dot(b.normal).abs();
        if cos < self.min_cos {
            return None;
        }
        let d = a.center.distance(b.center) / (a.radius + b.radius);
        let w = &self.weights;
        let (na, nb) = (a.count, b.count);
        let (aa, ab) = (a.area, b.area);
        let mid = (a.center + b.center) * 0.5;
        let cost = w.distance * d
            + w.coplanarity * (1.0 - cos.min(1.0))
            + w.count * (na - nb).abs() / (na + nb)
            + w.area * (aa - ab).abs() / (aa + ab)
            + w.interiority * self.axis.distance(mid) * self.inv_crown;
        (cost.is_finite() && cost >= 0.0).then_some(cost)
    }
}

/// A 4-ary min-heap of (candidate key, leaf): half the levels of a binary heap, and a
/// node's four children lie side by side. Pops in the order of the pairs, so ties between
/// equal keys go to the lower leaf.
struct Queue {
    items: Vec<(u64, u32)>,
}

impl Queue {
    fn with_capacity(capacity: usize) -> Queue {
        Queue {
            items: Vec::with_capacity(capacity),
        }
    }

    fn push(&mut self, item: (u64, u32)) {
        let mut i = self.items.len();
        self.items.push(item);
        while i > 0 {
            let parent = (i - 1) / 4;
            if self.items[parent] <= item {
                break;
            }
            self.items[i] = self.items[parent];
            i = parent;
        }
        self.items[i] = item;
    }

    fn pop(&mut self) -> Option<(u64, u32)> {
        let last = self.items.pop()?;
        let Some(&top) = self.items.first() else {
            return Some(last);
        };
        // Sift `last` down from the root.
        let n = self.items.len();
        let mut i = 0;
        loop {
            let first = 4 * i + 1;
            if first >= n {
                break;
            }
            let end = (first + 4).min(n);
            let mut child = first;
            for c in first + 1..end {
                if self.items[c] < self.items[child] {
                    child = c;
                }
            }
            if self.items[child] >= last {
                break;
            }
            self.items[i] = self.items[child];
            i = child;
        }
        self.items[i] = last;
        Some(top)
    }
}

/// The label of a grid slot with no leaf.
const EMPTY: u32 = u32::MAX;

/// What the cost of a pair reads of a leaf (the grid keeps a copy in its cell, so a search
/// reads no leaf).
#[derive(Clone, Copy)]
struct Traits {
    center: Vec3,
    radius: f32,
    normal: Vec3,
    /// Original leaves represented.
    count: f32,
    area: f32,
    label: u32,
}

impl Traits {
    const NONE: Traits = Traits {
        center: Vec3::ZERO,
        radius: 0.0,
        normal: Vec3::ZERO,
        count: 0.0,
        area: 0.0,
        label: EMPTY,
    };

    fn of(label: u32, leaf: &Leaf) -> Traits {
        Traits {
            center: leaf.center,
            radius: leaf.radius(),
            normal: leaf.normal,
            count: leaf.count as f32,
            area: leaf.area(),
            label,
        }
    }
}

/// A cell of the grid: its slots are `start .. start + len` of the grid's arrays, with room
/// up to the next cell's start.
#[derive(Clone, Copy, Default)]
struct Cell {
    start: u32,
    len: u32,
}

/// A dense uniform grid of living leaves over the box of their centres; points outside the
/// box (new leaves may stray a little) go to the nearest border cell. The slots of all cells
/// lie in two arrays, cell after cell (x fastest, so a row of cells is one run of memory):
/// `spheres` holds each leaf's centre and radius, all the distance test reads, and `traits`
/// the rest the cost needs. Each cell keeps room for half as many leaves again as it was
/// laid out with, for the new leaves of collapses.
#[derive(Default)]
struct Grid {
    origin: Vec3,
    cell: f32,
    inv_cell: f32,
    dims: [i32; 3],
    /// One per cell, and one past the last that marks the end of the slots.
    cells: Vec<Cell>,
    spheres: Vec<Vec4>,
    traits: Vec<Traits>,
    /// Scratch: the cell of each leaf being laid out.
    cell_of: Vec<u32>,
}

impl Grid {
    /// Sets the grid's box and cell size, with at most one cell per leaf: a wider cell than
    /// asked when the box is large. The cells are laid out by [`Grid::fill`].
    fn shape(&mut self, lo: Vec3, hi: Vec3, cell: f32, leaves: usize) {
        let extent = (hi - lo).max(Vec3::ZERO);
        let most = leaves.max(1) as f32;
        let mut cell = if cell > 0.0 && cell.is_finite() {
            cell
        } else {
            extent.max_element().max(1.0)
        };
        let count = |cell: f32| {
            let n = (extent / cell).floor() + Vec3::ONE;
            n.x * n.y * n.z
        };
        let cells = count(cell);
        if cells > most {
            cell *= (cells / most).cbrt().max(1.0) * 1.01;
            while count(cell) > most {
                cell *= 1.26;
            }
        }
        let n = (extent / cell).floor() + Vec3::ONE;
        // `as` saturates and maps NaN to 0 (coordinates near f32::MAX): at least one cell.
        self.dims = [n.x, n.y, n.z].map(|v| (v as i32).max(1));
        self.origin = lo;
        self.cell = cell;
        self.inv_cell = 1.0 / cell;
    }

    /// Number of cells.
    fn cell_count(&self) -> usize {
        self.dims.iter().map(|&d| d as usize).product()
    }

    /// Counts the leaves `labels` of each cell into `cells` (zeroed first); the cell of each
    /// into `cell_of`.
    fn count(&mut self, leaves: &[Leaf], labels: &[u32]) {
        self.cells.clear();
        self.cells.resize(self.cell_count() + 1, Cell::default());
        self.cell_of.clear();
        for &l in labels {
            let c = self.index(self.coords(leaves[l as usize].center));
            self.cells[c].len += 1;
            self.cell_of.push(c as u32);
        }
    }

    /// How many cells the leaves `labels` occupy.
    fn occupied(&mut self, leaves: &[Leaf], labels: &[u32]) -> usize {
        self.count(leaves, labels);
        self.cells.iter().filter(|c| c.len > 0).count()
    }

    /// Lays out the leaves `labels` cell by cell, in the order given within each cell.
    fn fill(&mut self, leaves: &[Leaf], labels: &[u32]) {
        self.count(leaves, labels);
        let mut start = 0u32;
        for cell in &mut self.cells {
            let len = cell.len;
            *cell = Cell { start, len: 0 };
            start += len + len / 2 + 1;
        }
        let slots = start as usize;
        self.spheres.clear();
        self.spheres.resize(slots, Vec4::ZERO);
        self.traits.clear();
        self.traits.resize(slots, Traits::NONE);
        for (k, &l) in labels.iter().enumerate() {
            let cell = &mut self.cells[self.cell_of[k] as usize];
            let slot = (cell.start + cell.len) as usize;
            cell.len += 1;
            self.put(slot, Traits::of(l, &leaves[l as usize]));
        }
    }

    fn put(&mut self, slot: usize, traits: Traits) {
        self.spheres[slot] = traits.center.extend(traits.radius);
        self.traits[slot] = traits;
    }

    /// The cell coordinates of `p`, clamped to the grid.
    fn coords(&self, p: Vec3) -> [i32; 3] {
        let q = ((p - self.origin) * self.inv_cell).floor();
        let clamp = |v: f32, n: i32| {
            // `as` saturates and maps NaN to 0.
            (v as i32).clamp(0, n - 1)
        };
        [
            clamp(q.x, self.dims[0]),
            clamp(q.y, self.dims[1]),
            clamp(q.z, self.dims[2]),
        ]
    }

    fn index(&self, c: [i32; 3]) -> usize {
        ((c[2] * self.dims[1] + c[1]) * self.dims[0] + c[0]) as usize
    }

    /// Adds the leaf `label` to its cell; `false` when the cell has no room left.
    fn insert(&mut self, label: u32, leaf: &Leaf) -> bool {
        let i = self.index(self.coords(leaf.center));
        let (cell, end) = (self.cells[i], self.cells[i + 1].start);
        if cell.start + cell.len >= end {
            return false;
        }
        self.cells[i].len += 1;
        self.put((cell.start + cell.len) as usize, Traits::of(label, leaf));
        true
    }

    /// Removes the leaf `label` at `p` from its cell (the cell's last leaf takes its slot).
    fn remove(&mut self, label: u32, p: Vec3) {
        let i = self.index(self.coords(p));
        let Cell { start, len } = self.cells[i];
        let (start, end) = (start as usize, (start + len) as usize);
        if let Some(k) = self.traits[start..end]
            .iter()
            .position(|t| t.label == label)
        {
            let last = end - 1;
            self.spheres[start + k] = self.spheres[last];
            self.traits[start + k] = self.traits[last];
            self.traits[last] = Traits::NONE;
            self.cells[i].len -= 1;
        }
    }

    /// Whether any cell lies `ring` cells away from `c` (Chebyshev distance).
    fn has_ring(&self, c: [i32; 3], ring: i32) -> bool {
        (0..3).any(|k| c[k] - ring >= 0 || c[k] + ring < self.dims[k])
    }

    /// Calls `visit` on the slots of the cells exactly `ring` cells away from `c` (Chebyshev
    /// distance) within the grid: once per run of cells adjacent in memory.
    fn ring(&self, c: [i32; 3], ring: i32, mut visit: impl FnMut(Range<usize>)) {
        let lo = [0, 1, 2].map(|k| (c[k] - ring).max(0));
        let hi = [0, 1, 2].map(|k| (c[k] + ring).min(self.dims[k] - 1));
        let mut run = |x0: i32, x1: i32, y: i32, z: i32| {
            let (first, last) = (self.index([x0, y, z]), self.index([x1, y, z]));
            for cell in &self.cells[first..=last] {
                if cell.len > 0 {
                    visit(cell.start as usize..(cell.start + cell.len) as usize);
                }
            }
        };
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                if ring == 0 || (z - c[2]).abs() == ring || (y - c[1]).abs() == ring {
                    run(lo[0], hi[0], y, z);
                } else {
                    // Off the ring's faces in y and z only the two x ends are on it.
                    for x in [c[0] - ring, c[0] + ring] {
                        if x >= 0 && x < self.dims[0] {
                            run(x, x, y, z);
                        }
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn leaf(center: Vec3, normal: Vec3) -> Leaf {
        Leaf {
            center,
            normal,
            axis: normal.any_orthonormal_vector(),
            half_length: 0.5,
            half_width: 0.5,
            count: 1,
            leaf_area: 1.0,
            lo: center - Vec3::splat(0.75),
            hi: center + Vec3::splat(0.75),
        }
    }

    #[test]
    fn the_closest_pair_collapses_first_and_far_pairs_never() {
        let leaves = [
            leaf(Vec3::new(0.0, 0.0, 0.0), Vec3::Z),
            leaf(Vec3::new(10.0, 0.0, 0.0), Vec3::Z),
            leaf(Vec3::new(0.5, 0.0, 0.0), Vec3::Z),
            leaf(Vec3::new(100.0, 0.0, 0.0), Vec3::Z),
        ];
        let chain = simplify(&leaves, &Selection::default());
        assert_eq!(chain.children[0], [0, 2]);
        // Leaf 1 is 10 m away (bound: 2 x the radii), leaf 3 further: both stay roots.
        assert_eq!(chain.children.len(), 1);
        assert_eq!(chain.roots(), vec![1, 3, 4]);
        assert_eq!(chain.parents()[0], Some(4));
    }

    #[test]
    fn perpendicular_leaves_do_not_collapse() {
        let leaves = [
            leaf(Vec3::ZERO, Vec3::Z),
            leaf(Vec3::new(0.5, 0.0, 0.0), Vec3::X),
        ];
        let chain = simplify(&leaves, &Selection::default());
        assert!(chain.children.is_empty());
        let loose = Selection {
            bounds: Bounds {
                max_angle: 90.0,
                ..Bounds::default()
            },
            ..Selection::default()
        };
        assert_eq!(simplify(&leaves, &loose).children.len(), 1);
    }

    #[test]
    fn a_row_of_leaves_collapses_into_one_balanced_tree() {
        let leaves: Vec<Leaf> = (0..16)
            .map(|i| leaf(Vec3::new(i as f32 * 0.9, 0.0, 0.0), Vec3::Z))
            .collect();
        let chain = simplify(&leaves, &Selection::default());
        assert_eq!(chain.children.len(), 15);
        assert_eq!(chain.roots(), vec![30]);
        let root = chain.leaves[30];
        assert_eq!(root.count, 16);
        // Every leaf is represented exactly once below the root.
        let mut seen = [0; 16];
        let mut stack = vec![30u32];
        while let Some(n) = stack.pop() {
            if (n as usize) < 16 {
                seen[n as usize] += 1;
            } else {
                stack.extend(chain.children[n as usize - 16]);
            }
        }
        assert!(seen.iter().all(|&c| c == 1));
    }

    #[test]
    fn simplification_is_deterministic() {
        let leaves: Vec<Leaf> = (0..200)
            .map(|i| {
                let t = i as f32 * 0.37;
                leaf(
                    Vec3::new(t.sin() * 3.0, (i % 17) as f32 * 0.3, t.cos() * 3.0),
                    Vec3::new(t.cos(), 0.3, t.sin()).normalize(),
                )
            })
            .collect();
        let a = simplify(&leaves, &Selection::default());
        let b = simplify(&leaves, &Selection::default());
        assert_eq!(a, b);
        assert!(a.children.len() > 100, "{}", a.children.len());
    }

    #[test]
    fn the_queue_pops_in_increasing_order() {
        let mut queue = Queue::with_capacity(4);
        let mut items: Vec<(u64, u32)> = (0..500u32)
            .map(|i| (u64::from(i.wrapping_mul(2_654_435_761) % 97), i % 13))
            .collect();
        for &item in &items {
            queue.push(item);
        }
        items.sort_unstable();
        let popped: Vec<(u64, u32)> = std::iter::from_fn(|| queue.pop()).collect();
        assert_eq!(popped, items);
    }

    #[test]
    fn a_full_cell_refuses_a_leaf_until_laid_out_again() {
        let leaves: Vec<Leaf> = (0..6)
            .map(|i| leaf(Vec3::new(i as f32 * 0.01, 0.0, 0.0), Vec3::Z))
            .collect();
        let labels: Vec<u32> = (0..6).collect();
        let mut grid = Grid::default();
        grid.shape(Vec3::ZERO, Vec3::splat(0.05), 1.0, leaves.len());
        grid.fill(&leaves, &labels[..4]);
        // Four leaves leave room for 4 / 2 + 1 more in their one cell.
        assert!(grid.insert(4, &leaves[4]));
        assert!(grid.insert(5, &leaves[5]));
        assert!(grid.insert(5, &leaves[5]));
        assert!(!grid.insert(5, &leaves[5]));
        grid.remove(2, leaves[2].center);
        assert!(grid.insert(2, &leaves[2]));
        grid.fill(&leaves, &labels);
        let mut seen = Vec::new();
        grid.ring([0, 0, 0], 0, |slots| {
            seen.extend(grid.traits[slots].iter().map(|t| t.label));
        });
        assert_eq!(seen, labels);
    }
}
