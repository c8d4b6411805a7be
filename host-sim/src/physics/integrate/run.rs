//! The driver: one contact's integration from first contact to separation, step by step,
//! stopping and restarting at every event.

use crate::physics::hertz64::{HERTZ_TC_FACTOR, positive};
use crate::physics::integrate::control::{StepControl, Stepper};
use crate::physics::integrate::dense::Segment;
use crate::physics::integrate::peak::finish;
use crate::physics::integrate::rhs::{Rhs, Side, Trial};
use crate::physics::integrate::solution::ContactSolution;
use crate::physics::integrate::switching::{ClampSwitch, Event, find_event};
use crate::physics::integrate::{
    ContactProblem, Limits, MAX_CLAMP_RESTARTS, Method, Scales, SimError, Tolerance, WorkStats,
};
use crate::physics::laws::ForceLaw;

/// Phase 1 of [`integrate_contact`]: the problem, method, tolerance and limits are in range.
pub(super) fn validate_contact(
    problem: &ContactProblem,
    method: Method,
    tol: Tolerance,
    limits: &Limits,
) -> Result<(), SimError> {
    problem.law.validate()?;
    positive("mass_kg", problem.mass_kg)?;
    positive("speed_m_s", problem.speed_m_s)?;
    if !(problem.gravity_m_s2.is_finite() && problem.gravity_m_s2 >= 0.0) {
        return Err(SimError::InvalidParameter {
            name: "gravity_m_s2".to_string(),
            value: problem.gravity_m_s2,
            requirement: "finite and >= 0",
        });
    }
    if !matches!(method, Method::Rk4 { .. }) {
        positive("tolerance.rtol", tol.rtol)?;
        positive("tolerance.atol", tol.atol)?;
    }
    if let Method::Rk4 { steps_per_tc } = method
        && steps_per_tc == 0
    {
        return Err(SimError::InvalidParameter {
            name: "steps_per_tc".to_string(),
            value: 0.0,
            requirement: ">= 1",
        });
    }
    positive("limits.max_time_tc", limits.max_time_tc)?;
    positive("limits.max_step_tc", limits.max_step_tc)?;
    if let Some(h0) = limits.initial_step_tc {
        positive("limits.initial_step_tc", h0)?;
    }
    Ok(())
}

/// Phase 2: the scales of the integration, `delta_max = ((n + 1) m u^2 / (2 k))^(1/(n + 1))`
/// and `T = 2.9432751843247 delta_max / u`, both finite and positive.
pub(super) fn contact_scales(problem: &ContactProblem) -> Result<Scales, SimError> {
    let (m, u) = (problem.mass_kg, problem.speed_m_s);
    let (k, n) = (problem.law.stiffness(), problem.law.exponent());
    let d_m = ((n + 1.0) * m * u * u / (2.0 * k)).powf(1.0 / (n + 1.0));
    let time_s = HERTZ_TC_FACTOR * d_m / u;
    if !(d_m.is_finite() && d_m > 0.0 && time_s.is_finite() && time_s > 0.0) {
        return Err(SimError::InvalidParameter {
            name: "stiffness, mass and speed".to_string(),
            value: d_m,
            requirement: "giving a finite, positive Hertz penetration",
        });
    }
    Ok(Scales {
        delta_m: d_m,
        time_s,
        speed_m_s: u,
    })
}

/// Segments reserved up front: a contact at a tight tolerance takes about 50 steps, so the
/// output does not grow (and copy) step by step.
const SEGMENTS_RESERVED: usize = 64;

