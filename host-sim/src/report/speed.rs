//! Speed figures of host-sim measured in one run on the machine it runs on (`host-sim speed`):
//! the contact integrator's impacts per second on the paper's impact (undamped Hertz and
//! Adams IMPACT with e = 0.5, d = 0.01 mm, c_max from the restitution; one thread) for every
//! method and tolerance of the criterion bench's ladder, with its errors and work (force and
//! Jacobian evaluations), the `ode_solvers` crate's Dop853 on the same Hertz contact (every
//! method's throughput as a ratio to it at equal tolerance, and host-sim's Dop853 against it
//! at equal accuracy, [`crate::report::equal_accuracy`]), the heavily damped Adams
//! contact (c_max = 1 % of k in SI units) for Dopri5, Rodas4, Radau13 and Auto, and the
//! wall time of an end-to-end evaluation (`evaluate`: integrator, sensor chain, kernel,
//! scoring) of N impacts of a scene on every core and, optionally, on one.
//!
//! Errors are relative to the Hertz closed forms (undamped), to Dormand-Prince at
//! rtol = atol = 1e-13 (Adams e = 0.5) and to Rodas4 at 1e-12 (heavy damping), as in
//! `benches/integrator.rs`. Integrator throughput is the
//! best of repeated batches of 100 integrations over the measuring time (the least disturbed
//! batch on a shared machine); the evaluation is timed once. Ratios between figures of one run
//! are what carries over between machines.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result, anyhow};
use coalshock::math::DefaultBackend;
use serde::Serialize;

use crate::physics::integrate::{ContactProblem, Method};
use crate::physics::integrator_cases::{
    BENCH_NEW_TOLERANCES, MethodCase, bench_ladder, heavy_ladder, paper_problems, relative_errors,
};
use crate::report::best_rate::best_rate;
use crate::report::equal_accuracy::{EqualAccuracy, equal_accuracy};
use crate::report::ode_solvers_ref::dop853_hertz;
use crate::scene::{self, SceneFile};
use crate::score::evaluate::{EvalOptions, evaluate};

/// What `host-sim speed` measures and how it prints.
#[derive(Debug, Clone, PartialEq)]
pub struct SpeedOptions {
    /// Impacts of the timed evaluation, split evenly over the scene's classes.
    pub impacts: usize,
    /// Scene of the timed evaluation (`None`: the built-in paper scene, equal to
    /// `scenes/paper.toml`).
    pub scene: Option<PathBuf>,
    /// Measuring time of the integrator per law and method in s.
    pub integrator_seconds: f64,
    /// Also time the evaluation on one thread (the parallel speed-up).
    pub one_thread: bool,
    /// Print one JSON object instead of a table.
    pub json: bool,
}

impl Default for SpeedOptions {
    /// 10^6 impacts of the paper scene, 0.5 s per integrator, on every core only, a table.
    fn default() -> Self {
        Self {
            impacts: 1_000_000,
            scene: None,
            integrator_seconds: 0.5,
            one_thread: false,
            json: false,
        }
    }
}

/// Throughput of the integrator on one contact problem.
#[derive(Debug, Clone, Serialize)]
pub struct IntegratorSpeed {
    /// The law.
    pub law: &'static str,
    /// The method and tolerance.
    pub method: String,
    /// Integrations per second of one thread (best batch).
    pub impacts_per_s: f64,
    /// Relative error of the peak force against the reference.
    pub rel_err_peak_force: f64,
    /// Relative error of the contact duration against the reference.
    pub rel_err_duration: f64,
    /// Force-law evaluations per integration.
    pub force_evals: usize,
    /// Accepted steps per integration.
    pub steps: usize,
    /// Rejected steps per integration.
    pub rejected_steps: usize,
}

/// Wall time of one evaluation.
#[derive(Debug, Clone, Serialize)]
pub struct EvaluateSpeed {
    /// Threads of the pool it ran on.
    pub threads: usize,
    /// Impacts evaluated.
    pub impacts: usize,
    /// Wall time in s.
    pub seconds: f64,
    /// `impacts / seconds`.
    pub impacts_per_s: f64,
}

/// Everything `host-sim speed` measures.
#[derive(Debug, Clone, Serialize)]
pub struct SpeedReport {
    /// The evaluation's scene.
    pub scene: String,
    /// Integrator throughput, Hertz then Adams.
    pub integrator: Vec<IntegratorSpeed>,
    /// host-sim's Dop853 against ode_solvers' at equal accuracy, one row per
    /// [`BENCH_NEW_TOLERANCES`].
    pub equal_accuracy: Vec<EqualAccuracy>,
    /// Evaluation wall times, every core first.
    pub evaluate: Vec<EvaluateSpeed>,
}

