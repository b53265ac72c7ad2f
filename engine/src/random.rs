//! Lua-free random helpers: the draws every generator shares, so that a number drawn in
//! Rust and one drawn by `pge.random()` from the same generator are the same number, and the
//! one home of seed derivation: [`splitmix64`], the seeds of independent parts of a run
//! ([`hash_words`], [`SplitMix64`]) and a script's own seed mixed into the run's
//! ([`mix_seed`], [`mix_seed_multiply`]).
//!
//! ```
//! use pge_engine::random::{mt_from_seed, uniform};
//!
//! let mut a = mt_from_seed(7);
//! let mut b = mt_from_seed(7);
//! assert_eq!(uniform(&mut a), uniform(&mut b));
//! ```

use crate::math;
use rand_mt::{Mt, Mt64};

/// The golden-ratio increment of splitmix64 (2^64 / φ, odd): also a good multiplier for
/// spreading a word's bits.
pub const GOLDEN_GAMMA: u64 = 0x9e37_79b9_7f4a_7c15;

/// The output function of splitmix64 (the finaliser of MurmurHash3 with Stafford's
/// "Mix13" constants): a bijective, well-mixed hash of a 64-bit word.
#[must_use]
#[inline]
pub const fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// One round of splitmix64 on `z`: [`mix64`] of `z + GOLDEN_GAMMA`. Bijective, so distinct
/// words give distinct results.
#[must_use]
#[inline]
pub const fn splitmix64(z: u64) -> u64 {
    mix64(z.wrapping_add(GOLDEN_GAMMA))
}

/// A seed from several words, order mattering (a forest's seed, a purpose tag, a layer, a
/// cell's coordinates...): a seed derived from what is computed, never from the order work is
/// done in.
#[must_use]
pub fn hash_words(parts: &[u64]) -> u64 {
    parts
        .iter()
        .fold(0x6a09_e667_f3bc_c908, |h, &p| splitmix64(h ^ splitmix64(p)))
}

/// The run's seed combined with a script's own `seed` by splitmix64 of the latter; the
/// identity for `own = 0` (a script that sets no seed grows what the run's seed grows).
#[must_use]
pub const fn mix_seed(run: u64, own: u64) -> u64 {
    if own == 0 {
        return run;
    }
    run ^ splitmix64(own)
}

/// The run's seed combined with a script's own `seed` by one multiplication of the latter
/// (the tree mesher's mixing, kept because its outputs are pinned); also the identity for
/// `own = 0`. Prefer [`mix_seed`] in new code: its result is better spread.
#[must_use]
pub const fn mix_seed_multiply(run: u64, own: u64) -> u64 {
    run ^ own.wrapping_mul(GOLDEN_GAMMA)
}

/// A small, fast generator: the splitmix64 sequence (Steele, Lea and Flood 2014), for the
/// draws of one cell or one instance, seeded by [`hash_words`].
#[derive(Clone, Debug)]
pub struct SplitMix64(u64);

impl SplitMix64 {
    /// A generator seeded by `seed`.
    #[must_use]
    pub const fn new(seed: u64) -> SplitMix64 {
        SplitMix64(seed)
    }

    /// The next 64 random bits.
    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(GOLDEN_GAMMA);
        mix64(self.0)
    }

    /// Uniform in `[0, 1)`, 53 random bits.
    #[inline]
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform in `[a, b)`.
    #[inline]
    pub fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.uniform()
    }

    /// Uniform integer in `[0, n)` (0 for `n = 0`), by the multiply-shift of the high 32 bits.
    #[inline]
    pub fn below(&mut self, n: u32) -> u32 {
        (((self.next_u64() >> 32) * u64::from(n)) >> 32) as u32
    }
}

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
    mu + sigma * (-2.0 * math::ln(u1)).sqrt() * math::cos(std::f64::consts::TAU * u2)
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
    fn splitmix64_matches_the_reference_sequence() {
        // The first outputs of splitmix64.c (Vigna) seeded with 1234567.
        let mut r = SplitMix64::new(1_234_567);
        assert_eq!(r.next_u64(), 6_457_827_717_110_365_317);
        assert_eq!(r.next_u64(), 3_203_168_211_198_807_973);
        assert_eq!(splitmix64(1_234_567), 6_457_827_717_110_365_317);
    }

    #[test]
    fn hash_words_depends_on_every_word_and_its_order() {
        assert_ne!(hash_words(&[1, 2, 3]), hash_words(&[1, 3, 2]));
        assert_ne!(hash_words(&[1, 2, 3]), hash_words(&[1, 2, 4]));
        assert_eq!(hash_words(&[1, 2, 3]), hash_words(&[1, 2, 3]));
        assert_ne!(hash_words(&[]), hash_words(&[0]));
    }

    #[test]
    fn a_seed_of_zero_leaves_the_run_seed_alone() {
        assert_eq!(mix_seed(42, 0), 42);
        assert_eq!(mix_seed_multiply(42, 0), 42);
        assert_eq!(mix_seed(42, 7), 42 ^ splitmix64(7));
        assert_ne!(mix_seed(42, 7), mix_seed(42, 8));
        assert_eq!(mix_seed_multiply(1, 1), 1 ^ GOLDEN_GAMMA);
    }

    #[test]
    fn splitmix_draws_stay_in_range_and_spread() {
        let mut r = SplitMix64::new(42);
        let mut counts = [0u32; 4];
        for _ in 0..4000 {
            let u = r.uniform();
            assert!((0.0..1.0).contains(&u));
            let x = r.range(2.0, 3.0);
            assert!((2.0..3.0).contains(&x));
            counts[r.below(4) as usize] += 1;
        }
        assert!(counts.iter().all(|&c| c > 850 && c < 1150), "{counts:?}");
        assert_eq!(r.below(0), 0);
    }

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
