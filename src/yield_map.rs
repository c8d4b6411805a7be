//! The yield map of a class whose contact yields: Thornton's ratios to the Hertz impact,
//! tabulated over `y = ln u`, that bend the class's envelope.
//!
//! With `x = ln R`, `y = ln u` a yielding class's pulse is
//! `ln F = ln c_F + 2x + 6/5 y + phi_F(y)`, `ln t_c = ln c_t + x - 1/5 y + phi_t(y)`, with
//! `phi_F = ln(F*/F_Hertz)` and `phi_t = ln(t_c/t_Hertz)` at `s = V_y e^(-y)`
//! ([`crate::thornton`]; they do not depend on `R`). Eliminating `x`:
//! `ln F - 2 ln t_c - (ln c_F - 2 ln c_t) = h(y) = 8/5 y + phi_F(y) - 2 phi_t(y)`, increasing in
//! `y` (slope 1.6 elastic, about 1.1 deep in the plastic range). The map holds `h` and `phi_t`
//! at [`POINTS`] equally spaced `y` over the class's speed range, filled once at scene build, and
//! is linear between them (and beyond the ends, with the end segments' slopes). So a pulse
//! inverts by a bounded search for `y` on `h`, then `x = ln t_c - ln c_t + y/5 - phi_t(y)`, and
//! the map's Jacobian `|d(ln F, ln t_c)/d(x, y)| = h'(y)` replaces Hertz's constant `8/5`.
//! Without yield (`s >= 1` everywhere) the map is exactly the Hertz parallelogram.

use crate::error::{Error, positive};
use crate::math::Backend;
use crate::thornton::ratios_in;

/// Points of the table over the class's `ln u` range: 16 (128 bytes per class).
pub const POINTS: usize = 16;

/// Smallest slope `h'(y)` the map accepts (the Hertz slope is 1.6, the plastic limit 1.0):
/// a flatter table could not be inverted reliably.
const MIN_SLOPE: f32 = 0.5;

/// `h(y)` and `phi_t(y)` of a yielding class at `POINTS` equally spaced `y = ln u`.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct YieldMap {
    /// `ln u` of the first point (u in m/s).
    ln_speed_start: f32,
    /// Spacing of the points in `ln u`.
    ln_speed_step: f32,
    /// `h(y) = 8/5 y + ln(F*/F_Hertz) - 2 ln(t_c/t_Hertz)` at each point.
    h: [f32; POINTS],
    /// `phi_t(y) = ln(t_c/t_Hertz)` at each point.
    phi_t: [f32; POINTS],
}

/// Where `y` falls on the table: the segment's values and slopes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Local {
    /// `h(y)`.
    pub h: f32,
    /// `phi_t(y)`.
    pub phi_t: f32,
    /// `h'(y)`: the map's Jacobian `|det d(ln F, ln t_c)/d(ln R, ln u)|` (8/5 for Hertz).
    pub jacobian: f32,
    /// `phi_t'(y)`.
    pub phi_t_slope: f32,
}

impl YieldMap {
    /// The map of a class with yield speed `yield_speed_m_s`
    /// ([`crate::thornton::yield_speed_in`]) over `ln_speed = (ln u0, ln u1)` (`u` in m/s).
    /// Refused with a typed error if a ratio leaves f32 or `h` is not increasing by at least
    /// `0.5` per unit of `ln u` on every segment.
    pub fn new<M: Backend>(yield_speed_m_s: f32, ln_speed: (f32, f32)) -> Result<Self, Error> {
        let ln_vy = M::ln(positive(yield_speed_m_s, "yield speed")?);
        let (y0, y1) = ln_speed;
        let step = (y1 - y0) / (POINTS - 1) as f32;
        if !(step.is_finite() && step > 0.0) {
            return Err(Error::InvertedRange("speed_m_s"));
        }
        let mut map = Self {
            ln_speed_start: y0,
            ln_speed_step: step,
            h: [0.0; POINTS],
            phi_t: [0.0; POINTS],
        };
        for (k, (h, phi_t)) in map.h.iter_mut().zip(map.phi_t.iter_mut()).enumerate() {
            let y = y0 + k as f32 * step;
            let r = ratios_in::<M>(M::exp(ln_vy - y))?;
            *phi_t = M::ln(r.duration);
            *h = 1.6 * y + M::ln(r.force) - 2.0 * *phi_t;
        }
        for (a, b) in map.h.iter().zip(map.h.iter().skip(1)) {
            // NaN slopes are refused too.
            let steep = (b - a) >= MIN_SLOPE * step;
            if !steep {
                return Err(Error::OutOfRange("yield_pressure_pa (map not invertible)"));
            }
        }
        Ok(map)
    }

