//! host-sim's Dop853 against the `ode_solvers` crate's Dop853 at equal accuracy on the
//! paper's undamped Hertz contact: the same error measure for both, host-sim's tolerance
//! chosen so that its error is no larger than ode_solvers' at the tolerance given, and the
//! throughput of both measured in one run.
//!
//! The error of both is `max(|u_r / u - 1|, |t_c / t_Hertz - 1|)`, the rebound speed and the
//! contact time against the closed forms (ode_solvers has no peak search, so `F_max` does not
//! enter). host-sim's tolerances run from `rtol / 10` upwards on a grid of
//! [`GRID_PER_DECADE`] per decade; the one taken is the loosest before the first whose error
//! exceeds ode_solvers' (an error that falls again at a looser tolerance by chance is not
//! taken). ode_solvers integrates to the known contact time and forms no dense output;
//! host-sim locates the end, forms a dense output on every step and searches the peak.

use anyhow::{Result, anyhow};
use serde::Serialize;

use crate::physics::hertz64::HertzImpact64;
use crate::physics::integrate::{ContactSolution, Method};
use crate::physics::integrator_cases::{MethodCase, PaperProblems};
use crate::report::best_rate::best_rate;
use crate::report::ode_solvers_ref::dop853_hertz;

/// host-sim tolerances per decade searched for equal accuracy.
pub const GRID_PER_DECADE: i32 = 6;

/// Timing rounds, alternating between the two solvers (each round `seconds / ROUNDS` each).
const ROUNDS: u32 = 3;

/// One equal-accuracy comparison.
#[derive(Debug, Clone, Serialize)]
pub struct EqualAccuracy {
    /// ode_solvers' `rtol = atol`.
    pub ode_solvers_rtol: f64,
    /// Its error (see the module docs).
    pub ode_solvers_error: f64,
    /// Its force evaluations per impact.
    pub ode_solvers_evals: usize,
    /// host-sim's Dop853 tolerance chosen.
    pub rtol: f64,
    /// host-sim's error there, at most `ode_solvers_error`.
    pub error: f64,
    /// host-sim's force evaluations per impact there.
    pub force_evals: usize,
    /// host-sim's impacts per second over ode_solvers' (one thread each, one run).
    pub throughput_ratio: f64,
}

/// `max(|u_r / u - 1|, |t_c / t_Hertz - 1|)` of an undamped contact (dimensionless).
fn hertz_error(sol: &ContactSolution, hertz: &HertzImpact64) -> f64 {
    let rebound = (sol.rebound_speed_m_s / hertz.speed_m_s - 1.0).abs();
    rebound.max((sol.duration_s / hertz.duration_s - 1.0).abs())
}

/// The comparison on the paper's undamped contact of `p` at ode_solvers' `rtol = atol =
/// tol`, timing each solver for about `seconds` (s).
pub fn equal_accuracy(p: &PaperProblems, tol: f64, seconds: f64) -> Result<EqualAccuracy> {
    let failed = || anyhow!("ode_solvers' Dop853 failed at rtol {tol:.0e}");
    let (err_v, err_t, ode_solvers_evals) = dop853_hertz(tol).ok_or_else(failed)?;
    let ode_solvers_error = err_v.max(err_t);
    let mut chosen = None;
    for k in -GRID_PER_DECADE..=GRID_PER_DECADE {
        let rtol = tol * 10f64.powf(f64::from(k) / f64::from(GRID_PER_DECADE));
        let sol = MethodCase::adaptive(Method::Dop853, rtol).solve(&p.undamped)?;
        let error = hertz_error(&sol, &p.hertz);
        if error > ode_solvers_error {
            break;
        }
        chosen = Some((rtol, error, sol.work.force_evals));
    }
    let (rtol, error, force_evals) = chosen.ok_or_else(|| {
        anyhow!(
            "host-sim's Dop853 at rtol {:.0e} misses ode_solvers' error {ode_solvers_error:.1e}",
            tol / 10.0
        )
    })?;
    let case = MethodCase::adaptive(Method::Dop853, rtol);
    let (mut ours, mut theirs) = (0.0_f64, 0.0_f64);
    let round_s = seconds / f64::from(ROUNDS);
    for _ in 0..ROUNDS {
        ours = ours.max(best_rate(round_s, || {
            std::hint::black_box(case.solve(std::hint::black_box(&p.undamped))?);
            Ok(())
        })?);
        theirs = theirs.max(best_rate(round_s, || {
            std::hint::black_box(dop853_hertz(std::hint::black_box(tol)).ok_or_else(failed)?);
            Ok(())
        })?);
    }
    Ok(EqualAccuracy {
        ode_solvers_rtol: tol,
        ode_solvers_error,
        ode_solvers_evals,
        rtol,
        error,
        force_evals,
        throughput_ratio: ours / theirs,
    })
}

/// The comparisons as a markdown table.
pub fn render(rows: &[EqualAccuracy]) -> String {
    let mut s = String::from(
        "| ode_solvers rtol | its error (max of rebound, t_c) | its force evals | host-sim dop853 \
         rtol | its error | its force evals | impacts/s, host-sim / ode_solvers |\n\
         | --- | --- | --- | --- | --- | --- | --- |\n",
    );
    for r in rows {
        s += &format!(
            "| {:.0e} | {:.1e} | {} | {:.2e} | {:.1e} | {} | {:.2} |\n",
            r.ode_solvers_rtol,
            r.ode_solvers_error,
            r.ode_solvers_evals,
            r.rtol,
            r.error,
            r.force_evals,
            r.throughput_ratio
        );
    }
    s
}
