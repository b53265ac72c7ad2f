//! Periodic cellular (Worley) noise from a table of feature points.

use std::ops::Range;

use super::{UnitWrap, hash, unit, wrap};

/// Periodic cellular (Worley) noise with `nx x ny` cells over the unit square, one feature
/// point per cell, the points hashed once into a table with a border of one cell (wrapped
/// copies), so the 3 x 3 neighbourhood of a cell is nine loads with no wrapping. Distances
/// are measured in cell units (cells wider in `v` than in `u` are stretched along `v`).
pub(in crate::textures) struct Cells {
    nx: u32,
    ny: u32,
    /// `(nx + 2) x (ny + 2)` points: feature position inside its cell, and the cell's hash.
    points: Vec<(f32, f32, u32)>,
}

impl Cells {
    pub(in crate::textures) fn new(nx: u32, ny: u32, seed: u32) -> Cells {
        let points = (-1..=ny as i64)
            .flat_map(|gy| {
                (-1..=nx as i64).map(move |gx| {
                    let h = hash(wrap(gx, nx), wrap(gy, ny), seed);
                    (0.1 + 0.8 * unit(h), 0.1 + 0.8 * unit(h.rotate_left(16)), h)
                })
            })
            .collect();
        Cells { nx, ny, points }
    }

    /// The nearest and second-nearest feature distances at `(u, v)` and the nearest cell's
    /// hash: one lookup, the definition [`Cells::many`] is held to.
    #[cfg(test)]
    pub(in crate::textures) fn at(&self, u: f32, v: f32) -> (f32, f32, u32) {
        self.nearest(u, v).distances()
    }

    /// `Cells::at` (tests only) of every `(us[i], vs[i])`, the same numbers as one lookup at a time,
    /// for points that mostly follow each other in the same cell (a row of pixels): every
    /// run of points in one cell is measured against that cell's nine feature points, loaded
    /// once, in a loop the compiler vectorizes; square roots four at a time at the end.
    pub(in crate::textures) fn many(&self, us: &[f32], vs: &[f32]) -> Distances {
        let stride = self.nx as usize + 2;
        let (mut cell, mut rxs, mut rys) = (Vec::new(), Vec::new(), Vec::new());
        for (&u, &v) in us.iter().zip(vs) {
            let (x, y) = (
                u.rem_euclid_unit() * self.nx as f32,
                v.rem_euclid_unit() * self.ny as f32,
            );
            let cx = (x as u32).min(self.nx - 1);
            let cy = (y as u32).min(self.ny - 1);
            cell.push(cy as usize * stride + cx as usize);
            rxs.push(x - cx as f32);
            rys.push(y - cy as f32);
        }
        let mut at = Distances::new(cell.len());
        for run in runs(&cell) {
            let corner = cell[run.start];
            let points: [(f32, f32, u32); 9] =
                std::array::from_fn(|k| self.points[corner + k / 3 * stride + k % 3]);
            let (f1, f2, ids) = at.run(run.clone());
            for ((((&rx, &ry), f1), f2), id) in rxs[run.clone()]
                .iter()
                .zip(&rys[run])
                .zip(f1)
                .zip(f2)
                .zip(ids)
            {
                // As `nearest` measures, in the same order.
                let mut nearest = Nearest::new();
                for (k, &(px, py, h)) in points.iter().enumerate() {
                    let oy = (k / 3) as f32 - 1.0 - ry;
                    let ex = (k % 3) as f32 - 1.0 - rx + px;
                    let ey = oy + py;
                    nearest.add(ex * ex + ey * ey, h);
                }
                (*f1, *f2, *id) = (nearest.f1, nearest.f2, nearest.id);
            }
        }
        at.roots();
        at
    }

    #[cfg(test)]
    fn nearest(&self, u: f32, v: f32) -> Nearest {
        let (x, y) = (
            u.rem_euclid_unit() * self.nx as f32,
            v.rem_euclid_unit() * self.ny as f32,
        );
        let cx = (x as u32).min(self.nx - 1);
        let cy = (y as u32).min(self.ny - 1);
        let (rx, ry) = (x - cx as f32, y - cy as f32);
        let stride = self.nx as usize + 2;
        let mut nearest = Nearest::new();
        for dy in 0..3 {
            let row = &self.points[(cy as usize + dy) * stride + cx as usize..][..3];
            let oy = dy as f32 - 1.0 - ry;
            for (dx, &(px, py, h)) in row.iter().enumerate() {
                let ex = dx as f32 - 1.0 - rx + px;
                let ey = oy + py;
                nearest.add(ex * ex + ey * ey, h);
            }
        }
        nearest
    }

