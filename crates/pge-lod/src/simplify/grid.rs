//! The dense uniform grid of living leaves that the searches read.

use pge_engine::math;
use std::ops::Range;

use glam::Vec3;

use crate::leaf::Leaf;

/// The label of a grid slot with no leaf.
pub(super) const EMPTY: u32 = u32::MAX;

/// A grid slot: a copy of a living leaf, with what the search reads of it besides (a search
/// and the tests of its pairs read no leaf outside the grid).
#[derive(Clone, Copy)]
pub(super) struct Traits {
    pub(super) leaf: Leaf,
    pub(super) radius: f32,
    pub(super) label: u32,
}

impl Traits {
    pub(super) const NONE: Traits = Traits {
        leaf: Leaf {
            center: Vec3::ZERO,
            normal: Vec3::ZERO,
            axis: Vec3::ZERO,
            half_length: 0.0,
            half_width: 0.0,
            count: 0,
            leaf_area: 0.0,
            lo: Vec3::ZERO,
            hi: Vec3::ZERO,
        },
        radius: 0.0,
        label: EMPTY,
    };

    pub(super) fn of(label: u32, leaf: &Leaf) -> Traits {
        Traits {
            leaf: *leaf,
            radius: leaf.radius(),
            label,
        }
    }
}

/// What the distance test reads of a slot's leaf, in an array of its own: most slots a
/// search reads fail the test, and four of these share a cache line.
#[derive(Clone, Copy)]
pub(super) struct Sphere {
    pub(super) center: Vec3,
    pub(super) radius: f32,
}

impl Sphere {
    const NONE: Sphere = Sphere {
        center: Vec3::ZERO,
        radius: 0.0,
    };
}

/// A cell of the grid: its slots are `start .. start + len` of the grid's arrays, the leaves
/// made before the round's first fresh label (see [`Grid::fill`]) the first `old` of them.
#[derive(Clone, Copy, Default)]
pub(super) struct Cell {
    pub(super) start: u32,
    pub(super) len: u32,
    pub(super) old: u32,
    /// The largest radius of its leaves, for the searches to skip a cell whose every leaf
    /// is beyond the distance bound.
    pub(super) radius: f32,
}

impl Cell {
    /// Its slots.
    pub(super) fn slots(&self) -> Range<usize> {
        self.start as usize..(self.start + self.len) as usize
    }
}

/// A dense uniform grid of living leaves over the box of their centres; points outside the
/// box go to the nearest border cell. The slots of all cells lie cell after cell (x
/// fastest, so a row of cells is one run of memory) in two arrays: the spheres that the
/// distance test reads, and beside them a copy of each leaf for the cost and the area
/// bounds of the pairs that pass it.
#[derive(Default)]
pub(super) struct Grid {
    pub(super) origin: Vec3,
    pub(super) cell: f32,
    pub(super) inv_cell: f32,
    /// How much [`Grid::gap`] and [`Grid::beyond`] take off their distances, so that
    /// rounding never makes them more than the distance of a point they bound.
    pub(super) slack: f32,
    pub(super) dims: [i32; 3],
    /// At least the largest radius of a leaf in the grid.
    pub(super) radius: f32,
    /// One per cell, and one past the last that marks the end of the slots.
    pub(super) cells: Vec<Cell>,
    pub(super) spheres: Vec<Sphere>,
    pub(super) traits: Vec<Traits>,
    /// Scratch: the cell of each leaf being laid out.
    pub(super) cell_of: Vec<u32>,
}

impl Grid {
    /// Sets the grid's box and cell size, with at most one cell per leaf: a wider cell than
    /// asked when the box is large. The cells are laid out by [`Grid::fill`].
    pub(super) fn shape(&mut self, lo: Vec3, hi: Vec3, cell: f32, leaves: usize) {
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
            cell *= math::cbrt(cells / most).max(1.0) * 1.01;
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
        // Rounding in `coords` and `gap` is a few units in the last place of the coordinates
        // and of the cell indices: a thousandth of a cell is far more in any grid.
        let scale = lo.abs().max(hi.abs()).max_element();
        let most_cells = self.dims.iter().copied().max().unwrap_or(1) as f32;
        self.slack = cell * (1e-3 + 1e-6 * most_cells) + 8.0 * f32::EPSILON * scale;
    }

    /// Number of cells.
    pub(super) fn cell_count(&self) -> usize {
        self.dims.iter().map(|&d| d as usize).product()
    }

