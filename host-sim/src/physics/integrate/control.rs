//! The step-size controller: the adaptive methods' error-per-step control (Hairer's
//! constants), RK4's graded fixed steps, and the automatic choice between an explicit and a
//! stiff method.

use crate::physics::hertz64::HERTZ_TC_FACTOR;
use crate::physics::integrate::dop853::dop853_step;
use crate::physics::integrate::dopri5::dopri_step;
use crate::physics::integrate::error_scale::ErrorScale;
use crate::physics::integrate::radau::{RadauState, radau_step};
use crate::physics::integrate::rhs::{Rhs, Trial, spectral_radius};
use crate::physics::integrate::rk4::rk4_step;
use crate::physics::integrate::rodas4::rodas4_step;
use crate::physics::integrate::{Limits, Method, SimError, Tolerance};

/// Dopri5's controller (Hairer's DOPRI5: beta = 0.04, safety 0.9, factors 0.2..10).
pub(super) const BETA: f64 = 0.04;
/// Safety factor of the step-size controller.
pub(super) const SAFE: f64 = 0.9;
/// Smallest step-size factor of Dopri5 (`h_new >= FACMIN h`).
pub(super) const FACMIN: f64 = 0.2;
/// Largest step-size factor of Dopri5 (`h_new <= FACMAX h`).
pub(super) const FACMAX: f64 = 10.0;
/// RK4's steps are graded down near first contact, up to scaled time `T1`.
pub(super) const T1: f64 = 1.0 / 16.0;
/// [`Method::Auto`] turns to Radau13 once an accepted explicit step has `h rho(J)` above this
/// (DOP853's stability region reaches about 6 on the negative real axis; an accuracy-limited
/// step stays well inside it).
pub(super) const STIFF_H_RHO: f64 = 4.0;
/// [`Method::Auto`] turns back to Dop853 after [`CALM_STEPS`] accepted Radau13 steps with
/// `h rho(J)` below this.
pub(super) const CALM_H_RHO: f64 = 1.0;
/// See [`CALM_H_RHO`].
pub(super) const CALM_STEPS: u32 = 3;
/// [`Method::Auto`] also turns to Radau13 where `rho(J)` itself, in units of the Hertz contact
/// time, is above this, whatever the step, and does not turn back while it is: the contact
/// is stiff though the explicit step is still held by accuracy (a step of a fiftieth of the
/// contact time is then at DOP853's stability limit). The heavily damped contact of
/// `host-sim speed` passes it during its spike and turn, where Dop853 had spent about 950
/// evaluations; the undamped and the lightly damped contacts stay far below it.
pub(super) const STIFF_RHO: f64 = 300.0;
/// Halvings the clamp's event search may spend on one step of Dop853, Rodas4, Radau13 and
/// Auto. A
/// heavily damped contact creeps out along its clamp (the unclamped force stays within
/// rounding of zero for hundreds of steps), where the enclosures settle nothing and an
/// unbounded search costs 2^depth evaluations; past this many halvings a part is searched for
/// a sign change between its ends only. Dopri5 and RK4 search without a bound, as before.
pub(super) const CLAMP_SPLITS: usize = 16;

/// The step a controller takes now.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Stepper {
    /// Dormand-Prince 5(4).
    Dopri5,
    /// Dormand-Prince 8(5,3).
    Dop853,
    /// Rosenbrock Rodas4.
    Rodas4,
    /// Radau IIA of order 13.
    Radau13,
    /// Classical RK4, graded fixed steps.
    Rk4,
}

/// A stepper's controller constants: the factor is
/// `clamp(err^expo1 / facold^beta / SAFE, 1 / facmax, 1 / facmin)`, and a step to an event
/// that fails shrinks by `SAFE err^shrink_expo`. A predictive controller also takes
/// Gustafsson's factor `(h_acc / h) (err^2 / err_acc)^expo1 / SAFE` from the last two accepted
/// steps when it is the larger (the smaller step), as Hairer's RODAS and RADAU5 do: where the
/// error grows step by step (the approach to the contact's end, whose force `~ (t_c - t)^1.5`
/// has ever larger derivatives), the step shrinks ahead of it instead of being rejected every
/// other time.
#[derive(Debug, Clone, Copy)]
pub(super) struct Gains {
    pub(super) expo1: f64,
    pub(super) beta: f64,
    pub(super) facmin: f64,
    pub(super) facmax: f64,
    pub(super) shrink_expo: f64,
    pub(super) predictive: bool,
}

