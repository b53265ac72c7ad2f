//! Approximate equality of floats and glam vectors: one [`assert_approx_eq!`] for every
//! test that compares computed geometry, instead of a `close` helper per test module.
//!
//! ```
//! use glam::Vec3;
//! use pge_engine::assert_approx_eq;
//!
//! assert_approx_eq!(0.1_f32 + 0.2, 0.3);
//! assert_approx_eq!(Vec3::X.cross(Vec3::Y), Vec3::Z, 1e-6);
//! // Relative: within 1e-5 of 1 + the larger magnitude.
//! assert_approx_eq!(1.0e6_f64 + 1.0, 1.0e6, rel 1e-5);
//! ```

use glam::{DVec3, Vec2, Vec3, Vec4};

/// A value with a distance to another of its type: the absolute difference of numbers, the
/// length of the difference of vectors.
pub trait ApproxEq: Copy + std::fmt::Debug {
    /// The distance between `self` and `other` (NaN when either is NaN).
    #[must_use]
    fn distance(self, other: Self) -> f64;

    /// The size of `self` (absolute value, vector length), for relative tolerances.
    #[must_use]
    fn magnitude(self) -> f64;
}

impl ApproxEq for f32 {
    fn distance(self, other: Self) -> f64 {
        f64::from((self - other).abs())
    }
    fn magnitude(self) -> f64 {
        f64::from(self.abs())
    }
}

impl ApproxEq for f64 {
    fn distance(self, other: Self) -> f64 {
        (self - other).abs()
    }
    fn magnitude(self) -> f64 {
        self.abs()
    }
}

macro_rules! vector {
    ($($t:ty),*) => {$(
        impl ApproxEq for $t {
            fn distance(self, other: Self) -> f64 {
                f64::from(self.distance(other))
            }
            fn magnitude(self) -> f64 {
                f64::from(self.length())
            }
        }
    )*};
}
vector!(Vec2, Vec3, Vec4, DVec3);

/// Whether `a` and `b` are within `tolerance` of each other (never for NaN).
#[must_use]
pub fn approx_eq<T: ApproxEq>(a: T, b: T, tolerance: f64) -> bool {
    a.distance(b) <= tolerance
}

/// The tolerance `relative * (1 + max(|a|, |b|))`: relative for large values, absolute near
/// zero.
#[must_use]
pub fn relative_tolerance<T: ApproxEq>(a: T, b: T, relative: f64) -> f64 {
    relative * (1.0 + a.magnitude().max(b.magnitude()))
}

/// Asserts that two floats or glam vectors ([`ApproxEq`]) are close:
/// `assert_approx_eq!(a, b)` within 1e-5, `assert_approx_eq!(a, b, tolerance)`, or
/// `assert_approx_eq!(a, b, rel r)` within `r * (1 + max(|a|, |b|))`. The message names both
/// expressions, their values and their distance.
#[macro_export]
macro_rules! assert_approx_eq {
    ($a:expr, $b:expr $(,)?) => {
        $crate::assert_approx_eq!($a, $b, 1e-5)
    };
    ($a:expr, $b:expr, rel $relative:expr $(,)?) => {{
        let (a, b) = ($a, $b);
        let tolerance = $crate::approx::relative_tolerance(a, b, $relative);
        $crate::assert_approx_eq!(@check a, b, tolerance, $a, $b)
    }};
    ($a:expr, $b:expr, $tolerance:expr $(,)?) => {{
        let (a, b) = ($a, $b);
        let tolerance: f64 = $tolerance;
        $crate::assert_approx_eq!(@check a, b, tolerance, $a, $b)
    }};
    (@check $a:ident, $b:ident, $tolerance:ident, $ea:expr, $eb:expr) => {
        assert!(
            $crate::approx::approx_eq($a, $b, $tolerance),
            "assert_approx_eq!({}, {}): {:?} and {:?} are {} apart (tolerance {})",
            stringify!($ea),
            stringify!($eb),
            $a,
            $b,
            $crate::approx::ApproxEq::distance($a, $b),
            $tolerance,
        )
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_and_vectors_within_the_tolerance_pass() {
        assert_approx_eq!(1.0_f32, 1.000_001);
        assert_approx_eq!(2.0_f64, 2.05, 0.1);
        assert_approx_eq!(Vec3::new(1.0, 2.0, 3.0), Vec3::new(1.0, 2.0, 3.000_001));
        assert_approx_eq!(1000.0_f32, 1000.005, rel 1e-5);
    }

    #[test]
    fn far_values_and_nan_are_not_close() {
        assert!(!approx_eq(1.0_f32, 1.1, 1e-3));
        assert!(!approx_eq(Vec2::ZERO, Vec2::ONE, 1.0));
        assert!(!approx_eq(f64::NAN, f64::NAN, 1.0));
        assert!(approx_eq(Vec4::ONE, Vec4::ONE, 0.0));
        assert!(!approx_eq(
            1000.0_f32,
            1000.1,
            relative_tolerance(1000.0_f32, 1000.1, 1e-5)
        ));
    }

    #[test]
    #[should_panic(expected = "are 0.5 apart")]
    fn the_assertion_names_the_distance() {
        assert_approx_eq!(DVec3::ZERO, DVec3::new(0.0, 0.5, 0.0), 0.1);
    }
}
