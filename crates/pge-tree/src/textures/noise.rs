//! Noise: hashed, periodic, cheap. Value noise from lattice tables read row by row, and
//! cellular (Worley) noise from a table of feature points.

use std::ops::Range;

/// A 32-bit hash of a lattice point and a seed (integer mixing, no tables).
pub(super) fn hash(x: u32, y: u32, seed: u32) -> u32 {
    let mut h =
        x.wrapping_mul(0x8da6_b343) ^ y.wrapping_mul(0xd816_3841) ^ seed.wrapping_mul(0xcb1a_b31f);
    h ^= h >> 15;
    h = h.wrapping_mul(0x2c1b_3c6d);
    h ^= h >> 12;
    h = h.wrapping_mul(0x297a_2d39);
    h ^ (h >> 15)
}

/// The `u` (or `v`) of the centre of pixel `i` of `n`.
#[inline]
pub(super) fn centre(i: usize, n: usize) -> f32 {
    (i as f32 + 0.5) / n as f32
}

/// A hash as a number in `[0, 1)`.
pub(super) fn unit(h: u32) -> f32 {
    (h >> 8) as f32 / (1u32 << 24) as f32
}

/// The largest integer not above `x` (for `|x|` below 2^31), without the `floorf` call that
/// `f32::floor` is on x86-64 without SSE 4.1.
#[inline]
pub(super) fn floor(x: f32) -> i64 {
    let i = x as i64;
    if (i as f32) > x { i - 1 } else { i }
}

/// `i` modulo `n` in `0..n`, without a division for the values noise lookups meet (one
/// period either side).
#[inline]
pub(super) fn wrap(i: i64, n: u32) -> u32 {
    let n = i64::from(n);
    if (0..n).contains(&i) {
        i as u32
    } else if (-n..0).contains(&i) {
        (i + n) as u32
    } else if (n..2 * n).contains(&i) {
        (i - n) as u32
    } else {
        i.rem_euclid(n) as u32
    }
}

#[inline]
pub(super) fn smooth(t: f32) -> f32 {
    t * t * (3.0 - 2.0 * t)
}

#[inline]
pub(super) fn smoothstep(a: f32, b: f32, x: f32) -> f32 {
    // A product, not a quotient: with constant edges the reciprocal folds away.
    smooth(((x - a) * (1.0 / (b - a))).clamp(0.0, 1.0))
}

/// Periodic value noise in `[0, 1]` with `px x py` lattice cells over the unit square (so it
/// tiles), its lattice values hashed once into a table: a lookup is four loads and a
/// bilinear blend. `(u, v)` may lie outside `[0, 1)`.
pub(super) struct Lattice {
    px: u32,
    py: u32,
    values: Vec<f32>,
    /// Where the pixel columns fall on the lattice (see [`Lattice::for_pixels`]).
    columns: Vec<Column>,
    /// The same as runs of pixel columns between the same two lattice columns, and every
    /// column's blend, for [`LatticeRow::values`].
    runs: Vec<(Range<usize>, u32, u32)>,
    tx: Vec<f32>,
}

/// Where one pixel column's `u` falls on a lattice: the lattice columns either side and the
/// smoothed blend between them, as [`LatticeRow::at`] finds them.
#[derive(Clone, Copy)]
struct Column {
    ix: u32,
    jx: u32,
    tx: f32,
}

impl Lattice {
    pub(super) fn new(px: u32, py: u32, seed: u32) -> Lattice {
        let values = (0..py)
            .flat_map(|y| (0..px).map(move |x| unit(hash(x, y, seed))))
            .collect();
        Lattice {
            px,
            py,
            values,
            columns: Vec::new(),
            runs: Vec::new(),
            tx: Vec::new(),
        }
    }

    /// The lattice with the columns of an `n`-pixel row found once, at the pixel centres
    /// `u = (x + 0.5) / n`, for `LatticeRow::pixel` (tests only): every row of a map shares them.
    pub(super) fn for_pixels(mut self, n: usize) -> Lattice {
        self.columns = (0..n)
            .map(|x| {
                let (ix, jx, tx) = self.column(centre(x, n));
                Column {
                    ix: ix as u32,
                    jx: jx as u32,
                    tx,
                }
            })
            .collect();
        self.tx = self.columns.iter().map(|c| c.tx).collect();
        self.runs.clear();
        for (x, c) in self.columns.iter().enumerate() {
            match self.runs.last_mut() {
                Some((run, ix, jx)) if (*ix, *jx) == (c.ix, c.jx) => run.end = x + 1,
                _ => self.runs.push((x..x + 1, c.ix, c.jx)),
            }
        }
        self
    }

