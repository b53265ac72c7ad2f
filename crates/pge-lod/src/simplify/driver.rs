//! The simplifier's driver: the state kept per leaf label and the rounds of greedy matching
//! that collapse the allowed pairs, cheapest first.

use glam::Vec3;
use pge_engine::math;

use super::grid::Grid;
use super::{Axis, NEAREST, SWEEP, Selection, Weights};
use crate::leaf::Leaf;

/// One allowed pair found by a round's searches: its sort key (see [`super::search::key`])
/// and the two labels, the searching leaf first (the order [`Leaf::collapse`] takes them).
pub(super) type Pair = (u64, u32, u32);

/// One simplification under way: the leaves made so far, which live, the grid and the
/// pairs of the round.
pub(super) struct Simplifier {
    pub(super) leaves: Vec<Leaf>,
    pub(super) children: Vec<[u32; 2]>,
    pub(super) alive: Vec<bool>,
    pub(super) grid: Grid,
    /// Scratch list of the living labels, for laying out the grid.
    pub(super) living: Vec<u32>,
    pub(super) pairs: Vec<Pair>,
    /// Scratch for matching the pairs: the pairs in buckets by cost, and where each ends.
    scratch: Vec<Pair>,
    ends: Vec<u32>,
    pub(super) weights: Weights,
    pub(super) max_distance: f32,
    pub(super) min_cos: f32,
    pub(super) max_growth: f32,
    pub(super) min_density: f32,
    pub(super) max_overhang: f32,
    pub(super) axis: Axis,
    pub(super) inv_crown: f32,
    deadline: Option<pge_engine::clock::Instant>,
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
        let mut alive = Vec::with_capacity(capacity);
        alive.resize(leaves.len(), true);
        Simplifier {
            leaves: all,
            children: Vec::with_capacity(leaves.len()),
            alive,
            grid: Grid::default(),
            living: Vec::with_capacity(leaves.len()),
            pairs: Vec::new(),
            scratch: Vec::new(),
            ends: Vec::new(),
            weights: selection.weights,
            max_distance: selection.bounds.max_distance.max(0.0),
            max_growth: selection.bounds.max_growth,
            min_density: selection.bounds.min_density,
            max_overhang: selection.bounds.max_overhang,
            min_cos: math::cos(selection.bounds.max_angle.clamp(0.0, 90.0).to_radians()) - 1e-6,
            axis,
            inv_crown: if crown > 0.0 { 1.0 / crown } else { 0.0 },
            deadline: selection.deadline,
        }
    }

    /// Rounds of greedy matching. In each round the leaves made by the last one (at first,
    /// every leaf) find their pairs: their nearest partners within the distance and angle
    /// bounds. Then the pairs are taken cheapest first, and each whose leaves both live
    /// collapses if its new leaf keeps the area bounds. A pair a search found needs no second
    /// look: one of its leaves has gone since, or the round would have collapsed it, or the
    /// area bounds refused it. A round that makes nothing is followed by a sweep, searching
    /// again among more partners around every living leaf made since the last sweep began (the
    /// first: every leaf); a sweep that makes nothing ends the simplification. Pairs beyond
    /// each other's nearest partners in every search around them are never tested (a heuristic;
    /// see the module's docs).
    pub(super) fn run(&mut self) {
        let mut fresh = 0u32;
        let mut sweep = false;
        // The labels made before the last sweep began: it searched around each of them.
        let mut swept = 0u32;
        loop {
            if self.past_deadline() {
                return;
            }
            self.rebuild_grid(fresh);
            self.pairs.clear();
            // Cell by cell, so neighbouring searches share the cells they read; the fresh
            // leaves are the last slots of each cell.
            for c in 0..self.grid.cells.len() {
                if c % 4096 == 4095 && self.past_deadline() {
                    return;
                }
                let cell = self.grid.cells[c];
                for slot in (cell.start + cell.old) as usize..(cell.start + cell.len) as usize {
                    if sweep {
                        self.search::<SWEEP>(slot);
                    } else {
                        self.search::<NEAREST>(slot);
                    }
                }
            }
            fresh = self.leaves.len() as u32;
            self.match_pairs();
            let made = self.leaves.len() as u32 > fresh;
            if !made && sweep {
                break;
            }
            // Rounds that find nothing more end in a sweep: every leaf searches again, wider.
            sweep = !made;
            if sweep {
                fresh = swept;
                swept = self.leaves.len() as u32;
            }
        }
    }

    /// Whether the run's deadline has passed (the simplification then stops unfinished).
    fn past_deadline(&self) -> bool {
        self.deadline
            .is_some_and(|d| pge_engine::clock::Instant::now() >= d)
    }

    /// Collapses the round's pairs cheapest first, each whose leaves both live and whose new
    /// leaf keeps the area bounds. The pairs are put in buckets by cost, and each bucket in
    /// turn is rid of its pairs with a leaf gone, then sorted: the order is total, so the
    /// collapses are those of one sort of every pair, but most pairs are reached after one of
    /// their leaves has gone and are never sorted.
    fn match_pairs(&mut self) {
        let mut buckets = std::mem::take(&mut self.scratch);
        into_buckets(&self.pairs, &mut buckets, &mut self.ends);
        let mut start = 0;
        for k in 0..self.ends.len() {
            let end = self.ends[k] as usize;
            let bucket = &mut buckets[start..end];
            start = end;
            let mut kept = 0;
            for i in 0..bucket.len() {
                let (_, a, b) = bucket[i];
                if self.alive[a as usize] && self.alive[b as usize] {
                    bucket[kept] = bucket[i];
                    kept += 1;
                }
            }
            bucket[..kept].sort_unstable();
            for &(_, a, b) in &bucket[..kept] {
                // An earlier pair of the bucket may have taken one of them.
                if !(self.alive[a as usize] && self.alive[b as usize]) {
                    continue;
                }
                let (la, lb) = (&self.leaves[a as usize], &self.leaves[b as usize]);
                if let Some(new) = self.fits(la, lb) {
                    self.collapse(a, b, new);
                }
            }
        }
        self.scratch = buckets;
    }

    /// Replaces `a` and `b` by their new leaf `new` (built by [`Simplifier::fits`]).
    fn collapse(&mut self, a: u32, b: u32, new: Leaf) {
        self.alive[a as usize] = false;
        self.alive[b as usize] = false;
        // The thesis' figure 2.3 keeps the lower label on the left.
        self.children.push([a.min(b), a.max(b)]);
        self.leaves.push(new);
        self.alive.push(true);
    }

    /// The new leaf of `a` and `b` if they may collapse: it grows the pair's area by at most
    /// `max_growth`, its leaves cover at least `min_density` of it, and its corners stay
    /// within `max_overhang` of the box around the original leaves it stands for.
    pub(super) fn fits(&self, a: &Leaf, b: &Leaf) -> Option<Leaf> {
        if self.surely_overhangs(a, b) {
            return None;
        }
        self.keeps_bounds(a, b)
    }

    /// Whether the new leaf of `a` and `b` surely reaches past the box of its originals and
    /// its slack along some world axis, tested without building it ([`Leaf::surely_reaches`]):
    /// most pairs the overhang bound refuses, none that [`Simplifier::keeps_bounds`] accepts.
    /// Within the box and slack on both sides, a leaf's reach is at most half of them, plus
    /// what rounding in the full test lets through (a few units in the last place of the
    /// coordinates, far less than 1e-5 of them).
    pub(super) fn surely_overhangs(&self, a: &Leaf, b: &Leaf) -> bool {
        let (lo, hi) = (a.lo.min(b.lo), a.hi.max(b.hi));
        let allowed = (hi - lo) * (0.5 + self.max_overhang) + (lo.abs() + hi.abs()) * 1e-5;
        Leaf::surely_reaches(a, b, allowed)
    }

    /// The full test of [`Simplifier::fits`], on the new leaf itself: the leaf if it passes.
    pub(super) fn keeps_bounds(&self, a: &Leaf, b: &Leaf) -> Option<Leaf> {
        let new = Leaf::collapse(a, b);
        let area = new.area();
        let slack = (new.hi - new.lo) * self.max_overhang;
        // The corners' farthest reach along each world axis.
        let reach = (new.axis * new.half_length).abs() + (new.side() * new.half_width).abs();
        let keeps = area <= self.max_growth * (a.area() + b.area())
            && new.leaf_area >= self.min_density * area
            && (new.center - reach).cmpge(new.lo - slack).all()
            && (new.center + reach).cmple(new.hi + slack).all();
        keeps.then_some(new)
    }

    /// A grid of the living leaves with about three leaves per occupied cell, so that the
    /// nearest partners of a leaf are found in its cell and the next ring or two.
    fn rebuild_grid(&mut self, fresh: u32) {
        self.living.clear();
        let alive = self.alive.iter().enumerate().filter(|(_, a)| **a);
        self.living.extend(alive.map(|(i, _)| i as u32));
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
            let occupied = grid.count(&self.leaves, &self.living);
            let finer = grid.cell_count() * 8 <= living;
            if occupied * 3 >= living || !finer {
                break;
            }
            cell = grid.cell * 0.5;
        }
        grid.fill(&self.leaves, &self.living, fresh);
        self.grid = grid;
    }
}