    /// The noise along the row at `v`: the squared `v` distances from the row to the
    /// feature points of its three lattice rows found once, so a lookup (`CellsRow::at` (tests only))
    /// is nine multiply-adds (the same numbers as `Cells::at` (tests only)).
    pub(in crate::textures) fn row(&self, v: f32) -> CellsRow {
        let y = v.rem_euclid_unit() * self.ny as f32;
        let cy = (y as u32).min(self.ny - 1) as usize;
        let ry = y - cy as f32;
        let stride = self.nx as usize + 2;
        let mut points = Vec::with_capacity(3 * stride);
        for dy in 0..3 {
            let oy = dy as f32 - 1.0 - ry;
            points.extend(self.points[(cy + dy) * stride..][..stride].iter().map(
                |&(px, py, h)| {
                    let ey = oy + py;
                    (px, ey * ey, h)
                },
            ));
        }
        CellsRow {
            nx: self.nx,
            points,
        }
    }
}

/// One row of [`Cells`] (see [`Cells::row`]).
pub(in crate::textures) struct CellsRow {
    nx: u32,
    /// Three lattice rows of `nx + 2` points: feature `u` inside its cell, squared `v`
    /// distance from the row, the cell's hash.
    points: Vec<(f32, f32, u32)>,
}

impl CellsRow {
    /// The nearest and second-nearest feature distances at `u` and the nearest cell's hash:
    /// one lookup, the definition [`CellsRow::many`] is held to.
    #[cfg(test)]
    pub(in crate::textures) fn at(&self, u: f32) -> (f32, f32, u32) {
        self.nearest(u).distances()
    }

    /// `CellsRow::at` (tests only) of every `us[i]`, the same numbers as one lookup at a time (see
    /// [`Cells::many`]).
    pub(in crate::textures) fn many(&self, us: impl IntoIterator<Item = f32>) -> Distances {
        let stride = self.nx as usize + 2;
        let (mut cell, mut rxs) = (Vec::new(), Vec::new());
        for u in us {
            let x = u.rem_euclid_unit() * self.nx as f32;
            let cx = (x as u32).min(self.nx - 1);
            cell.push(cx as usize);
            rxs.push(x - cx as f32);
        }
        let mut at = Distances::new(cell.len());
        for run in runs(&cell) {
            let cx = cell[run.start];
            let points: [(f32, f32, u32); 9] =
                std::array::from_fn(|k| self.points[k / 3 * stride + cx + k % 3]);
            let (f1, f2, ids) = at.run(run.clone());
            for (((&rx, f1), f2), id) in rxs[run].iter().zip(f1).zip(f2).zip(ids) {
                let mut nearest = Nearest::new();
                for (k, &(px, ey2, h)) in points.iter().enumerate() {
                    let ex = (k % 3) as f32 - 1.0 - rx + px;
                    nearest.add(ex * ex + ey2, h);
                }
                (*f1, *f2, *id) = (nearest.f1, nearest.f2, nearest.id);
            }
        }
        at.roots();
        at
    }

    #[cfg(test)]
    fn nearest(&self, u: f32) -> Nearest {
        let x = u.rem_euclid_unit() * self.nx as f32;
        let cx = (x as u32).min(self.nx - 1) as usize;
        let rx = x - cx as f32;
        let stride = self.nx as usize + 2;
        let mut nearest = Nearest::new();
        for dy in 0..3 {
            let row = &self.points[dy * stride + cx..][..3];
            for (dx, &(px, ey2, h)) in row.iter().enumerate() {
                let ex = dx as f32 - 1.0 - rx + px;
                nearest.add(ex * ex + ey2, h);
            }
        }
        nearest
    }
}

/// The runs of equal values in `cells`, in order.
fn runs(cells: &[usize]) -> impl Iterator<Item = Range<usize>> + '_ {
    let mut start = 0;
    std::iter::from_fn(move || {
        let first = *cells.get(start)?;
        let len = cells[start..]
            .iter()
            .position(|&c| c != first)
            .unwrap_or(cells.len() - start);
        start += len;
        Some(start - len..start)
    })
}

/// Cellular noise at many points (see [`Cells::many`]): squared distances until
/// [`Distances::roots`].
pub(in crate::textures) struct Distances {
    f1: Vec<f32>,
    f2: Vec<f32>,
    ids: Vec<u32>,
}

impl Distances {
    fn new(n: usize) -> Distances {
        Distances {
            f1: vec![0.0; n],
            f2: vec![0.0; n],
            ids: vec![0; n],
        }
    }

    /// The nearest, second-nearest and nearest hash of the points in `run`.
    fn run(&mut self, run: Range<usize>) -> (&mut [f32], &mut [f32], &mut [u32]) {
        (
            &mut self.f1[run.clone()],
            &mut self.f2[run.clone()],
            &mut self.ids[run],
        )
    }

