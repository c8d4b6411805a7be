//! Impacts per second of the contact integrator on the paper scene (coal, R = 0.03 m, on
//! carbon steel at 1 m/s): Dormand-Prince 5(4) at rtol = atol = 1e-3 ... 1e-12 and RK4 at
//! 20 / 50 / 200 steps per contact time, undamped Hertz and Adams IMPACT (c_max for
//! e = 0.5, d = 0.01 mm).
//!
//! Before timing, an accuracy table is printed (markdown): relative error of F_max and t_c
//! against the closed forms (undamped) or against Dopri5 at rtol 1e-13 (Adams), and the work
//! per impact.

use std::hint::black_box;

use criterion::{Criterion, Throughput};
use host_sim::hertz64::HertzImpact64;
use host_sim::impact::ImpactSpec;
use host_sim::integrate::{
    ContactProblem, ContactSolution, Limits, Method, SimError, Tolerance, integrate_contact,
};
use host_sim::laws::ForceLaw;

/// A benchmarked configuration.
struct Case {
    label: String,
    method: Method,
    tol: Tolerance,
}

fn cases() -> Vec<Case> {
    let mut out = Vec::new();
    for rtol in [1e-3, 1e-6, 1e-9, 1e-12] {
        out.push(Case {
            label: format!("dopri5 rtol {rtol:.0e}"),
            method: Method::Dopri5,
            tol: Tolerance::new(rtol),
        });
    }
    for n in [20, 50, 200] {
        out.push(Case {
            label: format!("rk4 {n} steps per t_c"),
            method: Method::Rk4 { steps_per_tc: n },
            tol: Tolerance::default(),
        });
    }
    out
}

fn scene() -> Result<(HertzImpact64, ContactProblem, ContactProblem), SimError> {
    let hertz = ImpactSpec::paper_scene().hertz()?;
    let undamped = ContactProblem {
        law: ForceLaw::Hertz {
            stiffness: hertz.stiffness,
            exponent: 1.5,
        },
        mass_kg: hertz.mass_kg,
        speed_m_s: hertz.speed_m_s,
        gravity_m_s2: 0.0,
    };
    let adams_law = ForceLaw::adams_for_restitution(
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
    Ok((hertz, undamped, adams))
}

fn solve(p: &ContactProblem, c: &Case) -> Result<ContactSolution, SimError> {
    integrate_contact(p, c.method, c.tol, &Limits::default())
}

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
    for c in cases() {
        for (name, p, f_ref, t_ref) in [
            ("undamped", undamped, hertz.peak_force_n, hertz.duration_s),
            (
                "adams e=0.5",
                adams,
                reference.peak_force_n,
                reference.duration_s,
            ),
        ] {
            match solve(p, &c) {
                Ok(s) => println!(
                    "| {name} | {} | {:.1e} | {:.1e} | {} | {} | {} |",
                    c.label,
                    (s.peak_force_n / f_ref - 1.0).abs(),
                    (s.duration_s / t_ref - 1.0).abs(),
                    s.work.force_evals,
                    s.work.steps,
                    s.work.rejected_steps
                ),
                Err(e) => println!("| {name} | {} | error: {e} | | | | |", c.label),
            }
        }
    }
    Ok(())
}

fn main() {
    let (hertz, undamped, adams) = match scene() {
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
        for c in cases() {
            group.bench_function(c.label.as_str(), |b| {
                b.iter(|| solve(black_box(&problem), &c).map(|s| s.peak_force_n))
            });
        }
        group.finish();
    }
    crit.final_summary();
}
