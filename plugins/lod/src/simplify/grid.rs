//! The dense uniform grid of living leaves that the searches read.

use std::ops::Range;

use glam::{Vec3, Vec4};

use crate::leaf::Leaf;

/// The label of a grid slot with no leaf.
pub(super) const EMPTY: u32 = u32::MAX;

/// What the cost of a pair reads of a leaf (the grid keeps a copy in its cell, so a search
/// reads no leaf).
#[derive(Clone, Copy)]
pub(super) struct Traits {
    pub(super) center: Vec3,
    pub(super) radius: f32,
    pub(super) normal: Vec3,
    /// Original leaves represented.
    pub(super) count: f32,
    pub(super) area: f32,
    pub(super) label: u32,
}

impl Traits {
    pub(super) const NONE: Traits = Traits {
        center: Vec3::ZERO,
        radius: 0.0,
        normal: Vec3::ZERO,
        count: 0.0,
        area: 0.0,
        label: EMPTY,
    };

    pub(super) fn of(label: u32, leaf: &Leaf) -> Traits {
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
pub(super) struct Cell {
    pub(super) start: u32,
    pub(super) len: u32,
}

/// A dense uniform grid of living leaves over the box of their centres; points outside the
/// box (new leaves may stray a little) go to the nearest border cell. The slots of all cells
/// lie in two arrays, cell after cell (x fastest, so a row of cells is one run of memory):
/// `spheres` holds each leaf's centre and radius, all the distance test reads, and `traits`
/// the rest the cost needs. Each cell keeps room for half as many leaves again as it was
/// laid out with, for the new leaves of collapses.
#[derive(Default)]
pub(super) struct Grid {
    pub(super) origin: Vec3,
    pub(super) cell: f32,
    pub(super) inv_cell: f32,
    pub(super) dims: [i32; 3],
    /// One per cell, and one past the last that marks the end of the slots.
    pub(super) cells: Vec<Cell>,
    pub(super) spheres: Vec<Vec4>,
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
    pub(super) fn cell_count(&self) -> usize {
        self.dims.iter().map(|&d| d as usize).product()
    }

    /// Counts the leaves `labels` of each cell into `cells` (zeroed first); the cell of each
    /// into `cell_of`.
    pub(super) fn count(&mut self, leaves: &[Leaf], labels: &[u32]) {
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
    pub(super) fn occupied(&mut self, leaves: &[Leaf], labels: &[u32]) -> usize {
        self.count(leaves, labels);
        self.cells.iter().filter(|c| c.len > 0).count()
    }

    /// Lays out the leaves `labels` cell by cell, in the order given within each cell.
    pub(super) fn fill(&mut self, leaves: &[Leaf], labels: &[u32]) {
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

    pub(super) fn put(&mut self, slot: usize, traits: Traits) {
        self.spheres[slot] = traits.center.extend(traits.radius);
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

    /// Adds the leaf `label` to its cell; `false` when the cell has no room left.
    pub(super) fn insert(&mut self, label: u32, leaf: &Leaf) -> bool {
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
    pub(super) fn remove(&mut self, label: u32, p: Vec3) {
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
    pub(super) fn has_ring(&self, c: [i32; 3], ring: i32) -> bool {
        (0..3).any(|k| c[k] - ring >= 0 || c[k] + ring < self.dims[k])
    }

    /// Calls `visit` on the slots of the cells exactly `ring` cells away from `c` (Chebyshev
    /// distance) within the grid: once per run of cells adjacent in memory.
    pub(super) fn ring(&self, c: [i32; 3], ring: i32, mut visit: impl FnMut(Range<usize>)) {
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
    fn a_full_cell_refuses_a_leaf_until_laid_out_again() {
        let leaves: Vec<Leaf> = (0..6)
            .map(|i| leaf(Vec3::new(i as f32 * 0.01, 0.0, 0.0)))
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