impl Stepper {
    /// Hairer's constants: DOPRI5 (beta 0.04, factors 0.2..10), DOP853 (beta 0, 1/3..6),
    /// RODAS (no stabilisation, 0.2..6), RADAU5's for order 13 (`err^(1/8)`, 0.2..8; its
    /// safety factor falls with the Newton iterations, [`StepControl::safety`]).
    fn gains(self) -> Gains {
        match self {
            Stepper::Dopri5 | Stepper::Rk4 => Gains {
                expo1: 0.2 - BETA * 0.75,
                beta: BETA,
                facmin: FACMIN,
                facmax: FACMAX,
                shrink_expo: -0.2,
                predictive: false,
            },
            Stepper::Dop853 => Gains {
                expo1: 0.125,
                beta: 0.0,
                facmin: 1.0 / 3.0,
                facmax: 6.0,
                shrink_expo: -0.125,
                predictive: true,
            },
            Stepper::Rodas4 => Gains {
                expo1: 0.25,
                beta: 0.0,
                facmin: 0.2,
                facmax: 6.0,
                shrink_expo: -0.25,
                predictive: true,
            },
            Stepper::Radau13 => Gains {
                expo1: 0.125,
                beta: 0.0,
                facmin: 0.2,
                facmax: 8.0,
                shrink_expo: -0.125,
                predictive: true,
            },
        }
    }
}

/// The step size and its controller: the error-per-step control of the adaptive methods
/// (with Hairer's stabilisation `facold` for Dopri5), RK4's graded fixed steps, and
/// [`Method::Auto`]'s choice between Dop853 and Radau13 from the spectral radius of the exact
/// Jacobian.
pub(super) struct StepControl {
    pub(super) method: Method,
    /// The step taken now (for [`Method::Auto`], Dop853 or Radau13).
    pub(super) stepper: Stepper,
    pub(super) gains: Gains,
    pub(super) tol: Tolerance,
    /// The largest scaled penetration so far (for [`ErrorScale`]).
    pub(super) x_peak: f64,
    /// The next trial step (scaled time).
    pub(super) h: f64,
    /// Largest step.
    pub(super) hmax: f64,
    /// ln of Hairer's `facold` (the last accepted error, at least 1e-4), for the steppers
    /// with `beta > 0` (Dopri5): the controller's factor `err^expo1 / facold^beta` is one exp
    /// of logs, not two powf. The others take `err^expo1` alone ([`err_power`]).
    pub(super) ln_facold: f64,
    /// Whether the last trial was rejected (then the step may not grow).
    pub(super) last_rejected: bool,
    /// The last accepted step of this stepper and its error to the power `expo1` (the error
    /// at least 1e-2), for the predictive controller ([`Gains::predictive`]); `None` before
    /// the first.
    pub(super) last_accepted: Option<(f64, f64)>,
    /// RK4's ungraded step `1 / steps_per_tc` (0 for the adaptive methods).
    pub(super) h_rk: f64,
    /// RK4's step factor after event retries (1, halved per retry).
    pub(super) retry_scale: f64,
    /// [`Method::Auto`] on Radau13: accepted steps in a row with `h rho(J)` below
    /// [`CALM_H_RHO`].
    pub(super) calm: u32,
    /// Radau13's state between steps (starting values, Jacobian, Newton rate).
    pub(super) radau: RadauState,
}

/// The least error the predictive controller remembers (Hairer's RODAS).
const ERR_ACC_MIN: f64 = 1e-2;

/// `err^expo`: by square roots for the exponents 1/8 (Dop853, Radau13) and 1/4 (Rodas4),
/// `sqrt(sqrt(sqrt(err)))` and `sqrt(sqrt(err))`, each correctly rounded, so the result is
/// within a few ulps of the exact power and needs no `exp` or `ln`; `exp(expo ln err)`
/// otherwise (Dopri5's `0.2 - 0.75 beta`, as it always was).
pub(super) fn err_power(err: f64, expo: f64) -> f64 {
    if expo == 0.125 {
        err.sqrt().sqrt().sqrt()
    } else if expo == 0.25 {
        err.sqrt().sqrt()
    } else {
        (expo * err.ln()).exp()
    }
}

/// `ln 1e-4`, the least `ln facold`.
pub(super) fn ln_facold_min() -> f64 {
    1e-4_f64.ln()
}

