//! The ratio map of a class whose pulses leave the Hertz parallelogram: measured/Hertz ratios
//! of the peak force and the duration, tabulated over one direction `s = a ln R + b ln u` of
//! the class's plane, that bend the class's envelope.
//!
//! With `x = ln R`, `y = ln u`, `A = ln F - ln c_F`, `B = ln t_c - ln c_t` a bent class's pulse is
//! `A = 2x + 6/5 y + phi_F(s)`, `B = x - 1/5 y + phi_t(s)`, `s = a x + b y`, with
//! `phi_F = ln(F/F_Hertz)` and `phi_t = ln(t_c/t_Hertz)` functions of `s` alone:
//!
//! - Thornton's yield ([`crate::thornton`]): the ratios depend on `u / V_y` alone, so
//!   `(a, b) = (0, 1)`; filled at scene build from the closed forms (`RatioMap::thornton`),
//!   with `phi_t` the duration the detector reads from the pulse's area,
//!   `ln(t_A / t_Hertz)` ([`crate::thornton::YieldRatios::area_duration`]).
//! - A damped law with a fixed damping coefficient (MSC Adams IMPACT with a fixed `c_max`):
//!   scaled by `delta* = (m u^2 / k)^(2/5)` and `t* = delta*/u`, the contact is
//!   `delta'' = -delta^1.5 - Lambda delta'` with `Lambda = c delta* / (m u)`, and with
//!   `m ~ R^3`, `k ~ R^(1/2)`: `ln Lambda = const - 2x - y/5`, so `(a, b) = (-2, -1/5)`;
//!   filled by the host from its integrator ([`RatioMap::new`]).
//!
//! Inverting the linear part, `x = (A - phi_F)/8 + 3 (B - phi_t)/4`,
//! `y = 5 (A - phi_F)/8 - 5 (B - phi_t)/4`, so `s` solves
//! `h(s) = s + p phi_F(s) + q phi_t(s) = p A + q B` with `p = a/8 + 5b/8`, `q = 3a/4 - 5b/4`:
//! a bounded search on `h`, which must increase (`h' >= 0.3125` on every segment). The map's
//! Jacobian is `|det d(A, B)/d(x, y)| = 8/5 h'(s)` (Hertz's `8/5` for flat ratios). The table
//! holds `phi_F` and `phi_t` at [`POINTS`] equally spaced `s`, linear between them and beyond
//! the ends (with the end segments' slopes).

use crate::error::Error;
#[cfg(feature = "plasticity")]
use crate::{error::positive, math::Backend, thornton::ratios_in};

/// Points of the table over the class's `s` range: 16 (128 bytes of ratios per class).
pub const POINTS: usize = 16;

/// Smallest slope `h'(s)` the map accepts (the Hertz slope is 1, Thornton's plastic limit
/// 0.625): a flatter table could not be inverted reliably.
const MIN_SLOPE: f32 = 0.3125;

/// Largest `|ln ratio|` a table holds: the ratios stay within `1e-3..1e3`.
const MAX_LN_RATIO: f32 = 6.907_755;

/// `phi_F(s)` and `phi_t(s)` of a bent class at `POINTS` equally spaced `s = a ln R + b ln u`.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RatioMap {
    /// `(a, b)`: `s = a ln R + b ln u` (R in m, u in m/s).
    direction: (f32, f32),
    /// `s` of the first point.
    start: f32,
    /// `s` of the last point (as given, so that the map can be written out bit for bit).
    end: f32,
    /// Spacing of the points in `s`.
    step: f32,
    /// `phi_F(s) = ln(F_max / F_Hertz)` at each point.
    ln_force: [f32; POINTS],
    /// `phi_t(s) = ln(t_c / t_Hertz)` at each point.
    ln_duration: [f32; POINTS],
}

/// The map at one point: its ratios, its Jacobian and how `(x, y)` move with `(A, B)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Local {
    /// `phi_F(s)`.
    pub ln_force: f32,
    /// `phi_t(s)`.
    pub ln_duration: f32,
    /// `|det d(ln F_max, ln t_c)/d(ln R, ln u)| = 8/5 h'(s)` (8/5 for Hertz).
    pub jacobian: f32,
    /// `(dx/dA, dx/dB)`: `(1/8, 3/4)` for Hertz.
    pub dx: (f32, f32),
    /// `(dy/dA, dy/dB)`: `(5/8, -5/4)` for Hertz.
    pub dy: (f32, f32),
}