/// Integrations per second of `case` on `problem` (the best of batches of 100 over
/// `seconds`), errors against `reference` (`F_max` in N, `t_c` in s) and work.
fn integrator_speed(
    law: &'static str,
    case: &MethodCase,
    problem: &ContactProblem,
    reference: (f64, f64),
    seconds: f64,
) -> Result<IntegratorSpeed> {
    let sol = case.solve(problem)?;
    let (rel_err_peak_force, rel_err_duration) = relative_errors(&sol, reference.0, reference.1);
    let impacts_per_s = best_rate(seconds, || {
        std::hint::black_box(case.solve(std::hint::black_box(problem))?);
        Ok(())
    })?;
    Ok(IntegratorSpeed {
        law,
        method: case.label.clone(),
        impacts_per_s,
        rel_err_peak_force,
        rel_err_duration,
        force_evals: sol.work.force_evals + sol.work.jacobian_evals,
        steps: sol.work.steps,
        rejected_steps: sol.work.rejected_steps,
    })
}

/// The `ode_solvers` crate's Dop853 on the undamped Hertz contact at `rtol = atol = tol`
/// ([`dop853_hertz`]), timed as [`integrator_speed`] times host-sim's methods.
fn ode_solvers_speed(tol: f64, seconds: f64) -> Result<IntegratorSpeed> {
    let failed = || anyhow!("ode_solvers' Dop853 failed at rtol {tol:.0e}");
    let (rel_err_peak_force, rel_err_duration, force_evals) =
        dop853_hertz(tol).ok_or_else(failed)?;
    let impacts_per_s = best_rate(seconds, || {
        std::hint::black_box(dop853_hertz(std::hint::black_box(tol)).ok_or_else(failed)?);
        Ok(())
    })?;
    Ok(IntegratorSpeed {
        law: "Hertz",
        // Its first error is the rebound speed's (it has no peak search).
        method: format!("{ODE_SOLVERS_LABEL} rtol {tol:.0e}"),
        impacts_per_s,
        rel_err_peak_force,
        rel_err_duration,
        force_evals,
        steps: 0,
        rejected_steps: 0,
    })
}

/// The label of the `ode_solvers` rows (their F_max column holds the rebound speed's error).
const ODE_SOLVERS_LABEL: &str = "ode_solvers dop853";

/// Wall time of evaluating `impacts` impacts of `scene` (seed 1, default options) on a pool of
/// `threads` threads (`None`: rayon's default pool).
fn evaluate_speed(
    scene: &SceneFile,
    impacts: usize,
    threads: Option<usize>,
) -> Result<EvaluateSpeed> {
    let opts = EvalOptions {
        n_per_class: (impacts / scene.classes.len()).max(1),
        ..EvalOptions::default()
    };
    let run = || -> Result<EvaluateSpeed> {
        let t = Instant::now();
        let e = evaluate::<DefaultBackend>(scene, &opts)?;
        let seconds = t.elapsed().as_secs_f64();
        let impacts = e.n_per_class * e.classes.len();
        Ok(EvaluateSpeed {
            threads: rayon::current_num_threads(),
            impacts,
            seconds,
            impacts_per_s: impacts as f64 / seconds,
        })
    };
    match threads {
        None => run(),
        Some(n) => rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .context("building a thread pool")?
            .install(run),
    }
}