impl StepControl {
    pub(super) fn new(method: Method, tol: Tolerance, limits: &Limits) -> Self {
        let stepper = match method {
            Method::Dopri5 => Stepper::Dopri5,
            Method::Dop853 | Method::Auto => Stepper::Dop853,
            Method::Rodas4 => Stepper::Rodas4,
            Method::Radau13 => Stepper::Radau13,
            Method::Rk4 { .. } => Stepper::Rk4,
        };
        // Dopri5 and RK4 keep the step bound; the others take steps as long as their error
        // control allows (a force-free flight out of a damped contact is exact for them).
        let hmax = match method {
            Method::Dopri5 | Method::Rk4 { .. } => limits.max_step_tc,
            _ => limits.max_time_tc,
        };
        StepControl {
            method,
            stepper,
            gains: stepper.gains(),
            tol,
            x_peak: 0.0,
            h: limits
                .initial_step_tc
                .unwrap_or_else(|| 0.1 * tol.rtol.powf(0.4))
                .min(hmax),
            hmax,
            ln_facold: ln_facold_min(),
            last_rejected: false,
            last_accepted: None,
            h_rk: match method {
                Method::Rk4 { steps_per_tc } => 1.0 / f64::from(steps_per_tc),
                _ => 0.0,
            },
            retry_scale: 1.0,
            calm: 0,
            radau: RadauState::new(),
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
        if let Stepper::Rk4 = self.stepper {
            let to_end = if y[1] < 0.0 {
                y[0] / (HERTZ_TC_FACTOR * -y[1])
            } else {
                f64::INFINITY
            };
            let s = t.min(to_end).max(0.0);
            let grade = (s / T1).sqrt().max(self.h_rk / T1).min(1.0);
            self.h = self.h_rk * grade * self.retry_scale;
            return Ok(rk4_step(rhs, t, y, f, self.h));
        }
        if self.h <= 16.0 * f64::EPSILON * t.max(1e-3) {
            return Err(SimError::StepSizeUnderflow {
                t_s: t * time_s,
                h_s: self.h * time_s,
            });
        }
        Ok(self.step(rhs, t, y, f, self.h))
    }

    /// The error test of a finite trial: `Some(h_next)` when accepted, `None` when rejected
    /// (the step shrunk for the retry). RK4 accepts every step.
    pub(super) fn accept(&mut self, err: f64) -> Option<f64> {
        if let Stepper::Rk4 = self.stepper {
            return Some(self.h);
        }
        let g = self.gains;
        let safe = self.safety();
        let q = err_power(err, g.expo1);
        if err > 1.0 {
            self.h /= (q / safe).min(1.0 / g.facmin);
            self.last_rejected = true;
            return None;
        }
        let mut fac = if g.beta == 0.0 {
            q / safe
        } else {
            let ln_err = err.ln();
            let f = (g.expo1 * ln_err - g.beta * self.ln_facold).exp() / safe;
            self.ln_facold = ln_err.max(ln_facold_min());
            f
        }
        .clamp(1.0 / g.facmax, 1.0 / g.facmin);
        if g.predictive {
            if let Some((h_acc, q_acc)) = self.last_accepted {
                let gus = h_acc / self.h * (q * q / q_acc) / SAFE;
                fac = fac.max(gus.clamp(1.0 / g.facmax, 1.0 / g.facmin));
            }
            self.last_accepted = Some((self.h, q.max(err_power(ERR_ACC_MIN, g.expo1))));
        }
        let mut h_next = (self.h / fac).min(self.hmax);
        if self.last_rejected {
            h_next = h_next.min(self.h);
        }
        self.last_rejected = false;
        Some(h_next)
    }

    /// The step-size controller's safety factor: RADAU5's `0.9 min(1, (2 NIT + 1) /
    /// (2 NIT + newt))` after a Radau13 trial, else [`SAFE`].
    fn safety(&self) -> f64 {
        match self.stepper {
            Stepper::Radau13 => self.radau.safety,
            _ => SAFE,
        }
    }

    /// After an accepted step (`restart`: one that ended on an event, where the integration
    /// restarts): Radau13 keeps the step's continuous output and Jacobian for the next one.
    pub(super) fn accepted_step(&mut self, restart: bool) {
        self.radau.accepted(restart);
    }

    /// [`Method::Auto`] after an accepted step of size `h` that ended at `y`: Dop853 turns to
    /// Radau13 when `h rho(J(y)) > STIFF_H_RHO` (the step is held by stability, not accuracy)
    /// or `rho(J) > STIFF_RHO` (the contact is stiff), Radau13 back to Dop853 after
    /// [`CALM_STEPS`] steps with `h rho(J) < CALM_H_RHO` and `rho(J) <= STIFF_RHO`. One
    /// Jacobian per accepted Dop853 step (Radau13's own, at its step's predicted end, serves
    /// otherwise); nothing for the other methods.
    pub(super) fn choose(&mut self, rhs: &mut Rhs, h: f64, y: [f64; 2]) {
        self.x_peak = self.x_peak.max(y[0]);
        if self.method != Method::Auto {
            return;
        }
        // On the stiff stepper the Jacobian its step just used serves.
        let j = match (self.stepper, rhs.last_jac) {
            (Stepper::Rodas4 | Stepper::Radau13, Some(j)) => j,
            _ => rhs.jac(y),
        };
        let rho = spectral_radius(j);
        let h_rho = h * rho;
        let next = match self.stepper {
            Stepper::Dop853 if h_rho > STIFF_H_RHO || rho > STIFF_RHO => Stepper::Radau13,
            Stepper::Radau13 if h_rho < CALM_H_RHO && rho <= STIFF_RHO => {
                self.calm += 1;
                if self.calm >= CALM_STEPS {
                    Stepper::Dop853
                } else {
                    Stepper::Radau13
                }
            }
            other => {
                self.calm = 0;
                other
            }
        };
        if next != self.stepper {
            self.stepper = next;
            self.gains = next.gains();
            self.last_accepted = None;
            self.calm = 0;
            self.radau.reset();
        }
    }

    /// A non-finite trial: an adaptive method shrinks strongly and retries (`true`); RK4
    /// cannot.
    pub(super) fn retry_non_finite(&mut self) -> bool {
        if let Stepper::Rk4 = self.stepper {
            return false;
        }
        self.h *= self.gains.facmin;
        self.last_rejected = true;
        true
    }

    /// An event search that asks for a smaller step: the step is halved.
    pub(super) fn halve(&mut self) {
        match self.stepper {
            Stepper::Rk4 => self.retry_scale *= 0.5,
            _ => self.h *= 0.5,
        }
    }

    /// The step to an event, of size `he`, failed its error test `err`: retry with
    /// `he (0.9 err^shrink_expo)` (`err^(-1/5)` for Dopri5), the factor in `[facmin, 1]`
    /// (`facmin` for a non-finite error).
    pub(super) fn shrink_to_event(&mut self, he: f64, err: f64) {
        let g = self.gains;
        let shrink = if err.is_finite() {
            (SAFE * err.powf(g.shrink_expo)).clamp(g.facmin, 1.0)
        } else {
            g.facmin
        };
        self.h = he * shrink;
        self.last_rejected = true;
    }

    /// Halvings the clamp's event search may spend on a step (see [`CLAMP_SPLITS`]).
    pub(super) fn clamp_splits(&self) -> usize {
        match self.method {
            Method::Dopri5 | Method::Rk4 { .. } => usize::MAX,
            _ => CLAMP_SPLITS,
        }
    }

    /// After an accepted step: the next trial is `h_next`, unscaled.
    pub(super) fn advance(&mut self, h_next: f64) {
        self.h = h_next;
        self.retry_scale = 1.0;
    }

    /// The error scale of the new methods now.
    fn error_scale(&self) -> ErrorScale {
        ErrorScale {
            tol: self.tol,
            x_peak: self.x_peak,
        }
    }

    /// A step of size `h` from `(t, y, f)` with the current stepper (also the step to an
    /// event).
    pub(super) fn step(
        &mut self,
        rhs: &mut Rhs,
        t: f64,
        y: [f64; 2],
        f: [f64; 2],
        h: f64,
    ) -> Trial {
        match self.stepper {
            Stepper::Dopri5 => dopri_step(rhs, t, y, f, h, self.tol),
            Stepper::Dop853 => dop853_step(rhs, t, y, f, h, &self.error_scale()),
            Stepper::Rodas4 => rodas4_step(rhs, t, y, f, h, &self.error_scale()),
            Stepper::Radau13 => {
                let scale = self.error_scale();
                let retry = self.last_rejected;
                radau_step(rhs, &mut self.radau, (t, y, f), h, &scale, retry)
            }
            Stepper::Rk4 => rk4_step(rhs, t, y, f, h),
        }
    }
}
