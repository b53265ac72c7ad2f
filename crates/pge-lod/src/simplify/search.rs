//! A leaf's search for the pairs it may collapse into, in the grid, and the collapse
//! distance they are ranked by.

use std::ops::Range;

use super::driver::Simplifier;
use super::grid::Traits;

/// A pair's sort key: the cost's bits (non-negative floats order like their bits) above the
/// searching leaf's label.
pub(super) fn key(cost: f32, label: u32) -> u64 {
    (u64::from(cost.to_bits()) << 32) | u64::from(label)
}

impl Simplifier {
    /// Adds to the round's pairs, with their costs, those of the fresh leaf in grid slot `at`
    /// (labelled at least the round's `fresh`): its nearest partners within the distance and
    /// angle bounds (the round's matching tests the area bounds). A fresh partner in an earlier
    /// slot finds the pair itself, so it is not read: in the cells before its own (in memory
    /// order) only the old leaves are, which [`super::grid::Grid::fill`] puts first. The grid
    /// is searched in rings of cells around it until the ring is farther than the farthest of
    /// the nearest, or than the distance bound to the largest leaf.
    pub(super) fn search<const N: usize>(&mut self, at: usize) {
        let grid = &self.grid;
        let me = grid.traits[at];
        let a = me.label;
        let centre_of_me = me.leaf.center;
        let reach = self.max_distance * (me.radius + grid.radius);
        // The nearest partners within the angle bound: (distance squared, slot), by distance.
        let mut near = [(f32::MAX, 0usize); N];
        let mut len = 0usize;
        let centre = grid.coords(centre_of_me);
        let my_cell = grid.index(centre);
        let scan = |slots: Range<usize>, len: &mut usize, near: &mut [(f32, usize); N]| {
            for (slot, sphere) in slots.clone().zip(&grid.spheres[slots]) {
                let d2 = centre_of_me.distance_squared(sphere.center);
                let limit = self.max_distance * (me.radius + sphere.radius);
                if d2 > limit * limit || (*len == N && d2 >= near[N - 1].0) {
                    continue;
                }
                let other = &grid.traits[slot];
                if me.leaf.normal.dot(other.leaf.normal).abs() < self.min_cos {
                    continue;
                }
                // Insertion into the sorted, bounded list.
                let mut i = (*len).min(N - 1);
                while i > 0 && near[i - 1].0 > d2 {
                    near[i] = near[i - 1];
                    i -= 1;
                }
                near[i] = (d2, slot);
                *len = (*len + 1).min(N);
            }
        };
        let mut ring = 0i32;
        loop {
            // The slots to read, gathered into runs of adjacent slots (the cells of a row of
            // the ring, and the empty cells between them, are one run of memory).
            let mut pending = 0..0;
            grid.ring(centre, ring, centre_of_me, |index, cell, least| {
                // A cell whose every leaf is farther than the distance bound, or than the
                // farthest of a full list, would add nothing: not read at all.
                let limit = self.max_distance * (me.radius + cell.radius);
                if least > limit * limit || (len == N && least >= near[N - 1].0) {
                    return;
                }
                let slots = cell.slots();
                let mut read = |run: Range<usize>| {
                    if run.start == pending.end {
                        pending.end = run.end;
                    } else {
                        scan(std::mem::replace(&mut pending, run), &mut len, &mut near);
                    }
                };
                if index > my_cell {
                    read(slots);
                } else {
                    read(slots.start..slots.start + cell.old as usize);
                    if index == my_cell {
                        read(at + 1..slots.end);
                    }
                }
            });
            scan(pending, &mut len, &mut near);
            // Every point of the rings beyond is at least `ring` cells away, and farther
            // when `me` is far from its cell's faces.
            let beyond = ring as f32 * grid.cell;
            let least = grid.beyond(centre, ring, centre_of_me).max(0.0);
            let full = len == N;
            if (full && (beyond * beyond >= near[len - 1].0 || least * least >= near[len - 1].0))
                || beyond >= reach
                || !grid.has_ring(centre, ring + 1)
            {
                break;
            }
            ring += 1;
        }
        for &(_, slot) in &near[..len] {
            let other = &grid.traits[slot];
            if let Some(cost) = self.cost(&me, other) {
                self.pairs
                    .push((key(cost, a.min(other.label)), a, other.label));
            }
        }
    }

    /// The weighted distance of seed 003 §2.4.1 between two leaves within the distance
    /// bound, or `None` when the angle bound forbids the pair (the search tests it first).
    pub(super) fn cost(&self, a: &Traits, b: &Traits) -> Option<f32> {
        let (la, lb) = (&a.leaf, &b.leaf);
        let cos = la.normal.dot(lb.normal).abs();
        if cos < self.min_cos {
            return None;
        }
        let d = la.center.distance(lb.center) / (a.radius + b.radius);
        let w = &self.weights;
        let (na, nb) = (la.count as f32, lb.count as f32);
        let (aa, ab) = (la.area(), lb.area());
        let mid = (la.center + lb.center) * 0.5;
        let cost = w.distance * d
            + w.coplanarity * (1.0 - cos.min(1.0))
            + w.count * (na - nb).abs() / (na + nb)
            + w.area * (aa - ab).abs() / (aa + ab)
            + w.interiority * self.axis.distance(mid) * self.inv_crown;
        (cost.is_finite() && cost >= 0.0).then_some(cost)
    }
}
