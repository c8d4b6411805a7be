//! One-degree-of-freedom contact integrator.
//!
//! Equation of motion of the sphere's penetration `delta` (m) into the plate:
//!
//! `m delta'' = m g - F(delta, delta')`,
//!
//! with `g` = 0 (gravity off) or 9.80665 m/s^2 (it pushes into the plate), starting at first
//! contact `delta = 0`, `delta' = u`, and ending when `delta` returns to 0 with `delta' < 0`.
//!
//! # Scaling
//! The state is integrated in units of the undamped Hertz closed forms of the same stiffness
//! and mass: `x = delta / delta_max`, `v = delta' / u`, `tau = t / T` with
//! `delta_max = ((n + 1) m u^2 / (2 k))^(1/(n + 1))` (the Hertz `(5 m u^2/(4 k))^(2/5)` for
//! `n = 1.5`) and `T = 2.9432751843247 delta_max / u` (the Hertz contact time), so that
//! `dx/dtau = 2.9432751843247 v`, `dv/dtau = (T/u) (g - F/m)`. A tolerance therefore means the
//! same thing from R = 0.1 mm to 1 m and from 1 mm/s to 50 m/s.
//!
//! # Methods
//! * [`Method::Dopri5`]: adaptive Dormand-Prince 5(4) (Dormand & Prince, J. Comput. Appl.
//!   Math. 6 (1980) 19-26) with the PI step control and the 4th-order continuous extension of
//!   Hairer, Norsett & Wanner, *Solving ODEs I*, II.5-II.6 (`DOPRI5`). The error of a step is
//!   `sqrt(mean((err_i / (atol + rtol max(|y_i|, |y_new_i|)))^2))` on the scaled state.
//! * [`Method::Dop853`]: Dormand-Prince 8(5,3) (Hairer's `DOP853`, *Solving ODEs I*, II.10)
//!   with its 7th-order continuous extension; fewer force evaluations at tight tolerances.
//! * [`Method::Rodas4`]: the L-stable Rosenbrock method of order 4(3) of Hairer & Wanner,
//!   *Solving ODEs II*, IV.7 (`RODAS`), on the exact 2 x 2 Jacobian of the scaled equation
//!   ([`ForceLaw::force_gradient`]), with a 3rd-order continuous output.
//! * [`Method::Radau13`]: the 7-stage Radau IIA collocation method of order 13 (Hairer &
//!   Wanner, *Solving ODEs II*, IV.5 and IV.8, Hairer's `RADAU5` and `RADAU`), L-stable and
//!   stiffly accurate, by simplified Newton on the full 14 x 14 stage system with the exact
//!   Jacobian (at the step's start and its predicted end, interpolated linearly to the nodes),
//!   RADAU5's error estimate and step control, and the collocation polynomial (degree 7) as
//!   continuous output. Its stages see the smooth force of the current side of a damped law's
//!   clamp (the unclamped force while it is on, none while it is off; see Events).
//! * [`Method::Auto`]: Dop853 where the contact is not stiff, Radau13 where it is (the step
//!   times the Jacobian's spectral radius, or that radius alone). Rodas4 stays selectable on
//!   its own.
//! * [`Method::Rk4`]: classical fixed-step Runge-Kutta 4 with `N` steps per Hertz contact
//!   time, graded near the two ends of the contact (see [`Method::Rk4`]).
//!
//! Dopri5 scales a component's error by `atol + rtol max(|y_i|, |y_new_i|)`. Dop853, Rodas4,
//! Radau13 and Auto use `rtol m + atol min(1, max(m, floor))` (`m = max(|y_i|, |y_new_i|)`,
//! the floor the largest penetration so far for `x`, 0 for `v`): the speed keeps relative
//! accuracy when it is small (a heavily damped contact creeps out at 1e-5 to 1e-4 u, where Dopri5's
//! absolute part puts `t_c` off by 1e-5 to 2e-4 at 1e-9), and the penetration is held
//! relative to the contact's own size. Dopri5 keeps its norm so that its results, and the
//! streams made with it, stay as they were.
//!
//! # Events
//! Each accepted step is searched on its continuous output (a polynomial in the step
//! fraction `theta` of the method's degree: Dopri5's 4th-order extension and RK4's cubic
//! Hermite as quartics, Dop853's and Radau13's of degree 7, Rodas4's cubic) for every sign
//! change of
//! three switching functions: the contact end (`x`), for the Adams law the kink `delta = d`
//! (`x - d / delta_max`) and for the damped laws the clamp at zero
//! ([`ForceLaw::clamp_switch`], the unclamped force divided by a positive factor; the Adams law
//! switches off before separation and on again just before it, when `k delta^1.5` outgrows
//! the STEP-ramped damping). The search (`events.rs`) halves the step and drops a part
//! only where an enclosure (Bernstein coefficients of the polynomial, or
//! [`ForceLaw::clamp_switch_bounds`] over the box of states the polynomials take) proves no sign
//! change, so a switch inside a step is not stepped over, and it takes the earliest root
//! (Illinois regula falsi on its bracket). The step is then re-taken exactly to the root (and
//! must pass the error test) and, for the end and the kink, a last Newton correction lands on
//! it, so the integration stops (contact end) or restarts (kink, clamp) there. After the run,
//! `delta_max` is the root of `delta'` and the peak force the maximum of `F` over the
//! continuous output: the largest of the forces at the step starts (known from the stepping;
//! for a clamped law also at the step middles), refined by Brent's method between its
//! neighbours (about 10 evaluations of the output).
//!
//! Radau13 does not put the clamp's kink inside its Newton iteration: while every switch is
//! located (at most [`MAX_CLAMP_RESTARTS`]) its stages take the unclamped force on the side
//! where the force is on and no force where the clamp holds it off, so a switch shows as a
//! sign change of the clamp's switching function on its output, the step is re-taken to it,
//! and the integration restarts on the side the switching function's rate points to (with
//! the force 0 there; a sign change the output shows but the rate contradicts, as in the
//! creep where the unclamped force stays within rounding of zero, leaves the force on). A
//! whole step's end also sets the side from the switching function's sign there. Beyond the
//! located switches its stages take the clamped force.
//!
//! # Per-step cost
//! The step controller's factor is `err^(1/8)` for Dop853 and Radau13 and `err^(1/4)` for
//! Rodas4, taken by three and two square roots (no `exp` or `ln`; the predictive controller
//! keeps the last accepted error to that power), and Dopri5's `err^(0.2 - 0.75 beta) /
//! facold^beta` one `exp` of logarithms (`ln facold` is kept), not two `powf`. The undamped
//! Hertz force is taken in scaled units, `p k delta_max^1.5 x^1.5` with the constant hoisted
//! (one square root per evaluation, no unit conversion), and each Dop853 stage adds its newest
//! slope last, to a sum of the older ones formed while that slope is evaluated; a series of the force at increasing times
//! walks the steps instead of searching them.
//!
//! A history-dependent law ([`ForceLaw::awaits_turn`]: Thornton's elastic-plastic contact)
//! adds a fourth switching function, the rate `v`: where the penetration turns the step lands
//! on `v = 0` (Newton), the law is replaced by [`ForceLaw::turned_at`] (its elastic unloading
//! from that `delta_max`), and the contact ends at [`ForceLaw::contact_end_m`] (the residual
//! dent) instead of `x = 0`; the kink at first yield, `delta_y`, is a kink like Adams'. Every
//! other law never turns, and runs as before.
//!
//! # Stiffness
//! The damped laws with large damping (for example Adams with `c_max` a percent of `k` in SI)
//! make the equation stiff: `c/m` times the contact time reaches 1e4. An explicit method then
//! needs step sizes set by stability, not accuracy; the work is reported, not hidden
//! ([`WorkStats`]). Rodas4 and Radau13 are not held by stability, and [`Method::Auto`] uses
//! Radau13 where the explicit step would be (at rtol 1e-9 on the contact with `c_max` 1 % of
//! `k`, Radau13 needs about 1.05 k force and Jacobian evaluations, Rodas4 about 19 k: order 13
//! against 4 on the creep's long steps). The sphere then creeps out along the clamp (the unclamped force
//! within rounding of zero for hundreds of steps); there the new methods' clamp search is
//! bounded per step (`control::CLAMP_SPLITS`).
//!
//! # Layout
//! One concept per file: `rhs` (the scaled equation of motion and its Jacobian), `dopri5`,
//! `dop853`, `rodas4`, `radau` and `rk4` (the methods' tableaus and steps; Radau13's tableau
//! in `radau_tableau`, its Newton matrix's LU in `lu`), `dense` (a step's
//! continuous output), `control` (the step-size controller, the error scale and Auto's
//! choice), `switching` (the event search of a step), `run` (the driver of one contact),
//! `peak` (the post-processing: largest penetration, peak force, pulse end) and `solution`
//! (the result). The root finders and polynomial enclosures are in
//! `physics::events`.

