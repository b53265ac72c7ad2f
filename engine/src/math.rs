//! The engine's transcendental functions: one implementation on every platform.
//!
//! `f32::sin`, `f64::exp` and the like call the C library of the platform (glibc, musl, the
//! macOS or Windows one), and those round the last bit differently: the same script would
//! write different glb bytes on Linux, in the browser (emscripten's musl) or after a glibc
//! upgrade. Every crate of the workspace calls these instead (`clippy.toml` refuses the std
//! methods); they are the `libm` crate's pure Rust ports of musl's functions, so a result
//! depends only on its input. glam is built with its `libm` feature for the same reason.
//!
//! The functions are generic over [`Real`] (`f32` and `f64`): `math::sin(x)` takes and
//! returns the type of `x`. The exact operations (`sqrt`, `mul_add`, `floor`, `abs`, ...)
//! are IEEE-specified, equal everywhere, and stay the std methods.

/// `f32` or `f64`: the floating-point types the functions of [`crate::math`] accept.
pub trait Real: Copy {
    /// Sine (radians).
    fn sin_(self) -> Self;
    /// Cosine (radians).
    fn cos_(self) -> Self;
    /// Sine and cosine at once.
    fn sin_cos_(self) -> (Self, Self);
    /// Tangent (radians).
    fn tan_(self) -> Self;
    /// Arcsine, in [-pi/2, pi/2].
    fn asin_(self) -> Self;
    /// Arccosine, in [0, pi].
    fn acos_(self) -> Self;
    /// Arctangent, in [-pi/2, pi/2].
    fn atan_(self) -> Self;
    /// Four-quadrant arctangent of `self / x`.
    fn atan2_(self, x: Self) -> Self;
    /// Hyperbolic sine.
    fn sinh_(self) -> Self;
    /// Hyperbolic cosine.
    fn cosh_(self) -> Self;
    /// Hyperbolic tangent.
    fn tanh_(self) -> Self;
    /// e^self.
    fn exp_(self) -> Self;
    /// 2^self.
    fn exp2_(self) -> Self;
    /// e^self - 1, precise near 0.
    fn exp_m1_(self) -> Self;
    /// Natural logarithm.
    fn ln_(self) -> Self;
    /// ln(1 + self), precise near 0.
    fn ln_1p_(self) -> Self;
    /// Base-2 logarithm.
    fn log2_(self) -> Self;
    /// Base-10 logarithm.
    fn log10_(self) -> Self;
    /// self^e.
    fn powf_(self, e: Self) -> Self;
    /// Cube root.
    fn cbrt_(self) -> Self;
    /// sqrt(self² + y²) without overflow.
    fn hypot_(self, y: Self) -> Self;
    /// Remainder of self / y with the sign of self (C's `fmod`).
    fn fmod_(self, y: Self) -> Self;
}

macro_rules! real {
    ($t:ty, $sin:ident, $cos:ident, $sincos:ident, $tan:ident, $asin:ident, $acos:ident,
     $atan:ident, $atan2:ident, $sinh:ident, $cosh:ident, $tanh:ident, $exp:ident,
     $exp2:ident, $expm1:ident, $log:ident, $log1p:ident, $log2:ident, $log10:ident,
     $pow:ident, $cbrt:ident, $hypot:ident, $fmod:ident) => {
        impl Real for $t {
            #[inline]
            fn sin_(self) -> Self {
                libm::$sin(self)
            }
            #[inline]
            fn cos_(self) -> Self {
                libm::$cos(self)
            }
            #[inline]
            fn sin_cos_(self) -> (Self, Self) {
                libm::$sincos(self)
            }
            #[inline]
            fn tan_(self) -> Self {
                libm::$tan(self)
            }
            #[inline]
            fn asin_(self) -> Self {
                libm::$asin(self)
            }
            #[inline]
            fn acos_(self) -> Self {
                libm::$acos(self)
            }
            #[inline]
            fn atan_(self) -> Self {
                libm::$atan(self)
            }
            #[inline]
            fn atan2_(self, x: Self) -> Self {
                libm::$atan2(self, x)
            }
            #[inline]
            fn sinh_(self) -> Self {
                libm::$sinh(self)
            }
            #[inline]
            fn cosh_(self) -> Self {
                libm::$cosh(self)
            }
            #[inline]
            fn tanh_(self) -> Self {
                libm::$tanh(self)
            }
            #[inline]
            fn exp_(self) -> Self {
                libm::$exp(self)
            }
            #[inline]
            fn exp2_(self) -> Self {
                libm::$exp2(self)
            }
            #[inline]
            fn exp_m1_(self) -> Self {
                libm::$expm1(self)
            }
            #[inline]
            fn ln_(self) -> Self {
                libm::$log(self)
            }
            #[inline]
            fn ln_1p_(self) -> Self {
                libm::$log1p(self)
            }
            #[inline]
            fn log2_(self) -> Self {
                libm::$log2(self)
            }
            #[inline]
            fn log10_(self) -> Self {
                libm::$log10(self)
            }
            #[inline]
            fn powf_(self, e: Self) -> Self {
                libm::$pow(self, e)
            }
            #[inline]
            fn cbrt_(self) -> Self {
                libm::$cbrt(self)
            }
            #[inline]
            fn hypot_(self, y: Self) -> Self {
                libm::$hypot(self, y)
            }
            #[inline]
            fn fmod_(self, y: Self) -> Self {
                libm::$fmod(self, y)
            }
        }
    };
}