    /// Counts the leaves `labels` of each cell into `cells` (zeroed first) and the cell of
    /// each into `cell_of`; returns how many cells they occupy.
    pub(super) fn count(&mut self, leaves: &[Leaf], labels: &[u32]) -> usize {
        self.cells.clear();
        self.cells.resize(self.cell_count() + 1, Cell::default());
        self.cell_of.clear();
        let mut occupied = 0;
        for &l in labels {
            let c = self.index(self.coords(leaves[l as usize].center));
            occupied += usize::from(self.cells[c].len == 0);
            self.cells[c].len += 1;
            self.cell_of.push(c as u32);
        }
        occupied
    }

    /// Lays out the leaves `labels`, just counted by [`Grid::count`] in the grid's shape,
    /// cell by cell, in the order given within each cell, and counts in each cell the leaves
    /// labelled below `fresh` (with `labels` increasing, they are its first slots).
    pub(super) fn fill(&mut self, leaves: &[Leaf], labels: &[u32], fresh: u32) {
        let mut start = 0u32;
        for cell in &mut self.cells {
            let len = cell.len;
            *cell = Cell {
                start,
                len: 0,
                old: 0,
                radius: 0.0,
            };
            start += len;
        }
        let slots = start as usize;
        self.spheres.clear();
        self.spheres.resize(slots, Sphere::NONE);
        self.traits.clear();
        self.traits.resize(slots, Traits::NONE);
        self.radius = 0.0;
        for (k, &l) in labels.iter().enumerate() {
            let cell = &mut self.cells[self.cell_of[k] as usize];
            let slot = (cell.start + cell.len) as usize;
            let traits = Traits::of(l, &leaves[l as usize]);
            cell.len += 1;
            cell.old += u32::from(l < fresh);
            cell.radius = cell.radius.max(traits.radius);
            self.radius = self.radius.max(traits.radius);
            self.put(slot, traits);
        }
    }

    fn put(&mut self, slot: usize, traits: Traits) {
        self.spheres[slot] = Sphere {
            center: traits.leaf.center,
            radius: traits.radius,
        };
        self.traits[slot] = traits;
    }

