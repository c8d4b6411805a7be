//! The step-size controller: Dopri5's error-per-step control with Hairer's stabilisation,
//! or RK4's graded fixed steps.

use crate::physics::hertz64::HERTZ_TC_FACTOR;
use crate::physics::integrate::dopri5::dopri_step;
use crate::physics::integrate::rhs::{Rhs, Trial};
use crate::physics::integrate::rk4::rk4_step;
use crate::physics::integrate::{Limits, Method, SimError, Tolerance};

/// Dopri5's controller (Hairer's DOPRI5: beta = 0.04, safety 0.9, factors 0.2..10).
pub(super) const BETA: f64 = 0.04;
/// Safety factor of the step-size controller.
pub(super) const SAFE: f64 = 0.9;
/// Smallest step-size factor (`h_new >= FACMIN h`).
pub(super) const FACMIN: f64 = 0.2;
/// Largest step-size factor (`h_new <= FACMAX h`).
pub(super) const FACMAX: f64 = 10.0;
/// RK4's steps are graded down near first contact, up to scaled time `T1`.
pub(super) const T1: f64 = 1.0 / 16.0;

/// The step size and its controller: Dopri5's error-per-step control with Hairer's
/// stabilisation (`facold`), or RK4's graded fixed steps.
pub(super) struct StepControl {
    pub(super) method: Method,
    pub(super) tol: Tolerance,
    /// The next trial step (scaled time).
    pub(super) h: f64,
    /// Largest step.
    pub(super) hmax: f64,
    /// `0.2 - 0.75 BETA`, the exponent of the error in the controller's factor.
    pub(super) expo1: f64,
    /// ln of Hairer's `facold` (the last accepted error, at least 1e-4): the controller's
    /// factor `err^expo1 / facold^BETA` is one exp of logs, not two powf.
    pub(super) ln_facold: f64,
    /// Whether the last trial was rejected (then the step may not grow).
    pub(super) last_rejected: bool,
    /// RK4's ungraded step `1 / steps_per_tc` (0 for Dopri5).
    pub(super) h_rk: f64,
    /// RK4's step factor after event retries (1, halved per retry).
    pub(super) retry_scale: f64,
}

/// `ln 1e-4`, the least `ln facold`.
pub(super) fn ln_facold_min() -> f64 {
    1e-4_f64.ln()
}

impl StepControl {
    pub(super) fn new(method: Method, tol: Tolerance, limits: &Limits) -> Self {
        let hmax = limits.max_step_tc;
        StepControl {
            method,
            tol,
            h: limits
                .initial_step_tc
                .unwrap_or_else(|| 0.1 * tol.rtol.powf(0.4))
                .min(hmax),
            hmax,
            expo1: 0.2 - BETA * 0.75,
            ln_facold: ln_facold_min(),
            last_rejected: false,
            h_rk: match method {
                Method::Rk4 { steps_per_tc } => 1.0 / f64::from(steps_per_tc),
                Method::Dopri5 => 0.0,
            },
            retry_scale: 1.0,
        }
    }

    /// One trial step of size `h` (RK4: graded by the time since contact or to its end).
    pub(super) fn trial(
        &mut self,
        rhs: &mut Rhs,
        t: f64,
        y: [f64; 2],
        f: [f64; 2],
        time_s: f64,
    ) -> Result<Trial, SimError> {
        match self.method {
            Method::Dopri5 => {
                if self.h <= 16.0 * f64::EPSILON * t.max(1e-3) {
                    return Err(SimError::StepSizeUnderflow {
                        t_s: t * time_s,
                        h_s: self.h * time_s,
                    });
                }
                Ok(dopri_step(rhs, t, y, f, self.h, self.tol))
            }
            Method::Rk4 { .. } => {
                let to_end = if y[1] < 0.0 {
                    y[0] / (HERTZ_TC_FACTOR * -y[1])
                } else {
                    f64::INFINITY
                };
                let s = t.min(to_end).max(0.0);
                let grade = (s / T1).sqrt().max(self.h_rk / T1).min(1.0);
                self.h = self.h_rk * grade * self.retry_scale;
                Ok(rk4_step(rhs, t, y, f, self.h))
            }
        }
    }

    /// The error test of a finite trial: `Some(h_next)` when accepted, `None` when rejected
    /// (the step shrunk for the retry). RK4 accepts every step.
    pub(super) fn accept(&mut self, err: f64) -> Option<f64> {
        if let Method::Rk4 { .. } = self.method {
            return Some(self.h);
        }
        let ln_err = err.ln();
        if err > 1.0 {
            let fac11 = (self.expo1 * ln_err).exp();
            self.h /= (fac11 / SAFE).min(1.0 / FACMIN);
            self.last_rejected = true;
            return None;
        }
        let fac = ((self.expo1 * ln_err - BETA * self.ln_facold).exp() / SAFE)
            .clamp(1.0 / FACMAX, 1.0 / FACMIN);
        self.ln_facold = ln_err.max(ln_facold_min());
        let mut h_next = (self.h / fac).min(self.hmax);
        if self.last_rejected {
            h_next = h_next.min(self.h);
        }
        self.last_rejected = false;
        Some(h_next)
    }

    /// A non-finite trial: Dopri5 shrinks strongly and retries (`true`); RK4 cannot.
    pub(super) fn retry_non_finite(&mut self) -> bool {
        if let Method::Dopri5 = self.method {
            self.h *= FACMIN;
            self.last_rejected = true;
            return true;
        }
        false
    }

    /// An event search that asks for a smaller step: the step is halved.
    pub(super) fn halve(&mut self) {
        match self.method {
            Method::Dopri5 => self.h *= 0.5,
            Method::Rk4 { .. } => self.retry_scale *= 0.5,
        }
    }

    /// The step to an event, of size `he`, failed its error test `err`: retry with
    /// `he (0.9 err^(-1/5))`, the factor in `[FACMIN, 1]` (`FACMIN` for a non-finite error).
    pub(super) fn shrink_to_event(&mut self, he: f64, err: f64) {
        let shrink = if err.is_finite() {
            (SAFE * err.powf(-0.2)).clamp(FACMIN, 1.0)
        } else {
            FACMIN
        };
        self.h = he * shrink;
        self.last_rejected = true;
    }

    /// After an accepted step: the next trial is `h_next`, unscaled.
    pub(super) fn advance(&mut self, h_next: f64) {
        self.h = h_next;
        self.retry_scale = 1.0;
    }

    /// A step of size `h` from `(t, y, f)` with this method (the step to an event).
    pub(super) fn step(&self, rhs: &mut Rhs, t: f64, y: [f64; 2], f: [f64; 2], h: f64) -> Trial {
        match self.method {
            Method::Dopri5 => dopri_step(rhs, t, y, f, h, self.tol),
            Method::Rk4 { .. } => rk4_step(rhs, t, y, f, h),
        }
    }
}
