//! The `ode_solvers` crate's Dop853 on the undamped Hertz contact, as `host-sim speed` and the
//! criterion bench time it against host-sim's own methods.
//!
//! It integrates the same scaled equation as host-sim (`x = delta / delta_max`,
//! `v = delta' / u`, `tau = t / t_c`: `dx/dtau = C v`, `dv/dtau = -1.25 C x^1.5` with
//! `C = 2.9432751843247` for undamped Hertz) at `rtol = atol = tol` from first contact over
//! exactly one Hertz contact time, to the step that ends there (its sparse output: in
//! ode_solvers 0.6.2 the dense output at the interval's end is off, `x(1) = -0.058` at
//! rtol 1e-9, while the step's own end is right). It has no event location and no dense
//! output is formed (host-sim's methods form theirs on every step, Dop853 at 3 more
//! evaluations per step); its errors are read where the closed forms put the end:
//! `|v(1) + 1|` for the rebound speed, `|x(1)| / (C |v(1)|)` for the contact time.

use ode_solvers::{Dop853, OutputType, System, Vector2};

use crate::physics::hertz64::HERTZ_TC_FACTOR;

/// The scaled undamped Hertz contact `dx/dtau = C v`, `dv/dtau = -1.25 C max(x, 0)^1.5`
/// (`1.25 = (n + 1) / 2` makes `x = 1` the turning point).
struct ScaledHertz;

impl System<f64, Vector2<f64>> for ScaledHertz {
    fn system(&self, _tau: f64, y: &Vector2<f64>, dy: &mut Vector2<f64>) {
        let x = y[0].max(0.0);
        dy[0] = HERTZ_TC_FACTOR * y[1];
        dy[1] = -1.25 * HERTZ_TC_FACTOR * x * x.sqrt();
    }
}

/// One run of ode_solvers' Dop853 at `rtol = atol = tol`: `(relative error of the rebound
/// speed, relative error of t_c, force evaluations)`; `None` if the solver fails.
pub fn dop853_hertz(tol: f64) -> Option<(f64, f64, usize)> {
    let mut solver = Dop853::new(ScaledHertz, 0.0, 1.0, 1.0, Vector2::new(0.0, 1.0), tol, tol);
    solver.set_output(OutputType::Sparse);
    let stats = solver.integrate().ok()?;
    let end = solver.y_out().last()?;
    let err_v = (end[1] + 1.0).abs();
    let err_t = (end[0] / (HERTZ_TC_FACTOR * end[1])).abs();
    Some((err_v, err_t, stats.num_eval as usize))
}