    /// The cell coordinates of `p`, clamped to the grid.
    pub(super) fn coords(&self, p: Vec3) -> [i32; 3] {
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

    pub(super) fn index(&self, c: [i32; 3]) -> usize {
        ((c[2] * self.dims[1] + c[1]) * self.dims[0] + c[0]) as usize
    }

    /// Whether any cell lies `ring` cells away from `c` (Chebyshev distance).
    pub(super) fn has_ring(&self, c: [i32; 3], ring: i32) -> bool {
        (0..3).any(|k| c[k] - ring >= 0 || c[k] + ring < self.dims[k])
    }

    /// How far `p` is, at least, from the points the cell at `i` along axis `k` holds: 0
    /// inside it, and the border cells reach to infinity (they hold the points beyond the
    /// box). Less the grid's slack, so that rounding in [`Grid::coords`] never makes it
    /// more than the distance of a point of the cell.
    fn gap(&self, k: usize, i: i32, p: f32) -> f32 {
        let lo = if i == 0 {
            f32::NEG_INFINITY
        } else {
            self.origin[k] + i as f32 * self.cell
        };
        let hi = if i == self.dims[k] - 1 {
            f32::INFINITY
        } else {
            self.origin[k] + (i + 1) as f32 * self.cell
        };
        ((lo - p).max(p - hi) - self.slack).max(0.0)
    }

    /// How far `p`, whose cell is `c`, is at least from every point of the cells more than
    /// `ring` cells away from `c` (infinity when there are none): at least `ring` cells, and
    /// more when `p` is far from its cell's faces.
    pub(super) fn beyond(&self, c: [i32; 3], ring: i32, p: Vec3) -> f32 {
        (0..3)
            .map(|k| {
                let below = if c[k] - ring > 0 {
                    p[k] - (self.origin[k] + (c[k] - ring) as f32 * self.cell)
                } else {
                    f32::INFINITY
                };
                let above = if c[k] + ring + 1 < self.dims[k] {
                    self.origin[k] + (c[k] + ring + 1) as f32 * self.cell - p[k]
                } else {
                    f32::INFINITY
                };
                below.min(above)
            })
            .fold(f32::INFINITY, f32::min)
            .max(ring as f32 * self.cell)
            - self.slack
    }

    /// Calls `visit` on each non-empty cell exactly `ring` cells away from `c` (Chebyshev
    /// distance) within the grid, in memory order (x fastest), with its index and the least
    /// squared distance from `p` to a point it may hold.
    pub(super) fn ring(
        &self,
        c: [i32; 3],
        ring: i32,
        p: Vec3,
        mut visit: impl FnMut(usize, &Cell, f32),
    ) {
        let lo = [0, 1, 2].map(|k| (c[k] - ring).max(0));
        let hi = [0, 1, 2].map(|k| (c[k] + ring).min(self.dims[k] - 1));
        let mut run = |x0: i32, x1: i32, y: i32, z: i32, yz2: f32| {
            let (first, last) = (self.index([x0, y, z]), self.index([x1, y, z]));
            for (x, cell) in (x0..).zip(&self.cells[first..=last]) {
                if cell.len > 0 {
                    let dx = self.gap(0, x, p.x);
                    visit(first + (x - x0) as usize, cell, dx * dx + yz2);
                }
            }
        };
        for z in lo[2]..=hi[2] {
            let dz = self.gap(2, z, p.z);
            for y in lo[1]..=hi[1] {
                let dy = self.gap(1, y, p.y);
                let yz2 = dy * dy + dz * dz;
                if ring == 0 || (z - c[2]).abs() == ring || (y - c[1]).abs() == ring {
                    run(lo[0], hi[0], y, z, yz2);
                } else {
                    // Off the ring's faces in y and z only the two x ends are on it.
                    for x in [c[0] - ring, c[0] + ring] {
                        if x >= 0 && x < self.dims[0] {
                            run(x, x, y, z, yz2);
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

    fn leaf(center: Vec3) -> Leaf {
        Leaf {
            center,
            normal: Vec3::Z,
            axis: Vec3::X,
            half_length: 0.5,
            half_width: 0.5,
            count: 1,
            leaf_area: 1.0,
            lo: center - Vec3::splat(0.75),
            hi: center + Vec3::splat(0.75),
        }
    }

    #[test]
    fn leaves_are_laid_out_cell_by_cell_in_the_order_given() {
        let leaves: Vec<Leaf> = [0.1, 2.5, 0.2, 2.6, 0.3]
            .map(|x| leaf(Vec3::new(x, 0.0, 0.0)))
            .to_vec();
        let labels: Vec<u32> = (0..5).collect();
        let mut grid = Grid::default();
        grid.shape(Vec3::ZERO, Vec3::new(2.6, 0.0, 0.0), 1.0, leaves.len());
        grid.count(&leaves, &labels);
        grid.fill(&leaves, &labels, 3);
        let order: Vec<u32> = grid.traits.iter().map(|t| t.label).collect();
        assert_eq!(order, [0, 2, 4, 1, 3]);
        // The leaves labelled below 3 come first in each cell.
        let old: Vec<(u32, u32)> = grid.cells.iter().map(|c| (c.len, c.old)).collect();
        assert_eq!(old, [(3, 2), (0, 0), (2, 1), (0, 0)]);
        let spheres: Vec<Vec3> = grid.spheres.iter().map(|s| s.center).collect();
        let copies: Vec<Vec3> = grid.traits.iter().map(|t| t.leaf.center).collect();
        assert_eq!(spheres, copies);
        assert_eq!(grid.radius, leaves[0].radius());
    }

    #[test]
    fn cell_and_ring_bounds_never_exceed_a_leafs_distance() {
        let mut x = 7u64;
        let mut r = move || {
            x = x.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
            (x >> 40) as f32 / (1u64 << 24) as f32
        };
        // A box smaller than the leaves' spread: some leaves lie in the border cells from
        // beyond it, as new leaves may.
        let leaves: Vec<Leaf> = (0..400)
            .map(|_| leaf(Vec3::new(r() * 10.0 - 1.0, r() * 5.0, r() * 3.0 - 0.5)))
            .collect();
        let labels: Vec<u32> = (0..400).collect();
        let mut grid = Grid::default();
        grid.shape(Vec3::ZERO, Vec3::new(8.0, 4.0, 2.0), 0.7, leaves.len());
        grid.count(&leaves, &labels);
        grid.fill(&leaves, &labels, 0);
        let mut visited = 0;
        for probe in leaves.iter().step_by(7) {
            let p = probe.center;
            let c = grid.coords(p);
            for ring in 0..5 {
                grid.ring(c, ring, p, |_, cell, least| {
                    for t in &grid.traits[cell.slots()] {
                        assert!(
                            least <= p.distance_squared(t.leaf.center),
                            "{p} {}",
                            t.leaf.center
                        );
                        assert!(t.radius <= cell.radius);
                        visited += 1;
                    }
                });
                let beyond = grid.beyond(c, ring, p).max(0.0);
                for t in grid.traits.iter().filter(|t| t.label != EMPTY) {
                    let tc = grid.coords(t.leaf.center);
                    if (0..3).any(|k| (tc[k] - c[k]).abs() > ring) {
                        assert!(beyond * beyond <= p.distance_squared(t.leaf.center));
                    }
                }
            }
        }
        // Each probe at least saw its own leaf.
        assert!(visited >= 400 / 7);
    }
}