/// Measures everything (see the module docs).
pub fn measure(args: &SpeedOptions) -> Result<SpeedReport> {
    if args.impacts == 0 {
        return Err(anyhow!("--impacts must be at least 1"));
    }
    if !args.integrator_seconds.is_finite() || args.integrator_seconds <= 0.0 {
        return Err(anyhow!(
            "--integrator-seconds must be a finite time in s above 0 (got {})",
            args.integrator_seconds
        ));
    }
    let scene = match &args.scene {
        Some(p) => scene::load(p).with_context(|| format!("loading {}", p.display()))?,
        None => SceneFile::paper(),
    };
    let p = paper_problems()?;
    let adams_ref = MethodCase::dopri5(1e-13).solve(&p.adams)?;
    let laws = [
        (
            "Hertz",
            &p.undamped,
            (p.hertz.peak_force_n, p.hertz.duration_s),
        ),
        (
            "Adams e = 0.5",
            &p.adams,
            (adams_ref.peak_force_n, adams_ref.duration_s),
        ),
    ];
    let heavy_ref = MethodCase::adaptive(Method::Rodas4, 1e-12).solve(&p.heavy)?;
    let heavy = (heavy_ref.peak_force_n, heavy_ref.duration_s);
    let secs = args.integrator_seconds;
    let mut integrator = Vec::new();
    for (law, problem, reference) in laws {
        for case in bench_ladder() {
            integrator.push(integrator_speed(law, &case, problem, reference, secs)?);
        }
    }
    for &tol in &BENCH_NEW_TOLERANCES {
        integrator.push(ode_solvers_speed(tol, secs)?);
    }
    for case in heavy_ladder() {
        let law = "Adams c_max = 1 % k";
        integrator.push(integrator_speed(law, &case, &p.heavy, heavy, secs)?);
    }
    let equal_accuracy = BENCH_NEW_TOLERANCES
        .iter()
        .map(|&tol| equal_accuracy(&p, tol, 2.0 * secs))
        .collect::<Result<Vec<_>>>()?;
    let mut evaluate = vec![evaluate_speed(&scene, args.impacts, None)?];
    if args.one_thread {
        evaluate.push(evaluate_speed(&scene, args.impacts, Some(1))?);
    }
    Ok(SpeedReport {
        scene: scene.name.clone(),
        integrator,
        equal_accuracy,
        evaluate,
    })
}

/// The report as markdown tables.
pub fn render(r: &SpeedReport) -> String {
    let mut s = String::from(
        "| law | method | impacts/s (one thread) | rel. err F_max | rel. err t_c | force evals \
         / impact | steps | rejected |\n| --- | --- | --- | --- | --- | --- | --- | --- |\n",
    );
    for i in &r.integrator {
        s += &format!(
            "| {} | {} | {:.0} | {:.1e} | {:.1e} | {} | {} | {} |\n",
            i.law,
            i.method,
            i.impacts_per_s,
            i.rel_err_peak_force,
            i.rel_err_duration,
            i.force_evals,
            i.steps,
            i.rejected_steps
        );
    }
    s += &format!(
        "\n| evaluate ({}) | threads | wall time (s) | impacts/s |\n| --- | --- | --- | --- |\n",
        r.scene
    );
    for e in &r.evaluate {
        s += &format!(
            "| {} impacts | {} | {:.1} | {:.0} |\n",
            e.impacts, e.threads, e.seconds, e.impacts_per_s
        );
    }
    s += &ratios(r);
    s += "\n";
    s += &crate::report::equal_accuracy::render(&r.equal_accuracy);
    if let [all, one] = r.evaluate.as_slice() {
        s += &format!(
            "\nspeed-up on {} threads: {:.2}\n",
            all.threads,
            one.seconds / all.seconds
        );
    }
    s
}

/// The undamped Hertz rows at each of [`BENCH_NEW_TOLERANCES`] side by side: each method's
/// work and its throughput as a ratio to ode_solvers' Dop853 at the same tolerance, with the
/// larger of its two errors (so that "equal accuracy" can be read off).
fn ratios(r: &SpeedReport) -> String {
    let methods = [
        "dopri5",
        "dop853",
        "rodas4",
        "radau13",
        "auto",
        ODE_SOLVERS_LABEL,
    ];
    let mut s = String::from(
        "\n| Hertz, rtol | method | error (max of F_max or rebound, t_c) | force evals / impact | \
         impacts/s / ode_solvers dop853 |\n| --- | --- | --- | --- | --- |\n",
    );
    for tol in BENCH_NEW_TOLERANCES {
        let find = |m: &str| {
            let label = format!("{m} rtol {tol:.0e}");
            r.integrator
                .iter()
                .find(|i| i.law == "Hertz" && i.method == label)
        };
        let Some(base) = find(ODE_SOLVERS_LABEL) else {
            continue;
        };
        for m in methods {
            if let Some(i) = find(m) {
                s += &format!(
                    "| {tol:.0e} | {m} | {:.1e} | {} | {:.2} |\n",
                    i.rel_err_peak_force.max(i.rel_err_duration),
                    i.force_evals,
                    i.impacts_per_s / base.impacts_per_s
                );
            }
        }
    }
    s
}

/// `host-sim speed`.
pub fn run(args: &SpeedOptions) -> Result<()> {
    let r = measure(args)?;
    if args.json {
        crate::report::write_json(&r)
    } else {
        crate::report::write_stdout(&render(&r))
    }
}