impl RatioMap {
    /// The map over `s = a ln R + b ln u` (`direction = (a, b)`) from `s_range.0` to
    /// `s_range.1`, with `ln_force[k] = ln(F/F_Hertz)` and `ln_duration[k] = ln(t_c/t_Hertz)`
    /// at the `k`-th of [`POINTS`] equally spaced `s`. Refused with a typed error if a value is
    /// not finite, a ratio leaves `1e-3..1e3`, the range is empty, or `h(s)` does not increase
    /// by at least `0.3125` per unit of `s` on every segment (the map would not invert).
    pub fn new(
        direction: (f32, f32),
        s_range: (f32, f32),
        ln_force: [f32; POINTS],
        ln_duration: [f32; POINTS],
    ) -> Result<Self, Error> {
        let (a, b) = direction;
        if !(a.is_finite() && b.is_finite()) {
            return Err(Error::NonFinite("ratio map direction"));
        }
        let step = (s_range.1 - s_range.0) / (POINTS - 1) as f32;
        if !(step.is_finite() && step > 0.0) {
            return Err(Error::InvertedRange("ratio map s"));
        }
        let map = Self {
            direction,
            start: s_range.0,
            end: s_range.1,
            step,
            ln_force,
            ln_duration,
        };
        for (k, (f, t)) in ln_force.iter().zip(ln_duration.iter()).enumerate() {
            // NaN fails both comparisons.
            if !(f.abs() <= MAX_LN_RATIO && t.abs() <= MAX_LN_RATIO) {
                return Err(Error::OutOfRange("ratio map ratio (outside 1e-3..1e3)"));
            }
            let steep = k == 0 || (map.h_at(k) - map.h_at(k - 1)) >= MIN_SLOPE * step;
            if !steep {
                return Err(Error::OutOfRange("ratio map (not invertible)"));
            }
        }
        Ok(map)
    }

    /// The map of a class with Thornton's yield speed `yield_speed_m_s`
    /// ([`crate::thornton::yield_speed_in`]) over `ln_speed = (ln u0, ln u1)` (`u` in m/s):
    /// `s = ln u`, the ratios `force` and `area_duration` at `V_y / u`
    /// ([`crate::thornton::ratios_in`]).
    #[cfg(feature = "plasticity")]
    pub fn thornton<M: Backend>(yield_speed_m_s: f32, ln_speed: (f32, f32)) -> Result<Self, Error> {
        let ln_vy = M::ln(positive(yield_speed_m_s, "yield speed")?);
        // An empty range gives nonsense points, which `new` refuses.
        let (y0, y1) = ln_speed;
        let step = (y1 - y0) / (POINTS - 1) as f32;
        let (mut lf, mut lt) = ([0.0; POINTS], [0.0; POINTS]);
        for (k, (f, t)) in lf.iter_mut().zip(lt.iter_mut()).enumerate() {
            let r = ratios_in::<M>(M::exp(ln_vy - (y0 + k as f32 * step)))?;
            *f = M::ln(r.force);
            *t = M::ln(r.area_duration);
        }
        Self::new((0.0, 1.0), ln_speed, lf, lt)
            .map_err(|_| Error::OutOfRange("yield_pressure_pa (map not invertible)"))
    }

    /// `(a, b)` of `s = a ln R + b ln u`, as given to [`RatioMap::new`].
    pub fn direction(&self) -> (f32, f32) {
        self.direction
    }

    /// `s` of the first and last points, as given to [`RatioMap::new`].
    pub fn s_range(&self) -> (f32, f32) {
        (self.start, self.end)
    }

    /// `ln(F_max / F_Hertz)` at each point.
    pub fn ln_force(&self) -> &[f32; POINTS] {
        &self.ln_force
    }

    /// `ln(t_c / t_Hertz)` at each point.
    pub fn ln_duration(&self) -> &[f32; POINTS] {
        &self.ln_duration
    }

    /// `(p, q)` of `h(s) = s + p phi_F + q phi_t`.
    fn pq(&self) -> (f32, f32) {
        let (a, b) = self.direction;
        (0.125 * a + 0.625 * b, 0.75 * a - 1.25 * b)
    }

    /// `h` at point `k` (0 past the table).
    fn h_at(&self, k: usize) -> f32 {
        let (p, q) = self.pq();
        let f = self.ln_force.get(k).copied().unwrap_or(0.0);
        let t = self.ln_duration.get(k).copied().unwrap_or(0.0);
        self.start + k as f32 * self.step + p * f + q * t
    }

    /// `s = a x + b y` of the point `(x, y) = (ln R, ln u)`.
    pub fn s(&self, x: f32, y: f32) -> f32 {
        self.direction.0 * x + self.direction.1 * y
    }