    /// The lattice columns either side of `u` and the smoothed blend between them.
    #[inline]
    fn column(&self, u: f32) -> (usize, usize, f32) {
        let x = u * self.px as f32;
        let fx = floor(x);
        let tx = smooth(x - fx as f32);
        let ix = wrap(fx, self.px) as usize;
        let jx = if ix + 1 == self.px as usize {
            0
        } else {
            ix + 1
        };
        (ix, jx, tx)
    }

    /// The noise along the row at `v`: its two lattice rows and the blend between them
    /// found once, so a lookup is two loads per lattice row and three blends.
    pub(super) fn row(&self, v: f32) -> LatticeRow<'_> {
        let y = v * self.py as f32;
        let fy = floor(y);
        let iy = wrap(fy, self.py);
        let jy = if iy + 1 == self.py { 0 } else { iy + 1 };
        let px = self.px as usize;
        LatticeRow {
            lattice: self,
            top: &self.values[iy as usize * px..][..px],
            bottom: &self.values[jy as usize * px..][..px],
            ty: smooth(y - fy as f32),
        }
    }
}

/// One row of a [`Lattice`] (see [`Lattice::row`]).
pub(super) struct LatticeRow<'a> {
    lattice: &'a Lattice,
    top: &'a [f32],
    bottom: &'a [f32],
    ty: f32,
}

impl LatticeRow<'_> {
    /// The noise at `u` (tests only): the definition the pixel columns are held to.
    #[cfg(test)]
    pub(super) fn at(&self, u: f32) -> f32 {
        let (ix, jx, tx) = self.lattice.column(u);
        self.blend(ix, jx, tx)
    }

    /// The noise at the centre of pixel column `x`, the same number as [`LatticeRow::at`]
    /// gives there, from the columns found once (the lattice made [`Lattice::for_pixels`]):
    /// the definition [`LatticeRow::values`] is held to.
    #[cfg(test)]
    pub(super) fn pixel(&self, x: usize) -> f32 {
        let c = self.lattice.columns[x];
        self.blend(c.ix as usize, c.jx as usize, c.tx)
    }

    /// The noise at every pixel column (the lattice made [`Lattice::for_pixels`]), the same
    /// numbers as `LatticeRow::pixel` (tests only): each run of columns between the same two lattice
    /// columns in a loop the compiler vectorizes.
    pub(super) fn values(&self) -> Vec<f32> {
        let mut out = vec![0.0; self.lattice.tx.len()];
        self.each(&mut out, |o, value| *o = value);
        out
    }

    /// Calls `put` with every pixel column's slot in `out` and the noise there.
    #[inline(always)]
    fn each(&self, out: &mut [f32], put: impl Fn(&mut f32, f32)) {
        for (run, ix, jx) in &self.lattice.runs {
            let (ix, jx) = (*ix as usize, *jx as usize);
            // As `blend` finds them.
            let (top0, top_d) = (self.top[ix], self.top[jx] - self.top[ix]);
            let (bottom0, bottom_d) = (self.bottom[ix], self.bottom[jx] - self.bottom[ix]);
            let tx = &self.lattice.tx[run.clone()];
            for (o, &tx) in out[run.clone()].iter_mut().zip(tx) {
                let top = top0 + top_d * tx;
                let bottom = bottom0 + bottom_d * tx;
                put(o, top + (bottom - top) * self.ty);
            }
        }
    }

    #[cfg(test)]
    fn blend(&self, ix: usize, jx: usize, tx: f32) -> f32 {
        let top = self.top[ix] + (self.top[jx] - self.top[ix]) * tx;
        let bottom = self.bottom[ix] + (self.bottom[jx] - self.bottom[ix]) * tx;
        top + (bottom - top) * self.ty
    }
}

/// Periodic fractal value noise in `[0, 1]`: octave `o` has `2^o` times the lattice cells
/// of the first, half its amplitude and its own seed.
pub(super) struct Fractal {
    octaves: Vec<Lattice>,
    norm: f32,
}