/// Puts `pairs` into `buckets` by the high bits of their costs, a few hundred pairs to a
/// bucket on average: bucket `k` is `buckets[ends[k - 1]..ends[k]]` (from 0 for the first),
/// and every pair of a bucket is less than every pair of a later one.
fn into_buckets(pairs: &[Pair], buckets: &mut Vec<Pair>, ends: &mut Vec<u32>) {
    let count = (pairs.len() / 256).clamp(1, 4096);
    let cost = |p: &Pair| p.0 >> 32;
    let (lo, hi) = pairs.iter().fold((u64::MAX, 0), |(lo, hi), p| {
        (lo.min(cost(p)), hi.max(cost(p)))
    });
    let mut shift = 0;
    while hi > lo && (hi - lo) >> shift >= count as u64 {
        shift += 1;
    }
    let bucket = |p: &Pair| ((cost(p) - lo) >> shift) as usize;
    ends.clear();
    ends.resize(count, 0);
    for p in pairs {
        ends[bucket(p)] += 1;
    }
    // Where each bucket starts, moved to its end as it is filled.
    let mut start = 0;
    for e in ends.iter_mut() {
        (*e, start) = (start, start + *e);
    }
    buckets.clear();
    buckets.resize(pairs.len(), (0, 0, 0));
    for p in pairs {
        let e = &mut ends[bucket(p)];
        buckets[*e as usize] = *p;
        *e += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::simplify::search::key;

    #[test]
    fn buckets_of_pairs_sorted_one_by_one_sort_every_pair() {
        let mut x = 11u64;
        let mut r = move || {
            x = x.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
            (x >> 33) as u32
        };
        for n in [0, 1, 10, 600, 5000, 70_000] {
            // Few distinct costs and labels: many ties on the key and on the labels.
            let pairs: Vec<Pair> = (0..n)
                .map(|_| {
                    let cost = 0.5 + (r() % 300) as f32 * 0.01;
                    (key(cost, r() % 50), r() % 40, r() % 40)
                })
                .collect();
            let (mut buckets, mut ends) = (Vec::new(), Vec::new());
            into_buckets(&pairs, &mut buckets, &mut ends);
            assert_eq!(ends.last().map_or(0, |&e| e as usize), n);
            let mut start = 0;
            for &end in &ends {
                buckets[start..end as usize].sort_unstable();
                start = end as usize;
            }
            let mut expected = pairs.clone();
            expected.sort_unstable();
            assert_eq!(buckets, expected, "{n}");
        }
    }
}
