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
//! compiled, so a host tool can compare them in one binary. `erf` comes from libm in both, and
//! [`sin_cos`] is this module's own polynomial (both run once per pulse, never per sample).

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
    /// `x^(2/3)` for `x > 0`.
    #[inline]
    fn pow_2_3(x: f32) -> f32 {
        Self::powf(x, 2.0 / 3.0)
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
    /// `cbrt(x)^2` with [`cbrt`] (libm's `cbrtf` and `powf` work in f64, which a Cortex-M4F
    /// emulates in software).
    #[inline]
    fn pow_2_3(x: f32) -> f32 {
        let c = cbrt(x);
        c * c
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
        // micromath's bit trick assumes a normal float: subnormals go to libm.
        if !(x.is_normal() && x > 0.0) {
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

/// Where the fractional index `at` falls in a table of `points >= 2` entries: `(i, f)` with
/// `i <= points - 2` and the weight `f` of entry `i + 1`, `at` clamped to `[0, points - 1]`
/// (a non-finite `at` reads entry 0). With [`interpolate`], a table linear between its points
/// and held beyond them.
#[inline]
pub fn table_position(at: f32, points: usize) -> (usize, f32) {
    let last = points.saturating_sub(1) as f32;
    let at = if at.is_finite() {
        at.clamp(0.0, last)
    } else {
        0.0
    };
    let i = (at as usize).min(points.saturating_sub(2));
    (i, at - i as f32)
}

/// `t[i] + (t[i + 1] - t[i]) f` at a [`table_position`] `(i, f)`; a missing entry reads 0.
#[inline]
pub fn interpolate(t: &[f32], (i, f): (usize, f32)) -> f32 {
    let (a, b) = (
        t.get(i).copied().unwrap_or(0.0),
        t.get(i + 1).copied().unwrap_or(0.0),
    );
    a + (b - a) * f
}

/// `P(a < Z < b) = Phi(b) - Phi(a)` of a standard normal `Z`, with relative precision in
/// both tails: when `a` and `b` lie on the same side of 0 the difference is taken between the
/// tails `Q(|x|) = erfc(|x| / sqrt 2) / 2` (libm), which keep their digits down to about
/// `1e-38` (`x` near 13), where `1 + erf` has lost them all by `x = -5.5`. 0 for `b <= a`.
#[inline]
pub fn normal_interval(a: f32, b: f32) -> f32 {
    let q = |x: f32| 0.5 * libm::erfcf(x * core::f32::consts::FRAC_1_SQRT_2);
    let p = if a >= 0.0 {
        q(a) - q(b)
    } else if b <= 0.0 {
        q(-b) - q(-a)
    } else {
        1.0 - q(-a) - q(b)
    };
    if p > 0.0 { p } else { 0.0 }
}

/// Cube root of `x` in f32 only: for `|x|` normal, an initial guess from the exponent bits
/// (`bits / 3 + 709921077`, within 4 %), then three Newton steps `c -= (c - x / c^2) / 3`
/// (quadratic: 4e-2, 2e-3, 4e-6, then f32 rounding; error <= 2.4e-7 relative, tested). A
/// subnormal `|x|` is scaled by `2^24` into the normal range and its root back by `2^-8`;
/// `cbrt(-x) = -cbrt(x)`; zero and non-finite `x` return `x`. (libm's `cbrtf` works in f64,
/// which a Cortex-M4F emulates in software, linking the soft double-precision arithmetic.)
#[inline]
pub fn cbrt(x: f32) -> f32 {
    if x == 0.0 || !x.is_finite() {
        return x;
    }
    let a = x.abs();
    let (a, scale) = if a.is_normal() {
        (a, 1.0)
    } else {
        (a * 16_777_216.0, 1.0 / 256.0)
    };
    let mut c = f32::from_bits(a.to_bits() / 3 + 709_921_077);
    for _ in 0..3 {
        c -= (c - a / (c * c)) * (1.0 / 3.0);
    }
    if x < 0.0 { -c * scale } else { c * scale }
}

/// Fifth root of `x >= 0` in f32 only, as [`cbrt`] does the cube root: an initial guess from
/// the exponent bits (`bits / 5 + 852282573`, within 7 %), then four Newton steps
/// `c -= (c - x / c^4) / 5` (7e-2, 1e-2, 2e-4, 8e-8, then f32 rounding; error <= 2.4e-7
/// relative, tested). A subnormal `x` is scaled by `2^40` and its root back by `2^-8`; zero,
/// negative and non-finite `x` return `x`. It gives the Hertz law's `u^(4/5)` and `ratio^(2/5)`
/// without libm's `powf` (which works in f64, in software on a Cortex-M4F).
#[inline(never)]
pub fn fifth_root(x: f32) -> f32 {
    if x <= 0.0 || !x.is_finite() {
        return x;
    }
    let (a, scale) = if x.is_normal() {
        (x, 1.0)
    } else {
        (x * 1_099_511_627_776.0, 1.0 / 256.0)
    };
    let mut c = f32::from_bits(a.to_bits() / 5 + 852_282_573);
    for _ in 0..4 {
        let c2 = c * c;
        c -= (c - a / (c2 * c2)) * 0.2;
    }
    c * scale
}

/// `(sin x, cos x)` for `x` in `[0, pi]`, in f32 without libm: `cos` by reflection
/// (`cos x = -cos(pi - x)` above `pi/2`), then the Taylor series to `x^11` / `x^12` on
/// `[0, pi/2]` (the first terms left out, `x^13/13!` and `x^14/14!`, are at most `5.7e-8`
/// and `6.4e-9`, at `pi/2`; with f32 rounding the error is <= 3e-7, tested).
/// libm's `sinf`/`cosf` reduce the argument in f64, which a Cortex-M4F does in software.
/// Arguments outside `[0, pi]` are clamped.
#[inline]
pub fn sin_cos(x: f32) -> (f32, f32) {
    use core::f32::consts::{FRAC_PI_2, PI};
    let x = x.max(0.0).min(PI);
    let (r, sign) = if x > FRAC_PI_2 {
        (PI - x, -1.0)
    } else {
        (x, 1.0)
    };
    let r2 = r * r;
    let s = r
        * (1.0
            + r2 * (-1.0 / 6.0
                + r2 * (1.0 / 120.0
                    + r2 * (-1.0 / 5040.0 + r2 * (1.0 / 362_880.0 - r2 / 39_916_800.0)))));
    let c = 1.0
        + r2 * (-0.5
            + r2 * (1.0 / 24.0
                + r2 * (-1.0 / 720.0
                    + r2 * (1.0 / 40_320.0 + r2 * (-1.0 / 3_628_800.0 + r2 / 479_001_600.0)))));
    (s, sign * c)
}

/// `(sin x, cos x)` for any finite `x`: reduced to `[-pi, pi]` by whole turns (in f32: the
/// rounding of `x / TAU`, of the whole turns times `TAU` and `TAU`'s own add an error that
/// grows as at most `2.4e-7 |x|` beside [`sin_cos`]'s `3e-7`, the bound the tests hold it
/// to), then [`sin_cos`] on `|x|`
/// (`sin` is odd, `cos` even). Past `2^31` turns, or not finite: `(0, 1)`.
#[inline(never)]
pub fn sin_cos_any(x: f32) -> (f32, f32) {
    use core::f32::consts::{PI, TAU};
    let turns = x / TAU;
    if !turns.is_finite() || turns.abs() >= 2.0e9 {
        return (0.0, 1.0);
    }
    // The nearest whole turn, without libm.
    let whole = (turns + if turns < 0.0 { -0.5 } else { 0.5 }) as i32 as f32;
    let r = (x - whole * TAU).max(-PI).min(PI);
    let (s, c) = sin_cos(r.abs());
    (if r < 0.0 { -s } else { s }, c)
}

#[cfg(test)]
mod tests {
    #[test]
    fn sin_cos_matches_f64() {
        let mut worst = 0.0f64;
        for i in 0..=10_000 {
            let x = core::f64::consts::PI * i as f64 / 10_000.0;
            let (s, c) = super::sin_cos(x as f32);
            worst = worst
                .max((s as f64 - x.sin()).abs())
                .max((c as f64 - x.cos()).abs());
        }
        assert!(worst < 3e-7, "{worst}");
    }

    #[test]
    fn sin_cos_any_matches_f64_over_many_turns() {
        let mut worst = 0.0f64;
        for i in -20_000..=20_000 {
            let x = (i as f32) * 0.0031;
            let (s, c) = super::sin_cos_any(x);
            let xd = x as f64;
            let err = (s as f64 - xd.sin()).abs().max((c as f64 - xd.cos()).abs());
            // f32 rounding of the reduction: a few ulps of |x|.
            worst = worst.max(err / (3e-7 + 2.4e-7 * xd.abs()));
        }
        assert!(worst <= 1.0, "{worst}");
        assert_eq!(super::sin_cos_any(f32::NAN), (0.0, 1.0));
    }

    #[test]
    fn cbrt_matches_f64() {
        let mut worst = 0.0f64;
        for i in 0..=100_000 {
            let x = 10f64.powf(-30.0 + 60.0 * i as f64 / 100_000.0);
            let c = super::cbrt(x as f32) as f64;
            worst = worst.max((c / (x as f32 as f64).cbrt() - 1.0).abs());
        }
        assert!(worst < 2.4e-7, "{worst}");
    }

    #[test]
    fn fifth_root_matches_f64() {
        let mut worst = 0.0f64;
        for i in 0..=100_000 {
            let x = 10f64.powf(-44.0 + 82.0 * i as f64 / 100_000.0) as f32;
            if x == 0.0 {
                continue;
            }
            let c = super::fifth_root(x) as f64;
            worst = worst.max((c / (x as f64).powf(0.2) - 1.0).abs());
        }
        assert!(worst < 2.4e-7, "{worst}");
        assert_eq!(super::fifth_root(0.0), 0.0);
        assert!(super::fifth_root(-1.0) < 0.0 && super::fifth_root(f32::NAN).is_nan());
        assert_eq!(super::fifth_root(f32::INFINITY), f32::INFINITY);
    }

    /// Subnormal, negative, zero and non-finite arguments against f64's `cbrt`.
    #[test]
    fn cbrt_edges_match_f64() {
        let mut worst = 0.0f64;
        for i in 1..=10_000u32 {
            // Subnormals from the smallest (bits 1) to just below f32::MIN_POSITIVE.
            let x = f32::from_bits(i * 838);
            for x in [x, -x, x * 1e6, -(x * 1e6)] {
                let want = (x as f64).cbrt();
                worst = worst.max((super::cbrt(x) as f64 / want - 1.0).abs());
            }
        }
        assert!(worst < 2.4e-7, "{worst}");
        assert_eq!(super::cbrt(0.0).to_bits(), 0.0f32.to_bits());
        assert_eq!(super::cbrt(-0.0).to_bits(), (-0.0f32).to_bits());
        assert_eq!(super::cbrt(f32::INFINITY), f32::INFINITY);
        assert_eq!(super::cbrt(f32::NEG_INFINITY), f32::NEG_INFINITY);
        assert!(super::cbrt(f32::NAN).is_nan());
        assert!((super::cbrt(-8.0) + 2.0).abs() < 1e-6);
    }
}