    /// The segment `k` (0..=POINTS-2) that holds `s`, the ends extended.
    fn segment(&self, s: f32) -> usize {
        let t = (s - self.start) / self.step;
        // NaN and negative go to 0; `as` saturates.
        (t.max(0.0) as usize).min(POINTS - 2)
    }

    /// The ratios, the Jacobian and the inverse's slopes at `s`, linear on the segment that
    /// holds `s` (see the module docs: with `j = h'(s)`, `ds = (p dA + q dB) / j`,
    /// `dx = (dA - phi_F' ds)/8 + 3 (dB - phi_t' ds)/4`, `dy = 5 (dA - phi_F' ds)/8 - 5 (dB - phi_t' ds)/4`).
    pub fn local(&self, s: f32) -> Local {
        let (f, t, w) = self.on_segment(s);
        let (df, dt) = ((f[1] - f[0]) / self.step, (t[1] - t[0]) / self.step);
        let (p, q) = self.pq();
        let j = 1.0 + p * df + q * dt;
        let (kx, ky) = ((0.125 * df + 0.75 * dt) / j, (0.625 * df - 1.25 * dt) / j);
        Local {
            ln_force: f[0] + w * (f[1] - f[0]),
            ln_duration: t[0] + w * (t[1] - t[0]),
            jacobian: 1.6 * j,
            dx: (0.125 - kx * p, 0.75 - kx * q),
            dy: (0.625 - ky * p, -1.25 - ky * q),
        }
    }

    /// The segment that holds `s` (the ends extended): `phi_F` and `phi_t` at its two points,
    /// and where `s` lies on it (0 at its first point, 1 at its second).
    fn on_segment(&self, s: f32) -> ([f32; 2], [f32; 2], f32) {
        let k = self.segment(s);
        let pair = |v: &[f32; POINTS]| {
            let lo = v.get(k).copied().unwrap_or(0.0);
            [lo, v.get(k + 1).copied().unwrap_or(lo)]
        };
        let w = (s - self.start) / self.step - k as f32;
        (pair(&self.ln_force), pair(&self.ln_duration), w)
    }

    /// `(phi_F(s), phi_t(s))`, linear on the segment that holds `s` (without the slopes of
    /// [`RatioMap::local`]: the forward map and the inverse need only the values).
    fn ratios_at(&self, s: f32) -> (f32, f32) {
        let (f, t, w) = self.on_segment(s);
        (f[0] + w * (f[1] - f[0]), t[0] + w * (t[1] - t[0]))
    }

    /// `(phi_F, phi_t)` at the point `(x, y) = (ln R, ln u)`.
    pub fn forward(&self, x: f32, y: f32) -> (f32, f32) {
        self.ratios_at(self.s(x, y))
    }

