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

/// Tolerances of Dop853, Rodas4, Radau13 and Auto in the criterion bench and `host-sim speed`.
pub const BENCH_NEW_TOLERANCES: [f64; 3] = [1e-6, 1e-9, 1e-12];

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

    /// An adaptive `method` at `rtol = atol = tol` (`"dop853 rtol 1e-9"`).
    pub fn adaptive(method: Method, tol: f64) -> Self {
        let name = match method {
            Method::Dopri5 => "dopri5",
            Method::Dop853 => "dop853",
            Method::Rodas4 => "rodas4",
            Method::Radau13 => "radau13",
            Method::Auto => "auto",
            Method::Rk4 { .. } => "rk4",
        };
        Self {
            label: format!("{name} rtol {tol:.0e}"),
            method,
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

/// The criterion bench's ladder: Dopri5 at [`BENCH_DOPRI5_TOLERANCES`], Dop853, Rodas4,
/// Radau13 and Auto at [`BENCH_NEW_TOLERANCES`], RK4 at [`BENCH_RK4_STEPS`].
pub fn bench_ladder() -> Vec<MethodCase> {
    let mut cases = ladder(&BENCH_DOPRI5_TOLERANCES, &[]);
    for method in [
        Method::Dop853,
        Method::Rodas4,
        Method::Radau13,
        Method::Auto,
    ] {
        cases.extend(
            BENCH_NEW_TOLERANCES
                .iter()
                .map(|&t| MethodCase::adaptive(method, t)),
        );
    }
    cases.extend(ladder(&[], &BENCH_RK4_STEPS));
    cases
}

/// The ladder of the heavily damped contact ([`PaperProblems::heavy`]): Dopri5, Rodas4,
/// Radau13 and Auto at rtol 1e-6 and 1e-9 (Dop853 is held by stability there, at 40-50 x
/// Auto's work).
pub fn heavy_ladder() -> Vec<MethodCase> {
    let mut cases = Vec::new();
    for method in [
        Method::Dopri5,
        Method::Rodas4,
        Method::Radau13,
        Method::Auto,
    ] {
        cases.extend([1e-6, 1e-9].map(|t| MethodCase::adaptive(method, t)));
    }
    cases
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
    /// Heavily damped Adams IMPACT: `d` = 0.01 mm, `c_max` = 1 % of `k` in SI units
    /// (`e` about 2.2e-5; stiff: `c_max / m` times the contact time is about 3e4).
    pub heavy: ContactProblem,
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
    let heavy = ContactProblem {
        law: ForceLaw::AdamsImpact {
            stiffness: hertz.stiffness,
            exponent: 1.5,
            c_max_n_s_m: 0.01 * hertz.stiffness,
            d_m: 1e-5,
        },
        ..undamped
    };
    Ok(PaperProblems {
        hertz,
        undamped,
        adams,
        heavy,
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