impl Fractal {
    pub(super) fn new(px: u32, py: u32, octaves: u32, seed: u32) -> Fractal {
        let octaves: Vec<Lattice> = (0..octaves)
            .map(|o| Lattice::new(px << o, py << o, seed + o))
            .collect();
        let weight: f32 = (0..octaves.len()).map(|o| 0.5f32.powi(o as i32)).sum();
        Fractal {
            octaves,
            norm: 1.0 / weight,
        }
    }

    /// The noise with every octave's pixel columns found once (see [`Lattice::for_pixels`]).
    pub(super) fn for_pixels(self, n: usize) -> Fractal {
        Fractal {
            octaves: self.octaves.into_iter().map(|o| o.for_pixels(n)).collect(),
            norm: self.norm,
        }
    }

    /// The noise along the row at `v` (see [`Lattice::row`]).
    pub(super) fn row(&self, v: f32) -> FractalRow<'_> {
        FractalRow {
            octaves: self.octaves.iter().map(|o| o.row(v)).collect(),
            norm: self.norm,
        }
    }
}

/// One row of a [`Fractal`].
pub(super) struct FractalRow<'a> {
    octaves: Vec<LatticeRow<'a>>,
    norm: f32,
}

impl FractalRow<'_> {
    /// The noise at `u`: one lookup, the definition the row's values are held to.
    #[cfg(test)]
    pub(super) fn at(&self, u: f32) -> f32 {
        let (mut sum, mut amp) = (0.0, 1.0);
        for octave in &self.octaves {
            sum += amp * octave.at(u);
            amp *= 0.5;
        }
        sum * self.norm
    }

    /// The noise at the centre of pixel column `x` (see `LatticeRow::pixel` (tests only)).
    #[cfg(test)]
    pub(super) fn pixel(&self, x: usize) -> f32 {
        let (mut sum, mut amp) = (0.0, 1.0);
        for octave in &self.octaves {
            sum += amp * octave.pixel(x);
            amp *= 0.5;
        }
        sum * self.norm
    }

    /// The noise at every `us[i]`, the same numbers as `FractalRow::at`, an octave at a time
    /// (tests only).
    #[cfg(test)]
    pub(super) fn values_at(&self, us: &[f32]) -> Vec<f32> {
        let (mut sum, mut amp) = (vec![0.0f32; us.len()], 1.0f32);
        for octave in &self.octaves {
            for (s, &u) in sum.iter_mut().zip(us) {
                *s += amp * octave.at(u);
            }
            amp *= 0.5;
        }
        for s in &mut sum {
            *s *= self.norm;
        }
        sum
    }

    /// The noise at every pixel column, the same numbers as `FractalRow::pixel` (tests only) (see
    /// [`LatticeRow::values`]).
    pub(super) fn values(&self) -> Vec<f32> {
        let n = self.octaves.first().map_or(0, |o| o.lattice.tx.len());
        let (mut sum, mut amp) = (vec![0.0f32; n], 1.0f32);
        for octave in &self.octaves {
            octave.each(&mut sum, |s, value| *s += amp * value);
            amp *= 0.5;
        }
        for s in &mut sum {
            *s *= self.norm;
        }
        sum
    }
}

/// Periodic cellular (Worley) noise with `nx x ny` cells over the unit square, one feature
/// point per cell, the points hashed once into a table with a border of one cell (wrapped
/// copies), so the 3 x 3 neighbourhood of a cell is nine loads with no wrapping. Distances
/// are measured in cell units (cells wider in `v` than in `u` are stretched along `v`).
pub(super) struct Cells {
    nx: u32,
    ny: u32,
    /// `(nx + 2) x (ny + 2)` points: feature position inside its cell, and the cell's hash.
    points: Vec<(f32, f32, u32)>,
}