    /// Squared distances to distances.
    fn roots(&mut self) {
        for d in self.f1.iter_mut().chain(&mut self.f2) {
            *d = d.sqrt();
        }
    }

    /// The nearest and second-nearest feature distances at point `i` and the nearest cell's
    /// hash, as `Cells::at` (tests only) gives them.
    #[inline]
    pub(in crate::textures) fn at(&self, i: usize) -> (f32, f32, u32) {
        (self.f1[i], self.f2[i], self.ids[i])
    }
}

/// The two smallest squared distances seen and the hash of the nearest, kept without
/// branches (a feature point's order among its neighbours is unpredictable).
struct Nearest {
    f1: f32,
    f2: f32,
    id: u32,
}

impl Nearest {
    #[inline]
    fn new() -> Nearest {
        Nearest {
            f1: f32::MAX,
            f2: f32::MAX,
            id: 0,
        }
    }

    #[inline]
    fn add(&mut self, d: f32, h: u32) {
        let closer = d < self.f1;
        // min(f2, max(f1, d)): the old nearest when `d` is nearer, else `d` if nearer than
        // the second.
        let second = if self.f1 > d { self.f1 } else { d };
        self.f2 = if second < self.f2 { second } else { self.f2 };
        self.f1 = if closer { d } else { self.f1 };
        self.id = if closer { h } else { self.id };
    }

    #[cfg(test)]
    fn distances(&self) -> (f32, f32, u32) {
        (self.f1.sqrt(), self.f2.sqrt(), self.id)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cellular_reference(u: f32, v: f32, nx: u32, ny: u32, seed: u32) -> (f32, f32, u32) {
        let (x, y) = (u * nx as f32, v * ny as f32);
        let (cx, cy) = (x.floor() as i64, y.floor() as i64);
        let (mut f1, mut f2, mut id) = (f32::MAX, f32::MAX, 0);
        for gy in cy - 1..=cy + 1 {
            for gx in cx - 1..=cx + 1 {
                let h = hash(wrap(gx, nx), wrap(gy, ny), seed);
                let fx = gx as f32 + 0.1 + 0.8 * unit(h);
                let fy = gy as f32 + 0.1 + 0.8 * unit(h.rotate_left(16));
                let d = (fx - x).powi(2) + (fy - y).powi(2);
                if d < f1 {
                    (f2, f1, id) = (f1, d, h);
                } else if d < f2 {
                    f2 = d;
                }
            }
        }
        (f1.sqrt(), f2.sqrt(), id)
    }

    #[test]
    fn cell_tables_give_the_cellular_noise_of_the_hashes() {
        for (nx, ny, seed) in [(8, 2, 12), (5, 4, 23), (16, 6, 13), (1, 1, 3)] {
            let cells = Cells::new(nx, ny, seed);
            for i in 0..200 {
                // Inside the tile, and a little outside it (warped lookups).
                let u = i as f32 / 173.0 - 0.07;
                let v = (i * 37 % 200) as f32 / 190.0 - 0.03;
                let (f1, f2, id) = cells.at(u, v);
                let (r1, r2, rid) =
                    cellular_reference(u.rem_euclid(1.0), v.rem_euclid(1.0), nx, ny, seed);
                assert!((f1 - r1).abs() < 1e-4 && (f2 - r2).abs() < 1e-4, "{u} {v}");
                assert_eq!(id, rid, "{u} {v}");
                assert!(f1 <= f2);
            }
        }
    }

    #[test]
    fn cell_rows_give_the_same_numbers_as_lookups() {
        for (nx, ny, seed) in [(8, 2, 12), (16, 6, 13), (11, 2, 42), (1, 1, 3)] {
            let cells = Cells::new(nx, ny, seed);
            for j in 0..40 {
                let v = j as f32 / 39.0 - 0.02;
                let row = cells.row(v);
                for i in 0..100 {
                    let u = i as f32 / 97.0 - 0.01;
                    assert_eq!(row.at(u), cells.at(u, v), "{u} {v}");
                }
            }
        }
    }

    #[test]
    fn many_lookups_give_the_same_numbers_as_one_at_a_time() {
        let cells = Cells::new(5, 4, 23);
        let us: Vec<f32> = (0..300).map(|i| i as f32 / 281.0 - 0.03).collect();
        let vs: Vec<f32> = (0..300)
            .map(|i| (i * 37 % 300) as f32 / 290.0 - 0.02)
            .collect();
        let many = cells.many(&us, &vs);
        let row = cells.row(0.37);
        let row_many = row.many(us.iter().copied());
        for (i, (&u, &v)) in us.iter().zip(&vs).enumerate() {
            assert_eq!(many.at(i), cells.at(u, v), "{u} {v}");
            assert_eq!(row_many.at(i), row.at(u), "{u}");
        }
    }
}
