//! Noise: hashed, periodic, cheap. Value noise from lattice tables read row by row
//! ([`Lattice`], [`Fractal`]), and cellular (Worley) noise from a table of feature points
//! ([`Cells`]); here the hash and the small numeric helpers they share.

mod cells;
mod lattice;

pub(super) use cells::Cells;
pub(super) use lattice::{Fractal, Lattice};

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

/// A coordinate wrapped into `[0, 1)`.
pub(super) trait UnitWrap {
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