/// The state of one contact's integration: the right-hand side (whose law turns), the
/// accepted steps' continuous output, and where the last step ended.
pub(super) struct ContactRun {
    /// The law given (the clamp's presence and the finish read it).
    pub(super) law: ForceLaw,
    pub(super) rhs: Rhs,
    pub(super) scales: Scales,
    /// The kink in scaled penetration, when the current law has one.
    pub(super) x_kink: Option<f64>,
    pub(super) clamp_switch: ClampSwitch,
    /// A history-dependent law: the law after the turn, from scaled time turned.0 on.
    pub(super) turned: Option<(f64, ForceLaw)>,
    pub(super) work: WorkStats,
    pub(super) segments: Vec<Segment>,
    /// The force (N) at each segment's start, known from the stepping (the peak search's grid).
    pub(super) start_force_n: Vec<f64>,
    pub(super) t: f64,
    pub(super) y: [f64; 2],
    pub(super) f: [f64; 2],
    pub(super) force_n: f64,
}

/// What the step to an event did.
pub(super) enum EventStep {
    /// The step failed its error test: retry with a smaller step.
    Retry,
    /// The contact ended.
    End(Box<ContactSolution>),
    /// Landed on a kink, turn or clamp switch; the integration goes on.
    Restart,
}

impl ContactRun {
    pub(super) fn new(problem: &ContactProblem, scales: Scales, method: Method) -> Self {
        let law = problem.law;
        let (d_m, u, time_s) = (scales.delta_m, scales.speed_m_s, scales.time_s);
        let p = time_s / (u * problem.mass_kg);
        let mut rhs = Rhs {
            law,
            d_m,
            u_m_s: u,
            cx: HERTZ_TC_FACTOR,
            g: time_s * problem.gravity_m_s2 / u,
            p,
            evals: 0,
            jac_evals: 0,
            last_jac: None,
            last_force_n: 0.0,
            // Only Radau13's stages take a side of the clamp's switch; the other methods'
            // runs need not follow it.
            side: if law.is_clamped() && matches!(method, Method::Radau13 | Method::Auto) {
                Side::On
            } else {
                Side::Law
            },
            hertz: Rhs::hertz_scaled(&law, d_m, p),
        };
        let y = [0.0, 1.0];
        let f = rhs.f(y);
        let force_n = rhs.last_force_n;
        ContactRun {
            law,
            rhs,
            scales,
            x_kink: law.kink_m().map(|d| d / d_m),
            clamp_switch: ClampSwitch { law, d_m, u_m_s: u },
            turned: None,
            work: WorkStats::default(),
            segments: Vec::with_capacity(SEGMENTS_RESERVED),
            start_force_n: Vec::with_capacity(SEGMENTS_RESERVED),
            t: 0.0,
            y,
            f,
            force_n,
        }
    }

    /// The errors of a run that goes on too long: too many steps, or no separation in time.
    pub(super) fn check_limits(&self, limits: &Limits) -> Result<(), SimError> {
        let t_s = self.t * self.scales.time_s;
        if self.work.steps + self.work.rejected_steps >= limits.max_steps {
            return Err(SimError::MaxSteps {
                max_steps: limits.max_steps,
                t_s,
            });
        }
        if self.t > limits.max_time_tc {
            return Err(SimError::NoSeparation { t_s });
        }
        Ok(())
    }

    /// The first event inside `trial` (see [`find_event`]), as `(theta, landing, is_end)`;
    /// `Err(())` when the search asks for a smaller step. The clamp's search may halve the
    /// step `clamp_splits` times ([`StepControl::clamp_splits`]).
    pub(super) fn event_in(
        &self,
        trial: &Trial,
        clamp_splits: usize,
    ) -> Result<Option<(f64, Landing, bool)>, ()> {
        let ends = (
            self.rhs.law.contact_end_m() / self.scales.delta_m,
            self.rhs.law.awaits_turn(),
        );
        Ok(
            match find_event(
                &trial.seg,
                self.x_kink,
                ends,
                self.law.is_clamped().then_some(&self.clamp_switch),
                (
                    MAX_CLAMP_RESTARTS.saturating_sub(self.work.clamp_restarts),
                    clamp_splits,
                ),
            ) {
                Some(Event::Retry) => return Err(()),
                Some(Event::End(th)) => Some((th, Landing::X(ends.0), true)),
                Some(Event::Kink(th)) => {
                    Some((th, self.x_kink.map_or(Landing::Free, Landing::X), false))
                }
                Some(Event::Turn(th)) => Some((th, Landing::V, false)),
                Some(Event::Clamp(th)) => Some((th, Landing::Free, false)),
                None => None,
            },
        )
    }

