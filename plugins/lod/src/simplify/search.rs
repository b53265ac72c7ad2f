//! A leaf's search for partners in the grid, the collapse distance it ranks them by, and
//! the list of candidates it keeps between searches.

use super::driver::Simplifier;
use super::grid::{EMPTY, Traits};

/// How many candidate partners a leaf remembers between searches (its nearest by cost).
pub(super) const CANDIDATES: usize = 8;

/// How many times a leaf whose candidates were all refused looks farther.
pub(super) const RETRIES: u8 = 1;

/// A candidate's sort key: the cost's bits (non-negative floats order like their bits)
/// above the partner's label, so ties go to the lower label.
pub(super) fn key(cost: f32, label: u32) -> u64 {
    (u64::from(cost.to_bits()) << 32) | u64::from(label)
}

/// What the simplifier keeps per leaf label besides the leaf: its candidate list (the
/// `CANDIDATES` nearest partners of its last search allowed by the distance and angle
/// bounds, by key), how far it has been consumed, the largest key consumed, the first label
/// its last search did not see, and the last partner that refused it. All in one record
/// (the state first, then the list): a pop reads one place of memory, not three.
#[derive(Clone, Copy)]
#[repr(C)]
pub(super) struct Search {
    pub(super) floor: u64,
    pub(super) seen_below: u32,
    /// The last partner whose pair with this leaf was refused by the area bounds (`EMPTY`:
    /// none). Refusal is symmetric and final while both leaves live, so the partner's own
    /// attempt at the pair is skipped instead of building the new leaf again.
    pub(super) refused_by: u32,
    pub(super) len: u8,
    pub(super) next: u8,
    /// Whether a candidate of the list was found dead (the search is worth repeating).
    pub(super) died: bool,
    /// Searches repeated although every candidate had been refused.
    pub(super) refused: u8,
    pub(super) list: [u64; CANDIDATES],
}

impl Search {
    pub(super) const FRESH: Search = Search {
        floor: 0,
        seen_below: 0,
        refused_by: EMPTY,
        len: 0,
        next: 0,
        died: false,
        refused: 0,
        list: [0; CANDIDATES],
    };
}

impl Simplifier {
    /// Fills `a`'s candidate list with its `CANDIDATES` nearest partners allowed by the
    /// distance and angle bounds, cheapest first, and returns the first (to queue). The grid
    /// is searched
    /// in rings of cells around `a` until the ring is farther than the farthest of them, or
    /// than the distance bound to a partner as large as `a`. A repeated search (`again`)
    /// skips the partners consumed before (keys up to the floor) unless they were made after
    /// the last search.
    pub(super) fn search(&mut self, a: u32, again: bool) -> Option<(u64, u32)> {
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
            grid.ring(centre, ring, centre_of_me, |slots, radius, least| {
                // A cell whose every leaf is farther than the distance bound, or than the
                // farthest of a full list, would add nothing: not read at all.
                let limit = self.max_distance * (me.radius + radius);
                if least > limit * limit || (len == CANDIDATES && least >= near[CANDIDATES - 1].0) {
                    return;
                }
                // The cost only for the pairs within the bound.
                for other in &grid.traits[slots] {
                    let d2 = centre_of_me.distance_squared(other.center);
                    let limit = self.max_distance * (me.radius + other.radius);
                    if d2 > limit * limit || (len == CANDIDATES && d2 >= near[CANDIDATES - 1].0) {
                        continue;
                    }
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
            // Every point of the rings beyond is at least `ring` cells away, and farther
            // when `a` is far from its cell's faces.
            let beyond = ring as f32 * grid.cell;
            let least = grid.beyond(centre, ring, centre_of_me).max(0.0);
            let full = len == CANDIDATES;
            if (full && (beyond * beyond >= near[len - 1].0 || least * least >= near[len - 1].0))
                || beyond >= reach
                || !grid.has_ring(centre, ring + 1)
            {
                break;
            }
            ring += 1;
        }
        let mut best = near.map(|(_, k)| k);
        best[..len].sort_unstable();
        let s = &mut self.searches[a as usize];
        s.list = best;
        s.died = false;
        s.len = len as u8;
        s.next = u8::from(len > 0);
        s.seen_below = self.leaves.len() as u32;
        (len > 0).then_some((best[0], a))
    }

    /// The weighted distance of seed 003 §2.4.1 between two leaves within the distance
    /// bound, or `None` when the angle bound forbids the pair.
    pub(super) fn cost(&self, a: &Traits, b: &Traits) -> Option<f32> {
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