use serde::{Deserialize, Serialize};

use crate::physics::laws::ForceLaw;

mod control;
mod dense;
mod dop853;
mod dopri5;
mod error_scale;
pub(crate) mod lu;
mod peak;
mod radau;
mod radau_tableau;
mod rhs;
mod rk4;
mod rodas4;
mod run;
mod solution;
mod switching;

pub use crate::physics::sim_error::SimError;
pub use run::integrate_contact;
pub use solution::ContactSolution;

/// Relative and absolute tolerance on the scaled state (`delta / delta_max`, `delta' / u`),
/// used by the adaptive methods (all but [`Method::Rk4`]). Dopri5 scales a component's error
/// by `atol + rtol m`, the others by `rtol m + atol min(1, m)`, with `m` the component's
/// largest magnitude over the step (so that a slow creep keeps its relative accuracy).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Tolerance {
    /// Relative tolerance (dimensionless).
    pub rtol: f64,
    /// Absolute tolerance in units of `delta_max` and `u` (dimensionless).
    pub atol: f64,
}

impl Tolerance {
    /// `rtol = atol = tol`.
    pub fn new(tol: f64) -> Self {
        Self {
            rtol: tol,
            atol: tol,
        }
    }
}

impl Default for Tolerance {
    /// `rtol = atol = 1e-9`.
    fn default() -> Self {
        Self::new(1e-9)
    }
}