real!(
    f32, sinf, cosf, sincosf, tanf, asinf, acosf, atanf, atan2f, sinhf, coshf, tanhf, expf, exp2f,
    expm1f, logf, log1pf, log2f, log10f, powf, cbrtf, hypotf, fmodf
);
real!(
    f64, sin, cos, sincos, tan, asin, acos, atan, atan2, sinh, cosh, tanh, exp, exp2, expm1, log,
    log1p, log2, log10, pow, cbrt, hypot, fmod
);

/// Sine (radians).
#[inline]
pub fn sin<T: Real>(x: T) -> T {
    x.sin_()
}
/// Cosine (radians).
#[inline]
pub fn cos<T: Real>(x: T) -> T {
    x.cos_()
}
/// `(sin x, cos x)`.
#[inline]
pub fn sin_cos<T: Real>(x: T) -> (T, T) {
    x.sin_cos_()
}
/// Tangent (radians).
#[inline]
pub fn tan<T: Real>(x: T) -> T {
    x.tan_()
}
/// Arcsine, in [-pi/2, pi/2]; NaN outside [-1, 1].
#[inline]
pub fn asin<T: Real>(x: T) -> T {
    x.asin_()
}
/// Arccosine, in [0, pi]; NaN outside [-1, 1].
#[inline]
pub fn acos<T: Real>(x: T) -> T {
    x.acos_()
}
/// Arctangent, in [-pi/2, pi/2].
#[inline]
pub fn atan<T: Real>(x: T) -> T {
    x.atan_()
}
/// Four-quadrant arctangent of `y / x` (std's `y.atan2(x)`).
#[inline]
pub fn atan2<T: Real>(y: T, x: T) -> T {
    y.atan2_(x)
}
/// Hyperbolic sine.
#[inline]
pub fn sinh<T: Real>(x: T) -> T {
    x.sinh_()
}
/// Hyperbolic cosine.
#[inline]
pub fn cosh<T: Real>(x: T) -> T {
    x.cosh_()
}
/// Hyperbolic tangent.
#[inline]
pub fn tanh<T: Real>(x: T) -> T {
    x.tanh_()
}
/// e^x.
#[inline]
pub fn exp<T: Real>(x: T) -> T {
    x.exp_()
}
/// 2^x.
#[inline]
pub fn exp2<T: Real>(x: T) -> T {
    x.exp2_()
}
/// e^x - 1, precise near 0.
#[inline]
pub fn exp_m1<T: Real>(x: T) -> T {
    x.exp_m1_()
}
/// Natural logarithm.
#[inline]
pub fn ln<T: Real>(x: T) -> T {
    x.ln_()
}
/// ln(1 + x), precise near 0.
#[inline]
pub fn ln_1p<T: Real>(x: T) -> T {
    x.ln_1p_()
}
/// Base-2 logarithm.
#[inline]
pub fn log2<T: Real>(x: T) -> T {
    x.log2_()
}
/// Base-10 logarithm.
#[inline]
pub fn log10<T: Real>(x: T) -> T {
    x.log10_()
}
/// x^e (std's `x.powf(e)`).
#[inline]
pub fn powf<T: Real>(x: T, e: T) -> T {
    x.powf_(e)
}
/// Cube root.
#[inline]
pub fn cbrt<T: Real>(x: T) -> T {
    x.cbrt_()
}
/// sqrt(x² + y²) without overflow.
#[inline]
pub fn hypot<T: Real>(x: T, y: T) -> T {
    x.hypot_(y)
}
/// Remainder of x / y with the sign of x (C's `fmod`, Rust's `%` on floats).
#[inline]
pub fn fmod<T: Real>(x: T, y: T) -> T {
    x.fmod_(y)
}

#[cfg(test)]
#[allow(clippy::disallowed_methods)] // compared with the platform's C library on purpose
mod tests {
    use super::*;

    #[test]
    fn agree_with_the_platform_to_an_ulp_or_two() {
        // libm is musl's code: within an ulp or two of any decent C library, and exact
        // where the answer is exactly representable.
        for i in -200..=200 {
            let x = i as f64 * 0.037;
            let close = |a: f64, b: f64| (a - b).abs() <= 4.0 * f64::EPSILON * b.abs().max(1.0);
            assert!(close(sin(x), x.sin()), "sin {x}");
            assert!(close(cos(x), x.cos()), "cos {x}");
            assert!(close(atan2(x, 0.7), x.atan2(0.7)), "atan2 {x}");
            assert!(close(exp(x * 0.1), (x * 0.1).exp()), "exp {x}");
            assert!(close(cbrt(x), x.cbrt()), "cbrt {x}");
            let xf = x as f32;
            let closef = |a: f32, b: f32| (a - b).abs() <= 4.0 * f32::EPSILON * b.abs().max(1.0);
            assert!(closef(sin(xf), xf.sin()), "sinf {x}");
            assert!(closef(tan(xf * 0.3), (xf * 0.3).tan()), "tanf {x}");
            let (s, c) = sin_cos(xf);
            assert_eq!((s, c), (sin(xf), cos(xf)), "sincosf {x}");
        }
        assert_eq!(cos(0.0f32), 1.0);
        assert_eq!(powf(2.0f64, 10.0), 1024.0);
        assert_eq!(ln(1.0f32), 0.0);
        assert_eq!(fmod(7.5f64, 2.0), 1.5);
        assert!(acos(1.5f32).is_nan());
    }

    #[test]
    fn known_bits() {
        // Pinned results: these are the same on every platform (the point of the module).
        // Values at which glibc and musl round differently would show a regression first.
        assert_eq!(sin(1.0e6f64).to_bits(), (-0.34999350217129294f64).to_bits());
        assert_eq!(sin(0.5f32).to_bits(), 0.47942555f32.to_bits());
    }
}
