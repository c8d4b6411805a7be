//! `host-sim tradeoff`, the Pareto fronts: which cost-loss points no other point beats, and the
//! points of each plot.

use serde::Serialize;

use crate::report::tradeoff::results::Tradeoff;

/// `true` for each point `(cost, loss)` that no other point dominates (both minimised: `q`
/// dominates `p` when `q.cost <= p.cost`, `q.loss <= p.loss` and one of them is smaller).
/// Non-finite points are never on the front.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<bool> {
    points
        .iter()
        .map(|&(c, l)| {
            c.is_finite()
                && l.is_finite()
                && !points.iter().any(|&(c2, l2)| {
                    c2.is_finite() && l2.is_finite() && c2 <= c && l2 <= l && (c2 < c || l2 < l)
                })
        })
        .collect()
}

/// One point of a Pareto plot.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ParetoPoint {
    /// The plot (`backend`, `grid`, `integrator`, `sample_rate`).
    pub plot: &'static str,
    /// The series within the plot (a front is computed per plot and series).
    pub series: String,
    /// The knob's setting.
    pub setting: String,
    /// Cost (minimised).
    pub cost: f64,
    /// Its unit.
    pub cost_unit: &'static str,
    /// Loss (minimised).
    pub loss: f64,
    /// Its unit.
    pub loss_unit: &'static str,
    /// Whether no point of the same plot and series dominates it.
    pub on_front: bool,
}

/// Adds the points `(setting, cost, loss)` of one plot and series to `out`, each marked
/// whether it is on the series' front.
fn push_plot(
    out: &mut Vec<ParetoPoint>,
    plot: &'static str,
    series: &str,
    (cost_unit, loss_unit): (&'static str, &'static str),
    pts: Vec<(String, f64, f64)>,
) {
    let front = pareto_front(&pts.iter().map(|p| (p.1, p.2)).collect::<Vec<_>>());
    for ((setting, cost, loss), on_front) in pts.into_iter().zip(front) {
        out.push(ParetoPoint {
            plot,
            series: series.to_string(),
            setting,
            cost,
            cost_unit,
            loss,
            loss_unit,
            on_front,
        });
    }
}

impl Tradeoff {
    /// The points of the Pareto plots, with the front of each plot and series:
    /// backend (ns per quiet sample, max rel. error of `F_max`), grid (build us,
    /// `|bayes_error - reference|`), integrator (us per impact, max of the `F_max` and `t_c`
    /// errors; one series for all methods), sample rate per scene (Cortex-M4F instructions
    /// per second of signal, `1 - forced-choice accuracy`).
    pub fn pareto_points(&self) -> Vec<ParetoPoint> {
        let mut out = Vec::new();
        let mut push = |plot, series: &str, cost_unit, loss_unit, pts| {
            push_plot(&mut out, plot, series, (cost_unit, loss_unit), pts)
        };
        push(
            "backend",
            "paper",
            "host ns per quiet sample",
            "max rel. error F_max",
            self.backends
                .iter()
                .map(|b| (b.backend.to_string(), b.quiet_ns, b.max_rel_err_force))
                .collect(),
        );
        push(
            "grid",
            "paper",
            "host us per scene build",
            "abs. error of bayes_error",
            self.grids
                .iter()
                .map(|g| (g.grid.to_string(), g.build_us, g.bayes_error_err))
                .collect(),
        );
        push(
            "integrator",
            "all methods",
            "host us per impact",
            "max rel. error F_max, t_c",
            self.integrator
                .iter()
                .map(|r| {
                    (
                        r.label.clone(),
                        1e6 / r.impacts_per_s,
                        r.max_rel_err_force.max(r.max_rel_err_duration),
                    )
                })
                .collect(),
        );
        for (scene, rows) in &self.rates {
            push(
                "sample_rate",
                scene,
                "M4F instructions per s of signal (est.)",
                "1 - forced-choice accuracy",
                rows.iter()
                    .map(|r| {
                        (
                            format!("{} Hz", r.sample_rate_hz),
                            r.m4_insns_per_signal_s,
                            1.0 - r.accuracy.forced_choice,
                        )
                    })
                    .collect(),
            );
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pareto_front_of_a_small_set() {
        let pts = [
            (1.0, 5.0),
            (2.0, 3.0),
            (3.0, 3.0),
            (4.0, 1.0),
            (5.0, 2.0),
            (f64::NAN, 0.0),
        ];
        assert_eq!(pareto_front(&pts), [true, true, false, true, false, false]);
    }
}