/// Integration method.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Method {
    /// Adaptive Dormand-Prince 5(4) with dense output and event location (uses the
    /// [`Tolerance`]). The default; its error scale is `atol + rtol max(|y0|, |y1|)`.
    Dopri5,
    /// Adaptive Dormand-Prince 8(5,3) (Hairer's DOP853) with its 7th-order continuous output:
    /// fewer force evaluations than Dopri5 at tight tolerances (1e-9 and below). Error scale
    /// as the module docs say (relative below the Hertz scales).
    Dop853,
    /// Rodas4, an L-stable Rosenbrock method of order 4 on the exact 2 x 2 Jacobian
    /// ([`ForceLaw::force_gradient`]), with a 3rd-order continuous output: for stiff contacts
    /// (heavy damping, `c/m` times the contact time far above 1).
    Rodas4,
    /// Radau13, the 7-stage Radau IIA collocation method of order 13 (L-stable, stiffly
    /// accurate) by simplified Newton on the exact Jacobian, with the collocation polynomial
    /// (degree 7) as continuous output: for stiff contacts at tight tolerances, where Rodas4's
    /// order 4 needs many steps.
    Radau13,
    /// Dop853 where the contact is not stiff and Radau13 where it is, chosen after every
    /// accepted step from the spectral radius `rho` of the exact Jacobian (per Hertz contact
    /// time): to Radau13 when `h rho > 4` (the explicit step is held by stability) or
    /// `rho > 300` (the contact is stiff, though the step may still be held by accuracy),
    /// back after 3 Radau13 steps with `h rho < 1` and `rho <= 300`.
    Auto,
    /// Classical fixed-step RK4 with `steps_per_tc` steps per Hertz contact time `T`
    /// (`h = T / N`). Near the two ends of the contact, where `k delta^1.5` is not smooth and
    /// uniform steps would only converge at order 2.5, the step is graded as
    /// `h min(1, max(sqrt(s / T1), h / T1))` with `T1 = T / 16` and `s` the time since first
    /// contact or the estimated time to separation `delta / |delta'|`: this keeps 4th-order
    /// convergence and costs about `N / 8` extra steps.
    Rk4 {
        /// Steps per Hertz contact time (>= 1).
        steps_per_tc: u32,
    },
}

