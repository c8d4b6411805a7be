//! Checks of the Radau13 stiff integrator, and of Auto, which turns to it on stiff contacts,
//! against independent references: the Hertz closed forms, Dop853 and Rodas4 at tight
//! tolerances (methods that share no step code with Radau13).
//!
//! Run with `--nocapture` to see the measured figures.

use host_sim::hertz64::{HertzImpact64, Material64};
use host_sim::integrate::{
    ContactProblem, ContactSolution, Limits, Method, Tolerance, integrate_contact,
};
use host_sim::law_spec::adams_for_restitution;
use host_sim::laws::{ForceLaw, RestitutionModel};

fn rel(a: f64, b: f64) -> f64 {
    ((a - b) / b).abs()
}

/// The paper's coal sphere (R = 0.03 m) on carbon steel at 1 m/s.
fn paper() -> HertzImpact64 {
    HertzImpact64::new(&Material64::COAL, &Material64::CARBON_STEEL, 0.03, 1.0).unwrap()
}

fn problem(h: &HertzImpact64, law: ForceLaw) -> ContactProblem {
    ContactProblem {
        law,
        mass_kg: h.mass_kg,
        speed_m_s: h.speed_m_s,
        gravity_m_s2: 0.0,
    }
}

fn run(p: &ContactProblem, method: Method, tol: f64) -> ContactSolution {
    integrate_contact(p, method, Tolerance::new(tol), &Limits::default()).unwrap()
}

/// `delta_max` (m), `F_max` (N), `t_c` (s) and the rebound speed (m/s).
fn outputs(s: &ContactSolution) -> [f64; 4] {
    [
        s.delta_max_m,
        s.peak_force_n,
        s.duration_s,
        s.rebound_speed_m_s,
    ]
}

/// The relative errors of `s`'s [`outputs`] against `reference`'s.
fn errors(s: &ContactSolution, reference: &[f64; 4]) -> [f64; 4] {
    let o = outputs(s);
    [0, 1, 2, 3].map(|i| rel(o[i], reference[i]))
}

/// Errors as `[1.2e-10, ...]`.
fn show(errs: &[f64; 4]) -> String {
    let parts: Vec<String> = errs.iter().map(|e| format!("{e:.1e}")).collect();
    format!("[{}]", parts.join(", "))
}

/// Force and Jacobian evaluations (each Jacobian costs about one force evaluation).
fn work(s: &ContactSolution) -> usize {
    s.work.force_evals + s.work.jacobian_evals
}

/// The heavily damped Adams contact (c_max = 1 % of k in SI units, d = 0.01 mm, e about
/// 2.2e-5: a 10-40 us force spike, then a creep of 620 Hertz contact times), against Rodas4
/// at rtol 1e-12: Radau13 at rtol 1e-9 has every output within 1e-8 in at most 1500 force
/// and Jacobian evaluations (measured: 1036; 1052 on `host-sim speed`'s problem, whose
/// `c_max` differs in the last bits), and within 1e-6 at rtol 1e-6. Auto at 1e-9 meets the
/// same 1500 (it turns to Radau13 once the Jacobian's spectral radius passes `STIFF_RHO`
/// during the spike; before that rule it ran Dop853 through the spike, where the step is
/// held by accuracy, not stability, and needed 1541, Dop853's part alone about 950).
#[test]
fn heavy_damping_radau13_meets_the_work_target() {
    let h = paper();
    let p = problem(
        &h,
        ForceLaw::AdamsImpact {
            stiffness: h.stiffness,
            exponent: 1.5,
            c_max_n_s_m: 0.01 * h.stiffness,
            d_m: 1e-5,
        },
    );
    let reference = outputs(&run(&p, Method::Rodas4, 1e-12));
    for (method, tol, bound, budget) in [
        (Method::Radau13, 1e-9, 1e-8, 1500),
        (Method::Radau13, 1e-6, 1e-6, 1000),
        (Method::Auto, 1e-9, 1e-8, 1500),
        (Method::Auto, 1e-6, 1e-6, 1200),
    ] {
        let s = run(&p, method, tol);
        let errs = errors(&s, &reference);
        eprintln!(
            "{method:?} rtol {tol:.0e}: errors (delta_max, F_max, t_c, rebound) {}, \
             {} force + {} Jacobian evaluations, {} steps ({} stiff), {} rejected",
            show(&errs),
            s.work.force_evals,
            s.work.jacobian_evals,
            s.work.steps,
            s.work.stiff_steps,
            s.work.rejected_steps
        );
        assert!(
            errs.iter().all(|&e| e <= bound),
            "{method:?} {tol}: {errs:?}"
        );
        assert!(
            work(&s) <= budget,
            "{method:?} {tol}: {} evaluations",
            work(&s)
        );
        assert!(s.work.stiff_steps > 0);
    }
}

