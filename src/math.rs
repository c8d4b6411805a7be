//! The math backend: every transcendental function the kernel uses goes through a
//! [`Backend`], chosen at compile time as a type parameter (default [`DefaultBackend`]).
//!
//! - [`Libm`]: `libm` 0.2, within about 1 ulp; the default.
//! - [`Micromath`]: `micromath` 2.1 for `sqrt` (refined by one Newton step: micromath alone is
//!   up to 6 % off), `exp`, and the mantissa part of `ln`. `ln` is range-reduced here
//!   (`x = m 2^e`, `m` in `[1, 2)`) because micromath's own `ln` is off by up to 0.12 for
//!   `x < 1`, which is exactly where penetrations in metres and durations in seconds lie.
//!   `powf(x, y) = exp(y ln x)`. Non-finite and edge inputs fall back to libm.
//!
//! The cargo feature `micromath` makes [`Micromath`] the default; both backends are always
//! compiled, so a host tool can compare them in one binary. `erf`, `sin`, `cos` come from libm
//! in both (they run once per pulse, never per sample).

/// The transcendental functions the kernel needs, all `f32 -> f32`.
pub trait Backend: Copy + Clone + core::fmt::Debug + Default + PartialEq + 'static {
    /// Backend name for reports.
    const NAME: &'static str;
    /// Square root; NaN for `x < 0`.
    fn sqrt(x: f32) -> f32;
    /// `e^x`.
    fn exp(x: f32) -> f32;
    /// Natural logarithm; `-inf` at 0, NaN for `x < 0`.
    fn ln(x: f32) -> f32;
    /// `x^y` for `x > 0`.
    fn powf(x: f32, y: f32) -> f32;
    /// `x^(3/2) = x sqrt(x)`.
    #[inline]
    fn pow_3_2(x: f32) -> f32 {
        x * Self::sqrt(x)
    }
}

/// The accurate backend: `libm`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Libm;

impl Backend for Libm {
    const NAME: &'static str = "libm";
    #[inline]
    fn sqrt(x: f32) -> f32 {
        libm::sqrtf(x)
    }
    #[inline]
    fn exp(x: f32) -> f32 {
        libm::expf(x)
    }
    #[inline]
    fn ln(x: f32) -> f32 {
        libm::logf(x)
    }
    #[inline]
    fn powf(x: f32, y: f32) -> f32 {
        libm::powf(x, y)
    }
}

/// The fast backend: `micromath`, with the fixes described in the module docs.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Micromath;

impl Backend for Micromath {
    const NAME: &'static str = "micromath";
    #[inline]
    fn sqrt(x: f32) -> f32 {
        if !(x > 0.0 && x.is_finite()) {
            return libm::sqrtf(x);
        }
        let y = micromath::F32Ext::sqrt(x);
        0.5 * (y + x / y)
    }
    #[inline]
    fn exp(x: f32) -> f32 {
        if !(-87.0..=88.0).contains(&x) {
            return libm::expf(x);
        }
        micromath::F32Ext::exp(x)
    }
    #[inline]
    fn ln(x: f32) -> f32 {
        if !(x.is_normal() && x > 0.0) {
            return libm::logf(x);
        }
        // x = m 2^e with m in [1, 2): the exponent from the bits, the mantissa's ln from
        // micromath.
        let bits = x.to_bits();
        let e = ((bits >> 23) & 0xff) as i32 - 127;
        let m = f32::from_bits((bits & 0x007f_ffff) | 0x3f80_0000);
        e as f32 * core::f32::consts::LN_2 + micromath::F32Ext::ln(m)
    }
    #[inline]
    fn powf(x: f32, y: f32) -> f32 {
        Self::exp(y * Self::ln(x))
    }
}

/// The backend the `micromath` feature selects: [`Micromath`] with it, [`Libm`] without.
#[cfg(feature = "micromath")]
pub type DefaultBackend = Micromath;
/// The backend the `micromath` feature selects: [`Micromath`] with it, [`Libm`] without.
#[cfg(not(feature = "micromath"))]
pub type DefaultBackend = Libm;

/// Name of the default backend, for reports.
pub const BACKEND: &str = DefaultBackend::NAME;

/// Standard normal cumulative distribution `Phi(x) = (1 + erf(x / sqrt 2)) / 2` (libm).
#[inline]
pub fn normal_cdf(x: f32) -> f32 {
    0.5 * (1.0 + libm::erff(x * core::f32::consts::FRAC_1_SQRT_2))
}

/// `sin(x)` (libm in both backends).
#[inline]
pub fn sin(x: f32) -> f32 {
    libm::sinf(x)
}

/// `cos(x)` (libm in both backends).
#[inline]
pub fn cos(x: f32) -> f32 {
    libm::cosf(x)
}
