//! Speed figures of host-sim measured in one run on the machine it runs on (`host-sim speed`):
//! the contact integrator's impacts per second on the paper's impact (undamped Hertz and
//! Adams IMPACT with e = 0.5, d = 0.01 mm, c_max from the restitution; one thread) for every
//! method and tolerance of the criterion bench's ladder, with its errors and work, and the
//! wall time of an end-to-end evaluation (`evaluate`: integrator, sensor chain, kernel,
//! scoring) of N impacts of a scene on every core and, optionally, on one.
//!
//! Errors are relative to the Hertz closed forms (undamped) and to Dormand-Prince at
//! rtol = atol = 1e-13 (Adams), as in `benches/integrator.rs`. Integrator throughput is the
//! best of repeated batches of 100 integrations over the measuring time (the least disturbed
//! batch on a shared machine); the evaluation is timed once. Ratios between figures of one run
//! are what carries over between machines.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result, anyhow};
use coalshock::math::DefaultBackend;
use serde::Serialize;

use crate::physics::integrate::ContactProblem;
use crate::physics::integrator_cases::{MethodCase, bench_ladder, paper_problems, relative_errors};
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
    const BATCH: usize = 100;
    let sol = case.solve(problem)?;
    let (rel_err_peak_force, rel_err_duration) = relative_errors(&sol, reference.0, reference.1);
    let start = Instant::now();
    let mut best = f64::INFINITY;
    while best.is_infinite() || start.elapsed().as_secs_f64() < seconds {
        let t = Instant::now();
        for _ in 0..BATCH {
            std::hint::black_box(case.solve(std::hint::black_box(problem))?);
        }
        best = best.min(t.elapsed().as_secs_f64() / BATCH as f64);
    }
    Ok(IntegratorSpeed {
        law,
        method: case.label.clone(),
        impacts_per_s: 1.0 / best,
        rel_err_peak_force,
        rel_err_duration,
        force_evals: sol.work.force_evals,
        steps: sol.work.steps,
        rejected_steps: sol.work.rejected_steps,
    })
}

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
    let mut integrator = Vec::new();
    for (law, problem, reference) in laws {
        for case in bench_ladder() {
            let secs = args.integrator_seconds;
            integrator.push(integrator_speed(law, &case, problem, reference, secs)?);
        }
    }
    let mut evaluate = vec![evaluate_speed(&scene, args.impacts, None)?];
    if args.one_thread {
        evaluate.push(evaluate_speed(&scene, args.impacts, Some(1))?);
    }
    Ok(SpeedReport {
        scene: scene.name.clone(),
        integrator,
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
    if let [all, one] = r.evaluate.as_slice() {
        s += &format!(
            "\nspeed-up on {} threads: {:.2}\n",
            all.threads,
            one.seconds / all.seconds
        );
    }
    s
}

/// `host-sim speed`.
pub fn run(args: &SpeedOptions) -> Result<()> {
    let r = measure(args)?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&r)?);
    } else {
        print!("{}", render(&r));
    }
    Ok(())
}
