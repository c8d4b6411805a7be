//! The math backend: every transcendental function the kernel uses goes through here.
//!
//! Default: [`libm`] (errors <= 1 ulp-ish, see README). With the `micromath` feature, `sqrt`
//! (refined by one Newton step), `exp` and the mantissa part of `ln` come from `micromath`
//! (faster, less accurate). `ln` is
//! always range-reduced here (`x = m 2^e`, `m` in `[1, 2)`) because micromath's own `ln` is
//! off by up to 0.12 for `x < 1`, which is exactly where penetrations in metres and durations in
//! seconds lie. `erf` always comes from libm (micromath has none).

/// `ln 2`.
const LN_2: f32 = core::f32::consts::LN_2;

/// Square root. NaN for `x < 0`.
#[inline]
pub fn sqrt(x: f32) -> f32 {
    #[cfg(feature = "micromath")]
    {
        if x <= 0.0 || !x.is_finite() {
            return libm::sqrtf(x);
        }
        // micromath's estimate is up to 6 % off; one Newton step brings it to ~2e-3.
        let y = micromath::F32Ext::sqrt(x);
        0.5 * (y + x / y)
    }
    #[cfg(not(feature = "micromath"))]
    {
        libm::sqrtf(x)
    }
}

/// `e^x`.
#[inline]
pub fn exp(x: f32) -> f32 {
    #[cfg(feature = "micromath")]
    {
        if !(-87.0..=88.0).contains(&x) {
            return libm::expf(x);
        }
        micromath::F32Ext::exp(x)
    }
    #[cfg(not(feature = "micromath"))]
    {
        libm::expf(x)
    }
}

/// Natural logarithm. `-inf` for 0, NaN for `x < 0`.
#[inline]
pub fn ln(x: f32) -> f32 {
    #[cfg(feature = "micromath")]
    {
        if !(x.is_normal() && x > 0.0) {
            return libm::logf(x);
        }
        // x = m * 2^e with m in [1, 2): exponent from the bits, mantissa through micromath.
        let bits = x.to_bits();
        let e = ((bits >> 23) & 0xff) as i32 - 127;
        let m = f32::from_bits((bits & 0x007f_ffff) | 0x3f80_0000);
        e as f32 * LN_2 + micromath::F32Ext::ln(m)
    }
    #[cfg(not(feature = "micromath"))]
    {
        let _ = LN_2;
        libm::logf(x)
    }
}

/// `x^y` for `x > 0`, as `exp(y ln x)` (so both backends share the range reduction of [`ln`]).
#[inline]
pub fn powf(x: f32, y: f32) -> f32 {
    #[cfg(feature = "micromath")]
    {
        exp(y * ln(x))
    }
    #[cfg(not(feature = "micromath"))]
    {
        libm::powf(x, y)
    }
}

/// `x^(3/2)` written as `x sqrt(x)` (exact to the accuracy of [`sqrt`]).
#[inline]
pub fn pow_3_2(x: f32) -> f32 {
    x * sqrt(x)
}

/// Standard normal cumulative distribution `Phi(x) = (1 + erf(x / sqrt 2)) / 2` (libm).
#[inline]
pub fn normal_cdf(x: f32) -> f32 {
    0.5 * (1.0 + libm::erff(x * core::f32::consts::FRAC_1_SQRT_2))
}

/// `sin(x)` (libm in both backends: it runs once per pulse, not per sample).
#[inline]
pub fn sin(x: f32) -> f32 {
    libm::sinf(x)
}

/// `atan(x)` (libm in both backends).
#[inline]
pub fn atan(x: f32) -> f32 {
    libm::atanf(x)
}

/// `cos(x)` (libm in both backends).
#[inline]
pub fn cos(x: f32) -> f32 {
    libm::cosf(x)
}

/// Name of the compiled backend, for reports.
pub const BACKEND: &str = if cfg!(feature = "micromath") {
    "micromath"
} else {
    "libm"
};