/// Undamped Hertz on the paper scene against the closed forms (F_max = 1673.0 N,
/// t_c = 343.23 us, delta_max, rebound = approach speed): Radau13's error follows the
/// tolerance (at most 2e-6 at rtol 1e-6, 6e-9 at 1e-9, 2e-11 at 1e-12).
#[test]
fn radau13_matches_the_hertz_closed_forms() {
    let h = paper();
    assert!(
        rel(h.peak_force_n, 1673.0) < 1e-4,
        "F_max {}",
        h.peak_force_n
    );
    assert!(rel(h.duration_s, 343.23e-6) < 1e-4, "t_c {}", h.duration_s);
    let p = problem(
        &h,
        ForceLaw::Hertz {
            stiffness: h.stiffness,
            exponent: 1.5,
        },
    );
    let closed = [h.delta_max_m, h.peak_force_n, h.duration_s, h.speed_m_s];
    for (tol, bound) in [(1e-6, 2e-6), (1e-9, 6e-9), (1e-12, 2e-11)] {
        let s = run(&p, Method::Radau13, tol);
        let errs = errors(&s, &closed);
        eprintln!(
            "Radau13 Hertz rtol {tol:.0e}: errors (delta_max, F_max, t_c, rebound) \
             {}, {} evaluations",
            show(&errs),
            work(&s)
        );
        assert!(errs.iter().all(|&e| e <= bound), "{tol}: {errs:?}");
    }
}

/// Auto on the contacts that are not stiff (undamped Hertz and Adams with e = 0.5) never
/// turns to Radau13: its results and force evaluations are Dop853's, bit for bit.
#[test]
fn auto_follows_dop853_where_the_contact_is_not_stiff() {
    let h = paper();
    let adams = adams_for_restitution(h.stiffness, 1.5, 1e-5, h.mass_kg, h.speed_m_s, 0.5);
    let hertz = ForceLaw::Hertz {
        stiffness: h.stiffness,
        exponent: 1.5,
    };
    for law in [hertz, adams.unwrap()] {
        let p = problem(&h, law);
        for tol in [1e-6, 1e-9, 1e-12] {
            let auto = run(&p, Method::Auto, tol);
            let dop853 = run(&p, Method::Dop853, tol);
            assert_eq!(auto.work.stiff_steps, 0);
            assert_eq!(outputs(&auto), outputs(&dop853), "{law:?} {tol}");
            assert_eq!(auto.work.force_evals, dop853.work.force_evals);
        }
    }
}

/// Adams with e = 0.5 (d = 0.01 mm, c_max from the restitution; the kink at delta = d on the
/// way in and out) against Dop853 at rtol 1e-12: Radau13 within 1e-8 at rtol 1e-9 and 1e-5
/// at 1e-6.
#[test]
fn radau13_matches_dop853_on_adams_e_half() {
    let h = paper();
    let law = adams_for_restitution(h.stiffness, 1.5, 1e-5, h.mass_kg, h.speed_m_s, 0.5);
    let p = problem(&h, law.unwrap());
    let reference = outputs(&run(&p, Method::Dop853, 1e-12));
    for (tol, bound) in [(1e-6, 1e-5), (1e-9, 1e-8)] {
        let s = run(&p, Method::Radau13, tol);
        let errs = errors(&s, &reference);
        eprintln!(
            "Radau13 Adams e 0.5 rtol {tol:.0e}: errors {}, {} evaluations, {} kink \
             restarts",
            show(&errs),
            work(&s),
            s.work.kink_restarts
        );
        assert!(errs.iter().all(|&e| e <= bound), "{tol}: {errs:?}");
        assert_eq!(s.work.kink_restarts, 2);
    }
}

/// Heavily damped restitution laws (Hunt-Crossley and Flores with e = 0.05, the force
/// clamped at zero before separation) against Dop853 at rtol 1e-12: Radau13 and Auto at
/// rtol 1e-9 within 1e-8 on every output.
#[test]
fn radau13_matches_dop853_on_heavily_damped_restitution_laws() {
    let h = paper();
    for model in [RestitutionModel::HuntCrossley, RestitutionModel::Flores] {
        let law = ForceLaw::restitution_law(model, h.stiffness, 1.5, 0.05, h.speed_m_s);
        let p = problem(&h, law.unwrap());
        let reference = outputs(&run(&p, Method::Dop853, 1e-12));
        for method in [Method::Radau13, Method::Auto] {
            let s = run(&p, method, 1e-9);
            let errs = errors(&s, &reference);
            eprintln!(
                "{method:?} {model:?} e 0.05 rtol 1e-9: errors {}, {} evaluations, \
                 {} clamp restarts, e {:.3}",
                show(&errs),
                work(&s),
                s.work.clamp_restarts,
                s.restitution()
            );
            assert!(
                errs.iter().all(|&e| e <= 1e-8),
                "{method:?} {model:?}: {errs:?}"
            );
        }
    }
}