/// Guards against runaway integrations.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Limits {
    /// Maximum number of steps (accepted + rejected); the run fails with
    /// [`SimError::MaxSteps`] beyond it. Each accepted step keeps about 100 bytes of dense
    /// output.
    pub max_steps: usize,
    /// Maximum simulated time in Hertz contact times; the run fails with
    /// [`SimError::NoSeparation`] beyond it.
    pub max_time_tc: f64,
    /// First step of the adaptive methods in Hertz contact times; `None` picks
    /// `0.1 rtol^0.4` (small, because `k delta^1.5` is not smooth at first contact).
    pub initial_step_tc: Option<f64>,
    /// Largest step of [`Method::Dopri5`] (and RK4's graded step) in Hertz contact times.
    /// The other methods are bounded by [`Limits::max_time_tc`] only.
    pub max_step_tc: f64,
}

impl Default for Limits {
    /// 500 000 steps, 1000 contact times, automatic first step, largest step 0.25 contact
    /// times.
    fn default() -> Self {
        Self {
            max_steps: 500_000,
            max_time_tc: 1000.0,
            initial_step_tc: None,
            max_step_tc: 0.25,
        }
    }
}

/// The contact problem in SI units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactProblem {
    /// Contact force law.
    pub law: ForceLaw,
    /// Sphere mass `m` in kg.
    pub mass_kg: f64,
    /// Approach speed `u` at first contact in m/s (> 0).
    pub speed_m_s: f64,
    /// Gravity `g` in m/s^2 pushing the sphere into the plate (0 for none).
    pub gravity_m_s2: f64,
}

/// The scales of the integration: the undamped Hertz closed forms for the law's stiffness
/// and exponent.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Scales {
    /// `delta_max = ((n + 1) m u^2 / (2 k))^(1/(n + 1))` in m.
    pub delta_m: f64,
    /// `T = 2.9432751843247 delta_max / u` in s.
    pub time_s: f64,
    /// `u` in m/s.
    pub speed_m_s: f64,
}

/// Most clamp switches located per contact. A heavily damped contact creeps out with the
/// unclamped force hovering around zero (it slides along the switch); locating every sign
/// change there would cost a restart per step, so beyond this number the switches are left to
/// the error control.
pub const MAX_CLAMP_RESTARTS: usize = 8;

/// Work done by the integrator.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct WorkStats {
    /// Accepted steps (including the re-taken steps to an event).
    pub steps: usize,
    /// Rejected steps (error too large, or a step that left the Adams kink and came back).
    pub rejected_steps: usize,
    /// Evaluations of the right-hand side, i.e. of the force law, by the integrator. Not
    /// counted: the event search on the continuous output (for the damped laws one bound and
    /// two values of the clamp's switching function per step, about 60 more near a switch,
    /// and at a located switch one gradient for the side Radau13 continues on)
    /// and the peak-force search after the run (about 10, plus one per step for a clamped
    /// law).
    pub force_evals: usize,
    /// Stops and restarts at the Adams kink `delta = d`.
    pub kink_restarts: usize,
    /// Stops and restarts where a damped law's clamp at zero engages or releases (the
    /// unclamped force changes sign); at most [`MAX_CLAMP_RESTARTS`] per contact.
    pub clamp_restarts: usize,
    /// Stops and restarts where a history-dependent law's penetration turned (0 or 1).
    pub turns: usize,
    /// Evaluations of the exact Jacobian (Rodas4: one per step; Radau13: one per step, two
    /// after a restart; Auto: also one per accepted Dop853 step, for its choice). Each costs
    /// about one force evaluation.
    pub jacobian_evals: usize,
    /// Accepted steps taken by Rodas4 or Radau13 (for [`Method::Auto`], the stiff part of the
    /// contact).
    pub stiff_steps: usize,
}
