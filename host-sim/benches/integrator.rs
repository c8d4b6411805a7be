//! Impacts per second of the contact integrator on the paper scene (coal, R = 0.03 m, on
//! carbon steel at 1 m/s): Dormand-Prince 5(4) at rtol = atol = 1e-3 ... 1e-12, Dop853,
//! Rodas4, Radau13 and Auto at 1e-6, 1e-9 and 1e-12, and RK4 at 20 / 50 / 200 steps per
//! contact time, undamped Hertz and Adams IMPACT (c_max for e = 0.5, d = 0.01 mm); and the
//! ode_solvers crate's Dop853 on the undamped contact at 1e-6, 1e-9 and 1e-12.
//!
//! Before timing, an accuracy table is printed (markdown): relative error of F_max and t_c
//! against the closed forms (undamped) or against Dopri5 at rtol 1e-13 (Adams), and the work
//! per impact.

use std::hint::black_box;

use criterion::{Criterion, Throughput};
use host_sim::hertz64::HertzImpact64;
use host_sim::integrate::{ContactProblem, Limits, Method, SimError, Tolerance, integrate_contact};
use host_sim::integrator_cases::{
    BENCH_NEW_TOLERANCES, PaperProblems, bench_ladder, paper_problems, relative_errors,
};
use host_sim::laws::ForceLaw;
use host_sim::report::ode_solvers_ref::dop853_hertz;

fn accuracy_table(
    hertz: &HertzImpact64,
    undamped: &ContactProblem,
    adams: &ContactProblem,
) -> Result<(), SimError> {
    let reference = integrate_contact(
        adams,
        Method::Dopri5,
        Tolerance::new(1e-13),
        &Limits::default(),
    )?;
    if let ForceLaw::AdamsImpact { c_max_n_s_m, .. } = adams.law {
        println!(
            "Adams: c_max = {c_max_n_s_m:.2} N s/m, d = 1e-5 m; reference (Dopri5 rtol 1e-13): \
             F_max = {:.6} N, t_c = {:.6e} s, e = {:.6}",
            reference.peak_force_n,
            reference.duration_s,
            reference.restitution()
        );
    }
    println!("| law | method | rel. err F_max | rel. err t_c | force evals | steps | rejected |");
    println!("| --- | --- | --- | --- | --- | --- | --- |");
    for c in bench_ladder() {
        for (name, p, f_ref, t_ref) in [
            ("undamped", undamped, hertz.peak_force_n, hertz.duration_s),
            (
                "adams e=0.5",
                adams,
                reference.peak_force_n,
                reference.duration_s,
            ),
        ] {
            match c.solve(p) {
                Ok(s) => {
                    let (e_f, e_t) = relative_errors(&s, f_ref, t_ref);
                    println!(
                        "| {name} | {} | {e_f:.1e} | {e_t:.1e} | {} | {} | {} |",
                        c.label, s.work.force_evals, s.work.steps, s.work.rejected_steps
                    )
                }
                Err(e) => println!("| {name} | {} | error: {e} | | | | |", c.label),
            }
        }
    }
    Ok(())
}

fn main() {
    let PaperProblems {
        hertz,
        undamped,
        adams,
        ..
    } = match paper_problems() {
        Ok(s) => s,
        Err(e) => {
            eprintln!("cannot set up the paper scene: {e}");
            std::process::exit(1);
        }
    };
    if let Err(e) = accuracy_table(&hertz, &undamped, &adams) {
        eprintln!("accuracy table failed: {e}");
        std::process::exit(1);
    }
    let mut crit = Criterion::default().configure_from_args();
    for (group_name, problem) in [("undamped", undamped), ("adams", adams)] {
        let mut group = crit.benchmark_group(group_name);
        group.throughput(Throughput::Elements(1));
        for c in bench_ladder() {
            group.bench_function(c.label.as_str(), |b| {
                b.iter(|| c.solve(black_box(&problem)).map(|s| s.peak_force_n))
            });
        }
        group.finish();
    }
    // The same undamped contact integrated by the ode_solvers crate's Dop853 (no event
    // location; see host_sim::report::ode_solvers_ref).
    let mut group = crit.benchmark_group("undamped");
    group.throughput(Throughput::Elements(1));
    for tol in BENCH_NEW_TOLERANCES {
        group.bench_function(format!("ode_solvers dop853 rtol {tol:.0e}"), |b| {
            b.iter(|| dop853_hertz(black_box(tol)))
        });
    }
    group.finish();
    crit.final_summary();
}
