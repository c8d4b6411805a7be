//! The error scale of the adaptive steps: what a local error is measured against, per
//! component, so that every output holds relative accuracy in light and heavy damping.

use crate::physics::integrate::Tolerance;

/// The error scale of every adaptive method but Dopri5: component `i` that went from `y0`
/// to `y1` in a step has `sk = rtol m + atol min(1, max(m, floor_i))`, `m = max(|y0|, |y1|)`,
/// with the floor the largest penetration so far for `x` and 0 for `v`. The absolute part
/// counts fully only for a component as large as its Hertz scale (`delta_max`, `u`):
/// * the rate `v` is held to relative accuracy whatever its size, so that the slow creep out
///   of a heavily damped contact (`delta' ~ 1e-4 u`) keeps the relative accuracy of its speed,
///   and with it that of the contact time and the rebound;
/// * the penetration `x` is held to `atol` times the contact's own largest penetration (a
///   heavily damped contact reaches a few percent of the Hertz `delta_max`), not to relative
///   accuracy as it returns to 0 (the contact end is a root of `x`; its time is then as
///   accurate as `x` is against its rate).
///
/// Dopri5 keeps `atol + rtol m`, so that its results stay as they were. Never below the least
/// positive f64.
#[derive(Debug, Clone, Copy)]
pub(super) struct ErrorScale {
    pub(super) tol: Tolerance,
    /// The largest scaled penetration `x` so far.
    pub(super) x_peak: f64,
}

impl ErrorScale {
    /// `sk` of component `i` (0: `x`, 1: `v`) over a step from `y0` to `y1`.
    pub(super) fn sk(&self, i: usize, y0: f64, y1: f64) -> f64 {
        let m = y0.abs().max(y1.abs());
        let floor = if i == 0 { self.x_peak } else { 0.0 };
        (self.tol.rtol * m + self.tol.atol * m.max(floor).min(1.0)).max(f64::MIN_POSITIVE)
    }

    /// The RMS norm `sqrt(((e_x / sk_x)^2 + (e_v / sk_v)^2) / 2)` of a step's error `e` from
    /// `y0` to `y1`.
    pub(super) fn norm(&self, e: [f64; 2], y0: [f64; 2], y1: [f64; 2]) -> f64 {
        let mut sum = 0.0;
        for i in 0..2 {
            let q = e[i] / self.sk(i, y0[i], y1[i]);
            sum += q * q;
        }
        (sum / 2.0).sqrt()
    }
}