    /// After an accepted step (whole, or to an event where the integration restarts):
    /// counts a stiff step, lets [`Method::Auto`] choose the next stepper, and sets the next
    /// trial step `h_next`.
    fn accepted(&mut self, ctl: &mut StepControl, h_next: f64, restart: bool) {
        if matches!(ctl.stepper, Stepper::Rodas4 | Stepper::Radau13) {
            self.work.stiff_steps += 1;
        }
        ctl.accepted_step(restart);
        let h_taken = self.segments.last().map_or(h_next, |s| s.h);
        ctl.choose(&mut self.rhs, h_taken, self.y);
        ctl.advance(h_next);
    }

    /// Takes the accepted `trial` of size `h` whole. Radau13's side of the clamp's switch
    /// (for [`Method::Radau13`] and [`Method::Auto`]) follows the sign of the switching
    /// function at the step's end (a step of another method, or a sign change the search did
    /// not locate, may have crossed it).
    pub(super) fn take(&mut self, trial: Trial, h: f64) {
        if self.rhs.side != Side::Law {
            let s = self.clamp_switch.value(trial.y1);
            if s > 0.0 {
                self.rhs.side = Side::On;
            } else if s < 0.0 {
                self.rhs.side = Side::Off;
            }
        }
        self.work.steps += 1;
        self.segments.push(trial.seg);
        self.start_force_n.push(self.force_n);
        self.t += h;
        self.y = trial.y1;
        self.f = trial.f1;
        self.force_n = trial.force1_n;
    }

    /// Steps to the event at `theta` of a step of size `h` and lands on it by one Newton
    /// correction onto `x = target` (end and kink) or `v = 0` (turn); none for a clamp switch.
    /// The step to the event is a step too: it must pass the error test (it fails when the
    /// force switches on or off inside it), else the step is retried smaller and the event is
    /// found again later.
    pub(super) fn step_to_event(
        &mut self,
        ctl: &mut StepControl,
        (theta, target, is_end): (f64, Landing, bool),
        problem: &ContactProblem,
    ) -> EventStep {
        let he = theta * ctl.h;
        let (t, y, f) = (self.t, self.y, self.f);
        let (ye, fe, mut seg) = if he > 0.0 {
            let tr = ctl.step(&mut self.rhs, t, y, f, he);
            if tr.err > 1.0 || !(tr.y1[0].is_finite() && tr.y1[1].is_finite()) {
                self.work.rejected_steps += 1;
                ctl.shrink_to_event(he, tr.err);
                return EventStep::Retry;
            }
            (tr.y1, tr.f1, tr.seg)
        } else {
            (y, f, Segment::hermite(t, 0.0, y, f, y, f))
        };
        self.work.steps += 1;
        let (dt, y_e) = target.land(ye, fe);
        let t_e = t + he + dt;
        seg.h = t_e - t;
        self.segments.push(seg);
        self.start_force_n.push(self.force_n);
        if is_end {
            return EventStep::End(Box::new(self.finish(t_e, y_e, problem)));
        }
        match target {
            Landing::X(_) => self.work.kink_restarts += 1,
            Landing::Free => {
                // The force switched on or off: Radau13's stages now see the other side, or
                // the law itself once no further switch is located.
                self.work.clamp_restarts += 1;
                if self.rhs.side != Side::Law {
                    self.rhs.side = if self.work.clamp_restarts >= MAX_CLAMP_RESTARTS {
                        Side::Law
                    } else {
                        self.rhs.side_leaving_switch(y_e)
                    };
                }
            }
            Landing::V => {
                self.work.turns += 1;
                self.rhs
                    .set_law(self.rhs.law.turned_at(y_e[0] * self.scales.delta_m));
                self.clamp_switch.law = self.rhs.law;
                self.x_kink = self.rhs.law.kink_m().map(|d| d / self.scales.delta_m);
                self.turned = Some((t_e, self.rhs.law));
            }
        }
        self.t = t_e;
        self.y = y_e;
        self.f = self.rhs.f(y_e);
        self.force_n = self.rhs.last_force_n;
        EventStep::Restart
    }

