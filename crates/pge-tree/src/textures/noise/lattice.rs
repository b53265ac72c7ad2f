//! Periodic value noise: a lattice of hashed values read row by row, and its fractal sum.

use std::ops::Range;

use super::{centre, floor, hash, smooth, unit, wrap};

/// Periodic value noise in `[0, 1]` with `px x py` lattice cells over the unit square (so it
/// tiles), its lattice values hashed once into a table: a lookup is four loads and a
/// bilinear blend. `(u, v)` may lie outside `[0, 1)`.
pub(in crate::textures) struct Lattice {
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
    pub(in crate::textures) fn new(px: u32, py: u32, seed: u32) -> Lattice {
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
    pub(in crate::textures) fn for_pixels(mut self, n: usize) -> Lattice {
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
    pub(in crate::textures) fn row(&self, v: f32) -> LatticeRow<'_> {
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
pub(in crate::textures) struct LatticeRow<'a> {
    lattice: &'a Lattice,
    top: &'a [f32],
    bottom: &'a [f32],
    ty: f32,
}

impl LatticeRow<'_> {
    /// The noise at `u` (tests only): the definition the pixel columns are held to.
    #[cfg(test)]
    pub(in crate::textures) fn at(&self, u: f32) -> f32 {
        let (ix, jx, tx) = self.lattice.column(u);
        self.blend(ix, jx, tx)
    }

    /// The noise at the centre of pixel column `x`, the same number as [`LatticeRow::at`]
    /// gives there, from the columns found once (the lattice made [`Lattice::for_pixels`]):
    /// the definition [`LatticeRow::values`] is held to.
    #[cfg(test)]
    pub(in crate::textures) fn pixel(&self, x: usize) -> f32 {
        let c = self.lattice.columns[x];
        self.blend(c.ix as usize, c.jx as usize, c.tx)
    }

    /// The noise at every pixel column (the lattice made [`Lattice::for_pixels`]), the same
    /// numbers as `LatticeRow::pixel` (tests only): each run of columns between the same two lattice
    /// columns in a loop the compiler vectorizes.
    pub(in crate::textures) fn values(&self) -> Vec<f32> {
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
pub(in crate::textures) struct Fractal {
    octaves: Vec<Lattice>,
    norm: f32,
}

impl Fractal {
    pub(in crate::textures) fn new(px: u32, py: u32, octaves: u32, seed: u32) -> Fractal {
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
    pub(in crate::textures) fn for_pixels(self, n: usize) -> Fractal {
        Fractal {
            octaves: self.octaves.into_iter().map(|o| o.for_pixels(n)).collect(),
            norm: self.norm,
        }
    }

    /// The noise along the row at `v` (see [`Lattice::row`]).
    pub(in crate::textures) fn row(&self, v: f32) -> FractalRow<'_> {
        FractalRow {
            octaves: self.octaves.iter().map(|o| o.row(v)).collect(),
            norm: self.norm,
        }
    }
}

/// One row of a [`Fractal`].
pub(in crate::textures) struct FractalRow<'a> {
    octaves: Vec<LatticeRow<'a>>,
    norm: f32,
}

impl FractalRow<'_> {
    /// The noise at `u`: one lookup, the definition the row's values are held to.
    #[cfg(test)]
    pub(in crate::textures) fn at(&self, u: f32) -> f32 {
        let (mut sum, mut amp) = (0.0, 1.0);
        for octave in &self.octaves {
            sum += amp * octave.at(u);
            amp *= 0.5;
        }
        sum * self.norm
    }

    /// The noise at the centre of pixel column `x` (see `LatticeRow::pixel` (tests only)).
    #[cfg(test)]
    pub(in crate::textures) fn pixel(&self, x: usize) -> f32 {
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
    pub(in crate::textures) fn values_at(&self, us: &[f32]) -> Vec<f32> {
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
    pub(in crate::textures) fn values(&self) -> Vec<f32> {
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

#[cfg(test)]
mod tests {
    use super::*;

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
}