    /// The segment `k` (0..=POINTS-2) that holds `y`, the ends extended.
    fn segment(&self, y: f32) -> usize {
        let t = (y - self.ln_speed_start) / self.ln_speed_step;
        // NaN and negative go to 0; `as` saturates.
        (t.max(0.0) as usize).min(POINTS - 2)
    }

    /// `h`, `phi_t` and their slopes at `y = ln u`, linear on the segment that holds `y`.
    pub fn local(&self, y: f32) -> Local {
        let k = self.segment(y);
        let pair = |a: &[f32; POINTS]| {
            let lo = a.get(k).copied().unwrap_or(0.0);
            (lo, a.get(k + 1).copied().unwrap_or(lo))
        };
        let ((h0, h1), (p0, p1)) = (pair(&self.h), pair(&self.phi_t));
        let yk = self.ln_speed_start + k as f32 * self.ln_speed_step;
        let (dh, dp) = (
            (h1 - h0) / self.ln_speed_step,
            (p1 - p0) / self.ln_speed_step,
        );
        Local {
            h: h0 + dh * (y - yk),
            phi_t: p0 + dp * (y - yk),
            jacobian: dh,
            phi_t_slope: dp,
        }
    }

    /// The `y = ln u` with `h(y) = v`: a binary search over the points (4 steps), then the
    /// segment's line (the end segments extended).
    pub fn ln_speed_for(&self, v: f32) -> f32 {
        let (mut lo, mut hi) = (0usize, POINTS - 1);
        while hi - lo > 1 {
            let mid = (lo + hi) / 2;
            if self.h.get(mid).is_some_and(|&h| v >= h) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let h0 = self.h.get(lo).copied().unwrap_or(0.0);
        let h1 = self.h.get(lo + 1).copied().unwrap_or(h0 + 1.0);
        let yk = self.ln_speed_start + lo as f32 * self.ln_speed_step;
        yk + (v - h0) / (h1 - h0) * self.ln_speed_step
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::DefaultBackend as M;

    /// Far below yield (`V_y` above the range) the map is Hertz's: `h = 8/5 y`, `phi_t = 0`,
    /// Jacobian 8/5; a yielding map inverts its own `h` to the `y` it came from; bad inputs are
    /// typed errors.
    #[test]
    fn elastic_limit_inverse_and_errors() {
        let range = (0.0, libm::logf(5.0));
        let Ok(elastic) = YieldMap::new::<M>(10.0, range) else {
            unreachable!("valid")
        };
        for y in [-0.5, 0.3, 1.2, 2.0] {
            let l = elastic.local(y);
            assert!((l.h - 1.6 * y).abs() < 1e-5 && l.phi_t == 0.0, "{l:?}");
            assert!((l.jacobian - 1.6).abs() < 1e-5);
        }
        let Ok(map) = YieldMap::new::<M>(0.006, range) else {
            unreachable!("valid")
        };
        for y in [-0.7, 0.0, 0.41, 1.0, 1.6, 2.3] {
            let back = map.ln_speed_for(map.local(y).h);
            assert!((back - y).abs() < 1e-5, "{y} -> {back}");
            let j = map.local(y).jacobian;
            assert!(j > 1.0 && j < 1.6, "{j}");
        }
        for bad in [0.0, -1.0, f32::NAN, f32::INFINITY] {
            assert!(YieldMap::new::<M>(bad, range).is_err());
        }
        assert!(YieldMap::new::<M>(0.006, (1.0, 1.0)).is_err());
        assert!(map.ln_speed_for(f32::NAN).is_nan());
    }
}
