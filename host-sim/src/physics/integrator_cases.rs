//! The contact-integrator configurations that `benches/integrator.rs` and `host-sim tradeoff`
//! both measure: the paper's contact problems (undamped Hertz and Adams IMPACT) and the ladder
//! of methods, tolerances and step counts, with the relative errors against a reference.

use crate::physics::hertz64::HertzImpact64;
use crate::physics::impact::ImpactSpec;
use crate::physics::integrate::{
    ContactProblem, ContactSolution, Limits, Method, SimError, Tolerance, integrate_contact,
};
use crate::physics::laws::ForceLaw;

/// Dormand-Prince tolerances (`rtol = atol`, on the scaled state) of the criterion bench.
pub const BENCH_DOPRI5_TOLERANCES: [f64; 4] = [1e-3, 1e-6, 1e-9, 1e-12];

/// RK4 steps per Hertz contact time of the criterion bench.
pub const BENCH_RK4_STEPS: [u32; 3] = [20, 50, 200];

/// One integrator configuration: a method and its tolerance, with a label for reports.
#[derive(Debug, Clone, PartialEq)]
pub struct MethodCase {
    /// `"dopri5 rtol 1e-6"` or `"rk4 50 steps per t_c"` (also the criterion bench id).
    pub label: String,
    /// The method.
    pub method: Method,
    /// The tolerance (used by [`Method::Dopri5`] only; the default for RK4).
    pub tol: Tolerance,
}

impl MethodCase {
    /// Adaptive Dormand-Prince 5(4) at `rtol = atol = tol` (dimensionless, scaled state).
    pub fn dopri5(tol: f64) -> Self {
        Self {
            label: format!("dopri5 rtol {tol:.0e}"),
            method: Method::Dopri5,
            tol: Tolerance::new(tol),
        }
    }

    /// Fixed-step RK4 with `steps_per_tc` steps per Hertz contact time.
    pub fn rk4(steps_per_tc: u32) -> Self {
        Self {
            label: format!("rk4 {steps_per_tc} steps per t_c"),
            method: Method::Rk4 { steps_per_tc },
            tol: Tolerance::default(),
        }
    }

    /// Integrates `problem` with this configuration and the default [`Limits`].
    pub fn solve(&self, problem: &ContactProblem) -> Result<ContactSolution, SimError> {
        integrate_contact(problem, self.method, self.tol, &Limits::default())
    }
}

/// Dormand-Prince at each of `dopri5_tolerances`, then RK4 at each of `rk4_steps`.
pub fn ladder(dopri5_tolerances: &[f64], rk4_steps: &[u32]) -> Vec<MethodCase> {
    dopri5_tolerances
        .iter()
        .map(|&t| MethodCase::dopri5(t))
        .chain(rk4_steps.iter().map(|&n| MethodCase::rk4(n)))
        .collect()
}

/// The criterion bench's ladder: [`BENCH_DOPRI5_TOLERANCES`] and [`BENCH_RK4_STEPS`].
pub fn bench_ladder() -> Vec<MethodCase> {
    ladder(&BENCH_DOPRI5_TOLERANCES, &BENCH_RK4_STEPS)
}

/// The undamped Hertz contact `F = k delta^1.5` of an impact's closed forms, without gravity.
pub fn undamped_problem(hertz: &HertzImpact64) -> ContactProblem {
    ContactProblem {
        law: ForceLaw::Hertz {
            stiffness: hertz.stiffness,
            exponent: 1.5,
        },
        mass_kg: hertz.mass_kg,
        speed_m_s: hertz.speed_m_s,
        gravity_m_s2: 0.0,
    }
}

/// The paper's single impact (coal, R = 0.03 m, on carbon steel at 1 m/s, no gravity) as the
/// bench integrates it.
#[derive(Debug, Clone, Copy)]
pub struct PaperProblems {
    /// The closed forms (`F_max` = 1673.0 N, `t_c` = 343.23 us).
    pub hertz: HertzImpact64,
    /// Undamped Hertz.
    pub undamped: ContactProblem,
    /// Adams IMPACT with `d` = 0.01 mm and the `c_max` that gives `e` = 0.5 at this speed.
    pub adams: ContactProblem,
}

/// [`PaperProblems`]; errors only if the restitution search fails.
pub fn paper_problems() -> Result<PaperProblems, SimError> {
    let hertz = ImpactSpec::paper_scene().hertz()?;
    let undamped = undamped_problem(&hertz);
    let adams_law = crate::physics::law_spec::adams_for_restitution(
        hertz.stiffness,
        1.5,
        1e-5,
        hertz.mass_kg,
        hertz.speed_m_s,
        0.5,
    )?;
    let adams = ContactProblem {
        law: adams_law,
        ..undamped
    };
    Ok(PaperProblems {
        hertz,
        undamped,
        adams,
    })
}

/// Relative errors `(|F_max / F_ref - 1|, |t_c / t_ref - 1|)` of a solution's peak force and
/// contact duration against references in N and s.
pub fn relative_errors(
    solution: &ContactSolution,
    force_ref_n: f64,
    duration_ref_s: f64,
) -> (f64, f64) {
    (
        (solution.peak_force_n / force_ref_n - 1.0).abs(),
        (solution.duration_s / duration_ref_s - 1.0).abs(),
    )
}
