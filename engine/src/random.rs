//! Lua-free random helpers: the draws every generator shares, so that a number drawn in
//! Rust and one drawn by `pge.random()` from the same generator are the same number.
//!
//! ```
//! use pge_engine::random::{mt_from_seed, uniform};
//!
//! let mut a = mt_from_seed(7);
//! let mut b = mt_from_seed(7);
//! assert_eq!(uniform(&mut a), uniform(&mut b));
//! ```

use rand_mt::{Mt, Mt64};

/// A uniform number in `[0, 1)` with 53 random bits (MT19937's `genrand_res53`).
#[must_use]
pub fn uniform(rng: &mut Mt) -> f64 {
    let a = f64::from(rng.next_u32() >> 5);
    let b = f64::from(rng.next_u32() >> 6);
    (a * 67_108_864.0 + b) / 9_007_199_254_740_992.0
}

/// A uniform number in `[0, 1)` with 53 random bits from one draw of an MT19937-64.
#[must_use]
pub fn uniform64(rng: &mut Mt64) -> f64 {
    (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64
}

/// A uniform `f32` in `[0, 1)` with 24 random bits from one draw of an MT19937-64 (every
/// value exactly representable, so the result is never rounded up to 1).
#[must_use]
#[inline]
pub fn uniform24(rng: &mut Mt64) -> f32 {
    (rng.next_u64() >> 40) as f32 / (1u32 << 24) as f32
}

/// An integer in `[a, b]` (inclusive), from [`uniform`]. `a` must not exceed `b`.
#[must_use]
pub fn int_in(rng: &mut Mt, a: i64, b: i64) -> i64 {
    // In 128 bits: `b - a` of the widest interval (mininteger..maxinteger) passes i64.
    let span = (i128::from(b) - i128::from(a)) as f64 + 1.0;
    let offset = (uniform(rng) * span).floor() as i128;
    (i128::from(a) + offset).min(i128::from(b)) as i64
}

/// A normally distributed number (Box-Muller, one cosine branch) from two [`uniform`] draws.
#[must_use]
pub fn normal(rng: &mut Mt, mu: f64, sigma: f64) -> f64 {
    let u1 = 1.0 - uniform(rng);
    let u2 = uniform(rng);
    mu + sigma * (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// The MT19937 of a run seed (both halves of a 64-bit seed are used): the generator of
/// `pge.random()` and `pge.rng(seed)`.
#[must_use]
pub fn mt_from_seed(seed: u64) -> Mt {
    Mt::new_with_key([seed as u32, (seed >> 32) as u32])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_is_in_range_and_repeatable() {
        let mut a = mt_from_seed(7);
        let mut b = mt_from_seed(7);
        for _ in 0..1000 {
            let x = uniform(&mut a);
            assert!((0.0..1.0).contains(&x));
            assert_eq!(x, uniform(&mut b));
        }
    }

    #[test]
    fn uniform_matches_genrand_res53() {
        // init_genrand(0) then genrand_res53: numpy's RandomState(0).random_sample().
        let mut mt = Mt::new(0);
        assert_eq!(uniform(&mut mt), 0.548_813_503_927_324_8);
    }

    #[test]
    fn mt64_draws_are_in_range() {
        let mut r = Mt64::new(3);
        for _ in 0..1000 {
            assert!((0.0..1.0).contains(&uniform64(&mut r)));
            assert!((0.0..1.0).contains(&uniform24(&mut r)));
        }
    }

    #[test]
    fn int_is_inclusive() {
        let mut r = mt_from_seed(1);
        let mut seen = [false; 3];
        for _ in 0..200 {
            let v = int_in(&mut r, 1, 3);
            seen[(v - 1) as usize] = true;
        }
        assert_eq!(seen, [true; 3]);
    }

    #[test]
    fn int_spans_the_whole_integer_range() {
        let mut r = mt_from_seed(1);
        let draws: Vec<i64> = (0..200)
            .map(|_| int_in(&mut r, i64::MIN, i64::MAX))
            .collect();
        let negative = draws.iter().filter(|v| **v < 0).count();
        assert!((50..150).contains(&negative), "{negative} of 200 negative");
        assert!(draws.iter().all(|v| *v != i64::MIN));
        assert_eq!(int_in(&mut r, i64::MAX, i64::MAX), i64::MAX);
        assert_eq!(int_in(&mut r, i64::MIN, i64::MIN), i64::MIN);
    }
}