    /// The `s` with `h(s) = v`: a binary search over the points (4 steps), then the segment's
    /// line (the end segments extended).
    fn s_for(&self, v: f32) -> f32 {
        let (mut lo, mut hi) = (0usize, POINTS - 1);
        while hi - lo > 1 {
            let mid = (lo + hi) / 2;
            if v >= self.h_at(mid) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let (h0, h1) = (self.h_at(lo), self.h_at(lo + 1));
        self.start + (lo as f32 + (v - h0) / (h1 - h0)) * self.step
    }

    /// `(x, y, s)` with `A = 2x + 6/5 y + phi_F(s)`, `B = x - y/5 + phi_t(s)` (`A`, `B` the
    /// observation's `ln F - ln c_F`, `ln t_c - ln c_t`): the exact inverse of
    /// [`RatioMap::forward`] on the piecewise-linear table.
    pub fn invert(&self, a: f32, b: f32) -> (f32, f32, f32) {
        let (p, q) = self.pq();
        let s = self.s_for(p * a + q * b);
        let (pf, pt) = self.ratios_at(s);
        let (fa, fb) = (a - pf, b - pt);
        (0.125 * fa + 0.75 * fb, 0.625 * fa - 1.25 * fb, s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    #[cfg(feature = "plasticity")]
    use crate::math::DefaultBackend as M;

    /// Far below yield (`V_y` above the range) the Thornton map is Hertz's: flat ratios,
    /// Jacobian 8/5, Hertz's inverse slopes; a yielding map inverts its own forward map to the
    /// point it came from, and its Jacobian lies between the plastic limit and Hertz's.
    #[cfg(feature = "plasticity")]
    #[test]
    fn thornton_elastic_limit_and_inverse() {
        let range = (0.0, libm::logf(5.0));
        let Ok(elastic) = RatioMap::thornton::<M>(10.0, range) else {
            unreachable!("valid")
        };
        for y in [-0.5, 0.3, 1.2, 2.0] {
            let l = elastic.local(y);
            assert!(l.ln_force == 0.0 && l.ln_duration == 0.0, "{l:?}");
            assert!(
                (l.jacobian - 1.6).abs() < 1e-6 && l.dx == (0.125, 0.75),
                "{l:?}"
            );
            assert!(l.dy == (0.625, -1.25), "{l:?}");
        }
        let Ok(map) = RatioMap::thornton::<M>(0.006, range) else {
            unreachable!("valid")
        };
        for y in [-0.7, 0.0, 0.41, 1.0, 1.6, 2.3] {
            let (x, _) = (-3.5f32, 0);
            let (f, t) = map.forward(x, y);
            let (xb, yb, _) = map.invert(2.0 * x + 1.2 * y + f, x - 0.2 * y + t);
            assert!(
                (xb - x).abs() < 2e-5 && (yb - y).abs() < 2e-5,
                "{y} -> {yb}"
            );
            let j = map.local(y).jacobian;
            assert!(j > 1.0 && j < 1.6, "{j}");
        }
        for bad in [0.0, -1.0, f32::NAN, f32::INFINITY] {
            assert!(RatioMap::thornton::<M>(bad, range).is_err());
        }
        assert!(RatioMap::thornton::<M>(0.006, (1.0, 1.0)).is_err());
    }

    /// A map along `(a, b) = (-2, -1/5)` with ratios linear in `s` has constant slopes: its
    /// Jacobian is the closed-form determinant `|det [[2 + a f, 6/5 + b f], [1 + a g,
    /// -1/5 + b g]]|` (`f`, `g` the slopes of `phi_F`, `phi_t`), its inverse slopes are the
    /// inverse of that matrix, and forward then inverse returns the point.
    #[test]
    fn linear_ratios_give_the_closed_form_jacobian() {
        let (a, b) = (-2.0f32, -0.2f32);
        let (f, g) = (-0.12f32, -0.05f32);
        let lf: [f32; POINTS] = core::array::from_fn(|k| f * k as f32 * 0.2);
        let lt: [f32; POINTS] = core::array::from_fn(|k| g * k as f32 * 0.2);
        let Ok(map) = RatioMap::new((a, b), (0.0, 3.0), lf, lt) else {
            unreachable!("valid")
        };
        let m = [[2.0 + a * f, 1.2 + b * f], [1.0 + a * g, -0.2 + b * g]];
        let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
        for (x, y) in [(-4.0f32, 0.1f32), (-3.2, 1.5), (-4.5, 0.8)] {
            let s = map.s(x, y);
            let l = map.local(s);
            assert!((l.jacobian - det.abs()).abs() < 1e-4, "{l:?} {det}");
            assert!((l.dx.0 - m[1][1] / det).abs() < 1e-4, "{l:?}");
            assert!((l.dx.1 + m[0][1] / det).abs() < 1e-4, "{l:?}");
            assert!((l.dy.0 + m[1][0] / det).abs() < 1e-4, "{l:?}");
            assert!((l.dy.1 - m[0][0] / det).abs() < 1e-4, "{l:?}");
            let (pf, pt) = map.forward(x, y);
            let (xb, yb, _) = map.invert(2.0 * x + 1.2 * y + pf, x - 0.2 * y + pt);
            assert!(
                (xb - x).abs() < 1e-4 && (yb - y).abs() < 1e-4,
                "{x},{y} -> {xb},{yb}"
            );
        }
    }

    /// Bad tables are typed errors: NaN, a ratio past 1e3, an empty range, a table that
    /// folds (h decreasing).
    #[test]
    fn bad_tables_are_refused() {
        let flat = [0.0f32; POINTS];
        assert!(RatioMap::new((-2.0, -0.2), (0.0, 1.0), flat, flat).is_ok());
        let mut nan = flat;
        nan[3] = f32::NAN;
        assert!(RatioMap::new((-2.0, -0.2), (0.0, 1.0), nan, flat).is_err());
        let mut big = flat;
        big[0] = 7.0;
        assert!(RatioMap::new((-2.0, -0.2), (0.0, 1.0), flat, big).is_err());
        assert!(RatioMap::new((-2.0, -0.2), (1.0, 1.0), flat, flat).is_err());
        assert!(RatioMap::new((f32::NAN, -0.2), (0.0, 1.0), flat, flat).is_err());
        // p = -3/8: phi_F rising by 4 per unit s makes h fall.
        let fold: [f32; POINTS] = core::array::from_fn(|k| 4.0 * k as f32 / 15.0);
        assert!(RatioMap::new((-2.0, -0.2), (0.0, 1.0), fold, flat).is_err());
    }
}