    /// The solution of a contact that ended at scaled time `t_e` in state `y_e`.
    pub(super) fn finish(
        &mut self,
        t_e: f64,
        y_e: [f64; 2],
        problem: &ContactProblem,
    ) -> ContactSolution {
        let rebound = -y_e[1] * self.scales.speed_m_s;
        let duration_s = t_e * self.scales.time_s;
        self.work.force_evals = self.rhs.evals;
        self.work.jacobian_evals = self.rhs.jac_evals;
        finish(
            (self.law, self.turned),
            self.scales,
            std::mem::take(&mut self.segments),
            &self.start_force_n,
            self.work,
            duration_s,
            rebound,
            problem.mass_kg,
            problem.gravity_m_s2,
        )
    }
}

/// Integrates one contact from first contact to separation.
///
/// Errors on invalid input, on reaching [`Limits::max_steps`] or [`Limits::max_time_tc`],
/// on a non-finite state or on step-size underflow.
pub fn integrate_contact(
    problem: &ContactProblem,
    method: Method,
    tol: Tolerance,
    limits: &Limits,
) -> Result<ContactSolution, SimError> {
    validate_contact(problem, method, tol, limits)?;
    let scales = contact_scales(problem)?;
    let mut run = ContactRun::new(problem, scales, method);
    let mut ctl = StepControl::new(method, tol, limits);
    loop {
        run.check_limits(limits)?;
        let trial = ctl.trial(&mut run.rhs, run.t, run.y, run.f, scales.time_s)?;
        if !(trial.y1[0].is_finite() && trial.y1[1].is_finite() && trial.err.is_finite()) {
            if ctl.retry_non_finite() {
                run.work.rejected_steps += 1;
                continue;
            }
            return Err(SimError::NonFinite {
                t_s: run.t * scales.time_s,
            });
        }
        let Some(h_next) = ctl.accept(trial.err) else {
            run.work.rejected_steps += 1;
            continue;
        };
        match run.event_in(&trial, ctl.clamp_splits()) {
            Err(()) => {
                run.work.rejected_steps += 1;
                ctl.halve();
            }
            Ok(Some(event)) => match run.step_to_event(&mut ctl, event, problem) {
                EventStep::Retry => {}
                EventStep::End(solution) => return Ok(*solution),
                EventStep::Restart => run.accepted(&mut ctl, h_next, true),
            },
            Ok(None) => {
                run.take(trial, ctl.h);
                run.accepted(&mut ctl, h_next, false);
            }
        }
    }
}

/// Where a step to an event lands.
#[derive(Debug, Clone, Copy)]
pub(super) enum Landing {
    /// On `x = target` (contact end, kink).
    X(f64),
    /// On `v = 0` (the penetration's turn).
    V,
    /// Where the step ends (a clamp switch).
    Free,
}

impl Landing {
    /// One Newton correction `(dt, y)` from the step's end `ye` with slope `fe` onto the
    /// landing's line.
    pub(super) fn land(self, ye: [f64; 2], fe: [f64; 2]) -> (f64, [f64; 2]) {
        let newton = |g: f64, dg: f64| if dg != 0.0 { -g / dg } else { 0.0 };
        match self {
            Landing::X(xt) => {
                let dt = newton(ye[0] - xt, fe[0]);
                (dt, [xt, ye[1] + fe[1] * dt])
            }
            Landing::V => {
                let dt = newton(ye[1], fe[1]);
                (dt, [ye[0] + fe[0] * dt, 0.0])
            }
            Landing::Free => (0.0, ye),
        }
    }
}