impl Cells {
    pub(super) fn new(nx: u32, ny: u32, seed: u32) -> Cells {
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
    pub(super) fn at(&self, u: f32, v: f32) -> (f32, f32, u32) {
        self.nearest(u, v).distances()
    }

    /// `Cells::at` (tests only) of every `(us[i], vs[i])`, the same numbers as one lookup at a time,
    /// for points that mostly follow each other in the same cell (a row of pixels): every
    /// run of points in one cell is measured against that cell's nine feature points, loaded
    /// once, in a loop the compiler vectorizes; square roots four at a time at the end.
    pub(super) fn many(&self, us: &[f32], vs: &[f32]) -> Distances {
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
    pub(super) fn row(&self, v: f32) -> CellsRow {
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
pub(super) struct CellsRow {
    nx: u32,
    /// Three lattice rows of `nx + 2` points: feature `u` inside its cell, squared `v`
    /// distance from the row, the cell's hash.
    points: Vec<(f32, f32, u32)>,
}

impl CellsRow {
    /// The nearest and second-nearest feature distances at `u` and the nearest cell's hash:
    /// one lookup, the definition [`CellsRow::many`] is held to.
    #[cfg(test)]
    pub(super) fn at(&self, u: f32) -> (f32, f32, u32) {
        self.nearest(u).distances()
    }

    /// `CellsRow::at` (tests only) of every `us[i]`, the same numbers as one lookup at a time (see
    /// [`Cells::many`]).
    pub(super) fn many(&self, us: impl IntoIterator<Item = f32>) -> Distances {
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
pub(super) struct Distances {
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
    pub(super) fn at(&self, i: usize) -> (f32, f32, u32) {
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

/// A coordinate wrapped into `[0, 1)`.
trait UnitWrap {
    fn rem_euclid_unit(self) -> Self;
}

impl UnitWrap for f32 {
    #[inline]
    fn rem_euclid_unit(self) -> f32 {
        if (0.0..1.0).contains(&self) {
            self
        } else {
            let f = self - floor(self) as f32;
            if f < 1.0 { f } else { 0.0 }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Cellular noise by definition: hash every neighbouring cell at each lookup.
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

    #[test]
    fn lattice_noise_interpolates_its_hashes_and_tiles() {
        let lattice = Lattice::new(4, 3, 11);
        for (x, y) in [(0u32, 0u32), (3, 2), (1, 2)] {
            let at = lattice.row(y as f32 / 3.0).at(x as f32 / 4.0);
            assert!((at - unit(hash(x, y, 11))).abs() < 1e-6, "{x} {y}");
        }
        for i in 0..50 {
            let (u, v) = (i as f32 / 47.0, (i * 7 % 50) as f32 / 53.0);
            let (a, b) = (lattice.row(v).at(u), lattice.row(v - 1.0).at(u + 1.0));
            assert!((a - b).abs() < 1e-4, "periodic at {u} {v}");
            assert!((0.0..=1.0).contains(&a));
        }
        let fractal = Fractal::new(6, 6, 3, 31);
        let row = fractal.row(0.3);
        assert!((0..100).all(|i| (0.0..=1.0).contains(&row.at(i as f32 / 99.0))));
    }

    #[test]
    fn pixel_columns_give_the_same_numbers_as_lookups() {
        for n in [16usize, 100, 512] {
            let lattice = Lattice::new(5, 5, 21).for_pixels(n);
            let fractal = Fractal::new(64, 6, 6, 14).for_pixels(n);
            for j in 0..20 {
                let v = (j as f32 + 0.5) / 20.0;
                let (row, frow) = (lattice.row(v), fractal.row(v));
                for x in 0..n {
                    let u = (x as f32 + 0.5) / n as f32;
                    assert_eq!(row.pixel(x).to_bits(), row.at(u).to_bits(), "{n} {x} {v}");
                    assert_eq!(frow.pixel(x).to_bits(), frow.at(u).to_bits(), "{n} {x}");
                }
                let shifted: Vec<f32> = (0..n).map(|x| centre(x, n) + 0.3 * v).collect();
                let at = frow.values_at(&shifted);
                for (x, &u) in shifted.iter().enumerate() {
                    assert_eq!(at[x].to_bits(), frow.at(u).to_bits(), "{n} {x} {u}");
                }
                let (values, fvalues) = (row.values(), frow.values());
                assert_eq!(values.len(), n);
                for x in 0..n {
                    assert_eq!(values[x].to_bits(), row.pixel(x).to_bits(), "{n} {x}");
                    assert_eq!(fvalues[x].to_bits(), frow.pixel(x).to_bits(), "{n} {x}");
                }
            }
        }
    }

    #[test]
    fn floor_is_the_floor() {
        for x in [-2.5f32, -1.0, -0.25, 0.0, 0.25, 1.0, 3.75, 511.5] {
            assert_eq!(floor(x), x.floor() as i64, "{x}");
        }
    }

    #[test]
    fn wrap_is_the_euclidean_remainder() {
        for n in [1u32, 2, 7, 22] {
            for i in -100i64..100 {
                assert_eq!(wrap(i, n), i.rem_euclid(i64::from(n)) as u32, "{i} mod {n}");
            }
        }
    }
}
