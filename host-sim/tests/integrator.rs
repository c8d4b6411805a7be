//! Checks of host-sim's contact integrator against the Hertz closed forms, an independent ODE
//! solver, quadrature, and the restitution each damping law promises.
//!
//! Run with `--nocapture` to see the measured figures.

use host_sim::hertz64::{
    HERTZ_TC_FACTOR, HertzImpact64, Material64, STANDARD_GRAVITY_M_S2, effective_modulus_pa,
    hertz_stiffness, sphere_mass_kg,
};
use host_sim::impact::{ImpactSpec, simulate};
use host_sim::integrate::{
    ContactProblem, ContactSolution, Limits, Method, SimError, Tolerance, integrate_contact,
};
use host_sim::law_spec::{LawSpec, adams_for_restitution};
use host_sim::laws::{ForceLaw, RestitutionModel, step_cubic};

fn rel(a: f64, b: f64) -> f64 {
    ((a - b) / b).abs()
}

fn paper() -> HertzImpact64 {
    HertzImpact64::new(&Material64::COAL, &Material64::CARBON_STEEL, 0.03, 1.0)
        .expect("paper scene is valid")
}

fn hertz_problem(h: &HertzImpact64, gravity_m_s2: f64) -> ContactProblem {
    ContactProblem {
        law: ForceLaw::Hertz {
            stiffness: h.stiffness,
            exponent: 1.5,
        },
        mass_kg: h.mass_kg,
        speed_m_s: h.speed_m_s,
        gravity_m_s2,
    }
}

fn run(p: &ContactProblem, method: Method, tol: f64) -> ContactSolution {
    integrate_contact(p, method, Tolerance::new(tol), &Limits::default())
        .expect("integration succeeds")
}

/// The paper scene's numbers (physics notes section 1) and Table 3.
#[test]
fn closed_forms_reproduce_the_paper() {
    let h = paper();
    assert!(rel(h.mass_kg, 0.1561) < 5e-4, "m = {}", h.mass_kg);
    assert!(rel(h.stiffness, 1.3285e9) < 5e-5, "k = {}", h.stiffness);
    assert!(
        rel(h.delta_max_m, 1.166e-4) < 5e-4,
        "delta_max = {}",
        h.delta_max_m
    );
    assert!(
        rel(h.peak_force_n, 1673.0) < 1e-3,
        "F_max = {}",
        h.peak_force_n
    );
    assert!(rel(h.duration_s, 343e-6) < 2e-3, "t_c = {}", h.duration_s);
    // t_c = 3.2180655 (m/k)^(2/5) u^(-1/5)
    let alt = 3.218_065_459_719_043 * (h.mass_kg / h.stiffness).powf(0.4);
    assert!(rel(h.duration_s, alt) < 1e-12);
    // Table 3, sandstone and coal at R = 0.015 and 0.040 m.
    let e_ss = effective_modulus_pa(&Material64::SANDSTONE, &Material64::CARBON_STEEL);
    let e_c = effective_modulus_pa(&Material64::COAL, &Material64::CARBON_STEEL);
    for (e, r, k) in [
        (e_ss, 0.015, 2.1091e9),
        (e_ss, 0.040, 3.4441e9),
        (e_c, 0.015, 9.3941e8),
        (e_c, 0.040, 1.5340e9),
    ] {
        assert!(
            rel(hertz_stiffness(e, r), k) < 5e-5,
            "k({r}) = {}",
            hertz_stiffness(e, r)
        );
    }
    assert!(rel(sphere_mass_kg(1000.0, 1.0), 4_188.790_204_786_391) < 1e-15);
}

/// Undamped Dopri5 at rtol = atol = 1e-12 matches the closed forms to <= 1e-9 relative over
/// R in {1e-4, 0.03, 1} m, u in {1e-3, 1, 50} m/s, E in {1e6, 2e11} Pa.
#[test]
fn undamped_matches_closed_forms_at_extremes() {
    let mut worst = [0.0_f64; 5];
    for e_pa in [1e6, 2e11] {
        let mat = Material64 {
            density_kg_m3: 2000.0,
            modulus_pa: e_pa,
            poisson: 0.3,
        };
        for r in [1e-4, 0.03, 1.0] {
            for u in [1e-3, 1.0, 50.0] {
                let h = HertzImpact64::new(&mat, &mat, r, u).expect("valid");
                let s = run(&hertz_problem(&h, 0.0), Method::Dopri5, 1e-12);
                let errs = [
                    rel(s.delta_max_m, h.delta_max_m),
                    rel(s.peak_force_n, h.peak_force_n),
                    rel(s.duration_s, h.duration_s),
                    (s.restitution() - 1.0).abs(),
                    rel(s.impulse_n_s, h.impulse_n_s),
                ];
                for (w, e) in worst.iter_mut().zip(errs) {
                    *w = w.max(e);
                }
                assert!(
                    errs.iter().all(|&e| e <= 1e-9),
                    "E {e_pa} R {r} u {u}: errors {errs:?} steps {}",
                    s.work.steps
                );
            }
        }
    }
    eprintln!(
        "worst relative errors over 18 scenes at rtol 1e-12: delta_max {:.2e}, F_max {:.2e}, \
         t_c {:.2e}, |e - 1| {:.2e}, impulse {:.2e}",
        worst[0], worst[1], worst[2], worst[3], worst[4]
    );
}

/// Undamped: KE + PE is conserved along the run (step ends and continuous output), with and
/// without gravity (PE = 2/5 k delta^2.5 - m g delta).
#[test]
fn undamped_conserves_energy() {
    for (tol, bound) in [(1e-6, 1e-5), (1e-9, 1e-8), (1e-12, 1e-11)] {
        for (r, u) in [(1e-4, 1e-3), (0.03, 1.0), (1.0, 50.0)] {
            for g in [0.0, STANDARD_GRAVITY_M_S2] {
                let h = HertzImpact64::new(&Material64::COAL, &Material64::CARBON_STEEL, r, u)
                    .expect("valid");
                let s = run(&hertz_problem(&h, g), Method::Dopri5, tol);
                let e0 = 0.5 * h.mass_kg * u * u;
                let energy = |t: f64| {
                    let (d, dd) = s.state_at(t).expect("inside the contact");
                    0.5 * h.mass_kg * dd * dd + 0.4 * h.stiffness * d * d * d.sqrt()
                        - h.mass_kg * g * d
                };
                let times = s.step_times_s();
                let mut worst = 0.0_f64;
                for w in times.windows(2) {
                    for t in [w[0], 0.5 * (w[0] + w[1])] {
                        worst = worst.max((energy(t) - e0).abs() / e0);
                    }
                }
                assert!(
                    worst <= bound,
                    "tol {tol} R {r} u {u} g {g}: energy drift {worst:.2e}"
                );
                if r == 0.03 && g == 0.0 {
                    eprintln!(
                        "rtol {tol:.0e}: max |E - E0|/E0 = {worst:.2e} ({} steps)",
                        s.work.steps
                    );
                }
            }
        }
    }
}

fn law_spec(name: &str, e: f64) -> LawSpec {
    match name {
        "HuntCrossley" => LawSpec::HuntCrossley { restitution: e },
        "LankaraniNikravesh" => LawSpec::LankaraniNikravesh { restitution: e },
        "Flores" => LawSpec::Flores { restitution: e },
        "Gonthier" => LawSpec::Gonthier { restitution: e },
        "Tsuji" => LawSpec::Tsuji { restitution: e },
        _ => LawSpec::AdamsRestitution {
            restitution: e,
            d_m: 1e-5,
        },
    }
}

fn restitution_of(spec: &ImpactSpec, law: LawSpec) -> f64 {
    let mut spec = spec.clone();
    spec.law = law;
    spec.tolerance = Tolerance::new(1e-10);
    simulate(&spec).expect("simulates").restitution
}

/// Each restitution law against its target e in {0.3, 0.5, 0.8, 0.95} on the paper scene.
///
/// Stated tolerances on |e_simulated - e_target| (the force clamped at zero):
/// * Adams with `c_max` from [`adams_for_restitution`]: 1e-6 (by construction);
/// * Flores: 0.05 over the whole range; Gonthier: 0.04 over the whole range;
/// * Tsuji: 0.01 for e >= 0.8; at e = 0.3 it rebounds markedly faster (> +0.05);
/// * Hunt-Crossley and Lankarani-Nikravesh: 0.005 at e = 0.95 only; they are derived for e
///   near 1 and miss low targets by a lot (asserted: > +0.15 at e = 0.5, > +0.25 at 0.3).
///
/// The laws other than Adams are scale-free (their restitution does not depend on size,
/// speed or material), which is checked on a second, very different scene.
#[test]
fn restitution_laws_reach_their_target() {
    let other = ImpactSpec::new(Material64::SANDSTONE, Material64::CARBON_STEEL, 0.2, 7.0);
    let targets = [0.3, 0.5, 0.8, 0.95];
    for name in [
        "Adams",
        "Flores",
        "Gonthier",
        "Tsuji",
        "HuntCrossley",
        "LankaraniNikravesh",
    ] {
        let mut line = format!("{name:>18}:");
        for e in targets {
            let got = restitution_of(&ImpactSpec::paper_scene(), law_spec(name, e));
            let dev = got - e;
            line += &format!("  {e} -> {got:.4} ({dev:+.4})");
            match name {
                "Adams" => assert!(dev.abs() <= 1e-6, "Adams {e}: {got}"),
                "Flores" => assert!(dev.abs() <= 0.05, "Flores {e}: {got}"),
                "Gonthier" => assert!(dev.abs() <= 0.04, "Gonthier {e}: {got}"),
                "Tsuji" => {
                    if e >= 0.8 {
                        assert!(dev.abs() <= 0.01, "Tsuji {e}: {got}");
                    }
                    if e == 0.3 {
                        assert!(dev > 0.05, "Tsuji {e}: {got}");
                    }
                }
                _ => {
                    if e == 0.95 {
                        assert!(dev.abs() <= 0.005, "{name} {e}: {got}");
                    }
                    if e == 0.5 {
                        assert!(dev > 0.15, "{name} {e}: expected a large miss, got {got}");
                    }
                    if e == 0.3 {
                        assert!(dev > 0.25, "{name} {e}: expected a large miss, got {got}");
                    }
                }
            }
            if name != "Adams" {
                let again = restitution_of(&other, law_spec(name, e));
                assert!((again - got).abs() < 1e-7, "{name} {e}: {got} vs {again}");
            }
        }
        eprintln!("{line}");
    }
}

/// The Adams law is continuous in delta at delta = d and delta = 0, and never pulls: F >= 0
/// over a grid of (delta, delta_dot) and over simulated runs.
#[test]
fn adams_is_continuous_and_never_pulls() {
    let h = paper();
    let d = 1e-5;
    for c_max in [0.0, 1e3, 1e5, 1.3e7] {
        let law = ForceLaw::AdamsImpact {
            stiffness: h.stiffness,
            exponent: 1.5,
            c_max_n_s_m: c_max,
            d_m: d,
        };
        for dd in [-5.0, -1.0, -1e-3, 0.0, 1e-3, 1.0, 5.0] {
            // Both sides of delta = d.
            let below = law.force(d * (1.0 - 1e-12), dd);
            let at = law.force(d, dd);
            let above = law.force(d * (1.0 + 1e-12), dd);
            let scale = h.stiffness * d.powf(1.5) + c_max * dd.abs();
            assert!(
                (below - at).abs() <= 1e-9 * scale,
                "c {c_max} v {dd}: {below} {at}"
            );
            assert!(
                (above - at).abs() <= 1e-9 * scale,
                "c {c_max} v {dd}: {above} {at}"
            );
            // Both sides of delta = 0: zero at and below, vanishing just above.
            assert_eq!(law.force(0.0, dd), 0.0);
            assert_eq!(law.force(-1e-9, dd), 0.0);
            assert!(law.force(1e-15, dd) <= 1e-12 * scale.max(1.0));
            for i in 0..=200 {
                let delta = -d + i as f64 * 0.1 * d;
                assert!(law.force(delta, dd) >= 0.0);
            }
        }
    }
    // STEP itself: ends and midpoint.
    assert_eq!(step_cubic(0.0, 0.0, 0.0, d, 7.0), 0.0);
    assert_eq!(step_cubic(d, 0.0, 0.0, d, 7.0), 7.0);
    assert!((step_cubic(0.5 * d, 0.0, 0.0, d, 7.0) - 3.5).abs() < 1e-12);
    // Over runs (the recorded series and every step end).
    for law in [
        LawSpec::AdamsRestitution {
            restitution: 0.3,
            d_m: d,
        },
        LawSpec::Adams {
            c_max_n_s_m: 1e5,
            d_m: d,
        },
    ] {
        let mut spec = ImpactSpec::paper_scene();
        spec.law = law;
        spec.record = Some(1e-6);
        let r = simulate(&spec).expect("simulates");
        let series = r.force_series.expect("recorded");
        assert!(series.len() > 100);
        assert!(series.iter().all(|&(_, f)| f >= 0.0));
    }
}

/// Damping lowers F_max below the Hertz value and the gap grows with speed (the paper's
/// Fig. 3): Adams with c_max fixed (chosen for e = 0.8 at 1 m/s) and d = 0.01 mm, u = 1..5.
#[test]
fn damping_lowers_peak_force_more_at_higher_speed() {
    let h1 = paper();
    let law =
        adams_for_restitution(h1.stiffness, 1.5, 1e-5, h1.mass_kg, 1.0, 0.8).expect("bracketed");
    let ForceLaw::AdamsImpact { c_max_n_s_m, .. } = law else {
        panic!("not an Adams law");
    };
    let mut last_gap = 0.0;
    let mut line = format!("c_max = {c_max_n_s_m:.1} N s/m:");
    for u in [1.0, 2.0, 3.0, 4.0, 5.0] {
        let mut spec = ImpactSpec::new(Material64::COAL, Material64::CARBON_STEEL, 0.03, u);
        spec.law = LawSpec::Adams {
            c_max_n_s_m,
            d_m: 1e-5,
        };
        let r = simulate(&spec).expect("simulates");
        let hz = spec.hertz().expect("valid");
        let gap = hz.peak_force_n - r.peak_force_n;
        line += &format!(
            "  u {u}: F {:.0} N vs Hertz {:.0} N, e {:.3}",
            r.peak_force_n, hz.peak_force_n, r.restitution
        );
        assert!(gap > 0.0, "u {u}: damping must lower F_max");
        assert!(gap > last_gap, "u {u}: gap {gap} not above {last_gap}");
        assert!(
            r.pulse_duration_s < hz.duration_s,
            "damping shortens the pulse"
        );
        last_gap = gap;
    }
    eprintln!("{line}");
}

/// Fixed-step RK4 (graded at both ends of the contact) converges at 4th order: halving the
/// step divides the error of t_c by about 16; the errors of F_max and delta_max, read from
/// the cubic Hermite interpolant inside a step (whose error depends on where in the step the
/// peak falls), stay within a factor 4 band of C N^-4, and |e - 1| falls at least as fast.
#[test]
fn rk4_converges_at_fourth_order() {
    let h = paper();
    let p = hertz_problem(&h, 0.0);
    let ns = [50_u32, 100, 200, 400];
    let errs: Vec<[f64; 4]> = ns
        .iter()
        .map(|&n| {
            let s = run(&p, Method::Rk4 { steps_per_tc: n }, 1.0);
            [
                rel(s.duration_s, h.duration_s),
                rel(s.peak_force_n, h.peak_force_n),
                rel(s.delta_max_m, h.delta_max_m),
                (s.restitution() - 1.0).abs(),
            ]
        })
        .collect();
    for (n, e) in ns.iter().zip(&errs) {
        eprintln!(
            "RK4 N = {n}: rel. error t_c {:.2e}, F_max {:.2e}, delta_max {:.2e}, |e - 1| {:.2e}",
            e[0], e[1], e[2], e[3]
        );
    }
    for w in errs.windows(2) {
        let r = w[0][0] / w[1][0];
        eprintln!("t_c error ratio {r:.2}");
        assert!((14.0..=19.0).contains(&r), "t_c ratio {r} not ~16");
    }
    for c in 1..=2 {
        let scaled: Vec<f64> = ns
            .iter()
            .zip(&errs)
            .map(|(&n, e)| e[c] * f64::from(n).powi(4))
            .collect();
        let (lo, hi) = scaled
            .iter()
            .fold((f64::INFINITY, 0.0_f64), |(lo, hi), &x| {
                (lo.min(x), hi.max(x))
            });
        assert!(hi / lo <= 4.0, "component {c}: err N^4 = {scaled:?}");
    }
    for (&n, e) in ns.iter().zip(&errs) {
        assert!(e[3] * f64::from(n).powi(4) <= 2.0 * errs[0][3] * 50f64.powi(4));
    }
}

/// Independent ODE solver: ode_solvers' Dop853 in SI units at rtol 1e-13; the contact end
/// and the maximum penetration are found by bisection on re-integrations from the last
/// output point before the sign change.
mod reference {
    use host_sim::laws::ForceLaw;
    use ode_solvers::{Dop853, System, Vector2};

    type State = Vector2<f64>;

    /// Units of the reference integration: length 1e-4 m, time 1e-4 s (so that one
    /// absolute tolerance suits both components).
    const L: f64 = 1e-4;
    const T: f64 = 1e-4;

    struct Sphere {
        law: ForceLaw,
        mass_kg: f64,
    }

    impl System<f64, State> for Sphere {
        fn system(&self, _t: f64, y: &State, dy: &mut State) {
            dy[0] = y[1];
            dy[1] = -self.law.force(y[0] * L, y[1] * L / T) / self.mass_kg * T * T / L;
        }
    }

    fn integrate(
        law: ForceLaw,
        mass_kg: f64,
        t0: f64,
        y0: State,
        t1: f64,
        n_out: f64,
    ) -> (Vec<f64>, Vec<State>) {
        let mut solver = Dop853::new(
            Sphere { law, mass_kg },
            t0,
            t1,
            (t1 - t0) / n_out,
            y0,
            1e-13,
            1e-15,
        );
        solver.integrate().expect("Dop853 integrates");
        (solver.x_out().clone(), solver.y_out().clone())
    }

    /// First time after `t0` where component `c` of the state changes sign (from positive),
    /// by bisection on re-integrations; returns the time and the state there.
    fn first_crossing(
        law: ForceLaw,
        m: f64,
        t_a: f64,
        y_a: State,
        t_b: f64,
        c: usize,
    ) -> (f64, State) {
        let (mut lo, mut hi) = (t_a, t_b);
        let mut y_lo = y_a;
        for _ in 0..80 {
            // Stop well before the step-size floor of the solver (0.1 h <= eps t).
            if hi - lo <= 1e-13 * hi {
                break;
            }
            let mid = 0.5 * (lo + hi);
            let (_, ys) = integrate(law, m, lo, y_lo, mid, 1.0);
            let y_mid = *ys.last().expect("an output");
            if y_mid[c] > 0.0 {
                lo = mid;
                y_lo = y_mid;
            } else {
                hi = mid;
            }
        }
        (lo, y_lo)
    }

    /// (t_delta_max, delta_max, t_c, rebound speed) of the impact, SI units.
    pub fn impact(law: ForceLaw, m: f64, u_m_s: f64, t_guess_s: f64) -> (f64, f64, f64, f64) {
        let y0 = State::new(0.0, u_m_s * T / L);
        let (ts, ys) = integrate(law, m, 0.0, y0, 1.5 * t_guess_s / T, 3000.0);
        let find = |c: usize| {
            let j = (1..ys.len())
                .find(|&j| ys[j][c] <= 0.0 && ys[j - 1][c] > 0.0)
                .expect("a sign change");
            first_crossing(law, m, ts[j - 1], ys[j - 1], ts[j], c)
        };
        let (t_max, y_max) = find(1);
        let (t_end, y_end) = find(0);
        (t_max * T, y_max[0] * L, t_end * T, -y_end[1] * L / T)
    }
}

/// Cross-check against ode_solvers' Dop853 (independent code, SI units, rtol 1e-13) on the
/// paper scene, undamped and Hunt-Crossley e = 0.8: Dopri5 at rtol 1e-12 agrees to 1e-9.
#[test]
fn agrees_with_ode_solvers_dop853() {
    let h = paper();
    for law in [
        ForceLaw::Hertz {
            stiffness: h.stiffness,
            exponent: 1.5,
        },
        ForceLaw::restitution_law(RestitutionModel::HuntCrossley, h.stiffness, 1.5, 0.8, 1.0)
            .expect("valid"),
    ] {
        let (t_max, d_max, t_c, rebound) = reference::impact(law, h.mass_kg, 1.0, h.duration_s);
        let p = ContactProblem {
            law,
            mass_kg: h.mass_kg,
            speed_m_s: 1.0,
            gravity_m_s2: 0.0,
        };
        for method in [Method::Dopri5, Method::Dop853, Method::Rodas4, Method::Auto] {
            let s = run(&p, method, 1e-12);
            let errs = [
                rel(s.t_delta_max_s, t_max),
                rel(s.delta_max_m, d_max),
                rel(s.duration_s, t_c),
                rel(s.rebound_speed_m_s, rebound),
            ];
            eprintln!(
                "{method:?} vs Dop853 ({law:?}): t_delta_max {:.1e}, delta_max {:.1e}, t_c \
                 {:.1e}, rebound {:.1e}",
                errs[0], errs[1], errs[2], errs[3]
            );
            assert!(errs.iter().all(|&e| e <= 1e-9), "{method:?}: {errs:?}");
        }
    }
}

/// Every adaptive method against the undamped Hertz closed forms on the paper scene: the
/// error falls with the tolerance (at most 6e-9 at rtol 1e-9, 2e-11 at 1e-12: the global
/// error of a per-step control reaches a few times the tolerance, see
/// `dop853_error_follows_the_tolerance`), and Dop853 needs fewer force evaluations than
/// Dopri5 at 1e-12.
#[test]
fn new_methods_match_the_closed_forms() {
    let h = paper();
    let p = hertz_problem(&h, 0.0);
    let mut evals = Vec::new();
    for method in [Method::Dopri5, Method::Dop853, Method::Rodas4, Method::Auto] {
        for (tol, bound) in [(1e-9, 6e-9), (1e-12, 2e-11)] {
            let s = run(&p, method, tol);
            let errs = [
                rel(s.peak_force_n, h.peak_force_n),
                rel(s.duration_s, h.duration_s),
                rel(s.delta_max_m, h.delta_max_m),
                rel(s.rebound_speed_m_s, 1.0),
            ];
            eprintln!(
                "{method:?} rtol {tol:.0e}: F {:.1e}, t_c {:.1e}, delta_max {:.1e}, rebound \
                 {:.1e}; {} force evals, {} Jacobians",
                errs[0], errs[1], errs[2], errs[3], s.work.force_evals, s.work.jacobian_evals
            );
            assert!(
                errs.iter().all(|&e| e <= bound),
                "{method:?} {tol}: {errs:?}"
            );
            if tol == 1e-12 {
                evals.push(s.work.force_evals);
            }
        }
    }
    assert!(
        evals[1] < evals[0],
        "Dop853 {} vs Dopri5 {}",
        evals[1],
        evals[0]
    );
}

/// Heavily damped Adams contact (c_max 0.1 % and 1 % of k in SI units, d = 0.01 mm, e about
/// 1e-4 and 2e-5): [`Method::Auto`] at rtol 1e-9 against Dop853 and Rodas4 at rtol 1e-12
/// (two methods that share no step code with each other): delta_max, F_max, t_c and the
/// rebound within 1e-8, and far less work than Dopri5 at 1e-9, whose absolute tolerance lets
/// the creep's speed and the contact time drift (t_c off by 1e-5 and more).
#[test]
fn heavy_damping_auto_is_accurate_and_cheaper() {
    let h = paper();
    for frac in [0.001, 0.01] {
        let p = ContactProblem {
            law: ForceLaw::AdamsImpact {
                stiffness: h.stiffness,
                exponent: 1.5,
                c_max_n_s_m: frac * h.stiffness,
                d_m: 1e-5,
            },
            mass_kg: h.mass_kg,
            speed_m_s: 1.0,
            gravity_m_s2: 0.0,
        };
        let outputs = |s: &ContactSolution| {
            [
                s.delta_max_m,
                s.peak_force_n,
                s.duration_s,
                s.rebound_speed_m_s,
            ]
        };
        let refs = [Method::Dop853, Method::Rodas4].map(|m| outputs(&run(&p, m, 1e-12)));
        for (a, b) in refs[0].iter().zip(&refs[1]) {
            assert!(rel(*a, *b) <= 1e-9, "references disagree: {refs:?}");
        }
        let auto = run(&p, Method::Auto, 1e-9);
        let errs: Vec<f64> = outputs(&auto)
            .iter()
            .zip(&refs[0])
            .map(|(a, b)| rel(*a, *b))
            .collect();
        let dopri = run(&p, Method::Dopri5, 1e-9);
        let work = auto.work.force_evals + auto.work.jacobian_evals;
        eprintln!(
            "c_max {frac} k: e {:.2e}; Auto 1e-9 errors (delta_max, F, t_c, rebound) {errs:?}, \
             work {work} ({} stiff steps of {}); Dopri5 1e-9 t_c error {:.1e}, {} force evals",
            auto.restitution(),
            auto.work.stiff_steps,
            auto.work.steps,
            rel(dopri.duration_s, refs[0][2]),
            dopri.work.force_evals
        );
        assert!(errs.iter().all(|&e| e <= 1e-8), "{errs:?}");
        assert!(auto.work.stiff_steps > 0);
        assert!(
            3 * work < dopri.work.force_evals,
            "{work} vs {}",
            dopri.work.force_evals
        );
    }
}

/// tanh-sinh quadrature of `integral_0^1 f(x) dx`, where `f` takes `(x, 1 - x)` so that the
/// endpoint singularity can be evaluated without cancellation.
fn tanh_sinh(f: impl Fn(f64, f64) -> f64, step: f64) -> f64 {
    let half_pi = std::f64::consts::FRAC_PI_2;
    let mut sum = 0.0;
    let n = (4.0 / step) as i64;
    for k in -n..=n {
        let t = k as f64 * step;
        let s = half_pi * t.sinh();
        // x = (1 + tanh s)/2, 1 - x = 1/(1 + e^(2 s)), dx/dt = (pi/4) cosh t / cosh^2 s.
        let x = 1.0 / (1.0 + (-2.0 * s).exp());
        let c = 1.0 / (1.0 + (2.0 * s).exp());
        let w = 0.5 * half_pi * t.cosh() / s.cosh().powi(2);
        if w > 0.0 && x > 0.0 && c > 0.0 {
            sum += w * f(x, c);
        }
    }
    sum * step
}

/// The contact-time constant 2 tau = 2 integral_0^1 (1 - x^(5/2))^(-1/2) dx = 2.9432751843
/// by tanh-sinh quadrature (endpoint singularity at x = 1 evaluated through 1 - x), to 1e-9.
#[test]
fn contact_time_constant_by_quadrature() {
    let f = |x: f64, c: f64| {
        // 1 - x^2.5 = -expm1(2.5 ln(1 - c)) without cancellation near x = 1.
        let one_minus = if c < 0.5 {
            -(2.5 * (-c).ln_1p()).exp_m1()
        } else {
            1.0 - x.powf(2.5)
        };
        one_minus.powf(-0.5)
    };
    let coarse = 2.0 * tanh_sinh(f, 1.0 / 16.0);
    let fine = 2.0 * tanh_sinh(f, 1.0 / 64.0);
    eprintln!(
        "2 tau by tanh-sinh: {fine:.15} (h = 1/16: {coarse:.15}); constant {HERTZ_TC_FACTOR:.15}"
    );
    assert!((fine - coarse).abs() < 1e-12);
    assert!((fine - 2.943_275_184_3).abs() < 1e-9);
    assert!((fine - HERTZ_TC_FACTOR).abs() < 1e-12);
}

/// Guards: a step limit gives a typed error, not a loop; bad input gives InvalidParameter; a
/// damped sphere that comes to rest under gravity gives NoSeparation.
#[test]
fn guards_return_typed_errors() {
    let mut spec = ImpactSpec::paper_scene();
    spec.limits.max_steps = 10;
    spec.tolerance = Tolerance::new(1e-12);
    assert!(matches!(
        simulate(&spec),
        Err(SimError::MaxSteps { max_steps: 10, .. })
    ));
    let bad = |edit: &dyn Fn(&mut ImpactSpec)| {
        let mut s = ImpactSpec::paper_scene();
        edit(&mut s);
        match simulate(&s) {
            Err(SimError::InvalidParameter { .. }) => {}
            other => panic!("expected InvalidParameter, got {other:?}"),
        }
    };
    bad(&|s| s.radius_m = 0.0);
    bad(&|s| s.speed_m_s = -1.0);
    bad(&|s| s.speed_m_s = f64::NAN);
    bad(&|s| s.sphere.modulus_pa = f64::INFINITY);
    bad(&|s| s.plate.poisson = 0.7);
    bad(&|s| s.tolerance = Tolerance::new(0.0));
    bad(&|s| s.method = Method::Rk4 { steps_per_tc: 0 });
    bad(&|s| s.law = LawSpec::Flores { restitution: 1.5 });
    bad(&|s| {
        s.law = LawSpec::AdamsRestitution {
            restitution: 1.0,
            d_m: 1e-5,
        }
    });
    bad(&|s| {
        s.law = LawSpec::Adams {
            c_max_n_s_m: -1.0,
            d_m: 1e-5,
        }
    });
    bad(&|s| s.record = Some(0.0));
    // 1 mm/s onto the plate with gravity: g t_c is ten times u, the damped sphere settles.
    let mut s = ImpactSpec::new(Material64::COAL, Material64::CARBON_STEEL, 0.03, 1e-3);
    s.gravity_m_s2 = STANDARD_GRAVITY_M_S2;
    s.law = LawSpec::Flores { restitution: 0.5 };
    s.limits.max_time_tc = 50.0;
    assert!(matches!(simulate(&s), Err(SimError::NoSeparation { .. })));
    // Undamped, the same sphere still leaves with its speed (gravity is conservative).
    s.law = LawSpec::Hertz;
    let r = simulate(&s).expect("undamped separates");
    assert!((r.restitution - 1.0).abs() < 1e-6, "e = {}", r.restitution);
}

/// Gravity (m g into the plate) raises F_max by less than 2e-3 relative on the paper's grid
/// (R 0.015-0.04 m, u 1-5 m/s, coal and sandstone); the largest effect is at low speed.
#[test]
fn gravity_changes_peak_force_by_under_two_per_mille() {
    let mut worst = 0.0_f64;
    for mat in [Material64::COAL, Material64::SANDSTONE] {
        for r in [0.015, 0.04] {
            for u in [1.0, 5.0] {
                let mut spec = ImpactSpec::new(mat, Material64::CARBON_STEEL, r, u);
                let without = simulate(&spec).expect("simulates");
                spec.gravity_m_s2 = STANDARD_GRAVITY_M_S2;
                let with = simulate(&spec).expect("simulates");
                let d = with.peak_force_n / without.peak_force_n - 1.0;
                assert!(d > 0.0, "gravity pushes into the plate");
                worst = worst.max(d);
            }
        }
    }
    eprintln!("largest F_max change from gravity on the paper grid: {worst:.2e}");
    assert!(worst < 2e-3);
}

/// The recorded series starts at zero, never pulls, integrates to the impulse 2 m u, and
/// has the universal shape F_max sin^1.5(pi t / t_c) within 2.4 % of F_max.
#[test]
fn recorded_series_has_the_hertz_shape_and_impulse() {
    let h = paper();
    let mut spec = ImpactSpec::paper_scene();
    let dt = h.duration_s / 400.0;
    spec.record = Some(dt);
    let r = simulate(&spec).expect("simulates");
    let series = r.force_series.expect("recorded");
    assert_eq!(series[0], (0.0, 0.0));
    assert!(series.len() >= 400);
    let mut impulse = 0.0;
    for w in series.windows(2) {
        impulse += 0.5 * (w[0].1 + w[1].1) * (w[1].0 - w[0].0);
    }
    let mut worst_shape = 0.0_f64;
    for &(t, f) in &series {
        assert!(f >= 0.0);
        let model = h.peak_force_n * (std::f64::consts::PI * t / h.duration_s).sin().powf(1.5);
        worst_shape = worst_shape.max((f - model).abs() / h.peak_force_n);
    }
    eprintln!(
        "impulse by trapezoid {:.3e} rel, shape vs sin^1.5 {worst_shape:.4}",
        rel(impulse, h.impulse_n_s)
    );
    assert!(rel(impulse, h.impulse_n_s) < 1e-4);
    // physics notes: "within 2.4 %"; measured 2.43 %.
    assert!(worst_shape < 0.025);
    assert!(rel(r.impulse_n_s, h.impulse_n_s) < 1e-8);
    assert!(rel(r.pulse_duration_s, r.duration_s) < 1e-9);
}

/// Adams: the integrator stops and restarts at delta = d on the way in and out; results
/// converge as the tolerance tightens. With a stiff c_max (1 % of k in SI) the explicit
/// method's work is reported: many force evaluations, and the step limit is a typed error.
#[test]
fn adams_kink_restarts_and_stiff_work_is_reported() {
    let h = paper();
    let adams = |c: f64| ContactProblem {
        law: ForceLaw::AdamsImpact {
            stiffness: h.stiffness,
            exponent: 1.5,
            c_max_n_s_m: c,
            d_m: 1e-5,
        },
        mass_kg: h.mass_kg,
        speed_m_s: 1.0,
        gravity_m_s2: 0.0,
    };
    let p = adams(500.0);
    let tight = run(&p, Method::Dopri5, 1e-12);
    assert_eq!(tight.work.kink_restarts, 2);
    for tol in [1e-6, 1e-9] {
        let s = run(&p, Method::Dopri5, tol);
        let errs = [
            rel(s.peak_force_n, tight.peak_force_n),
            rel(s.duration_s, tight.duration_s),
            rel(s.restitution(), tight.restitution()),
        ];
        eprintln!(
            "Adams c 500 rtol {tol:.0e}: errors F {:.1e}, t_c {:.1e}, e {:.1e}, work {:?}",
            errs[0], errs[1], errs[2], s.work
        );
        assert!(errs.iter().all(|&e| e < 100.0 * tol), "{errs:?}");
    }
    let stiff = adams(0.01 * h.stiffness);
    let s = run(&stiff, Method::Dopri5, 1e-6);
    eprintln!(
        "Adams c = 1 % of k: e {:.2e}, F_max {:.0} N ({:.0} x Hertz), contact {:.3e} s ({:.0} t_c), \
         work {:?}",
        s.restitution(),
        s.peak_force_n,
        s.peak_force_n / h.peak_force_n,
        s.duration_s,
        s.duration_s / h.duration_s,
        s.work
    );
    assert!(s.work.force_evals > 10_000);
    assert!(s.restitution() < 1e-3);
    let limits = Limits {
        max_steps: 1000,
        ..Limits::default()
    };
    assert!(matches!(
        integrate_contact(&stiff, Method::Dopri5, Tolerance::new(1e-6), &limits),
        Err(SimError::MaxSteps { .. })
    ));
}

/// The spec and the report serialise (for a CLI's CSV/JSON output).
#[test]
fn spec_and_report_are_serializable() {
    fn serializable<T: serde::Serialize + Clone + std::fmt::Debug>(_: &T) {}
    let spec = ImpactSpec::paper_scene();
    serializable(&spec);
    serializable(&simulate(&spec).expect("simulates"));
}

/// `ForceLaw::force_gradient` (Rodas4's Jacobian) against central differences of
/// `ForceLaw::force`, for every law on both sides of the Adams ramp's end, while loading and
/// unloading, and 0 where the clamp holds the force at zero.
#[test]
fn force_gradient_matches_finite_differences() {
    let h = paper();
    let k = h.stiffness;
    // Yields at about 5e-5 m, inside the penetrations checked.
    let thornton = host_sim::thornton::ThorntonContact {
        stiffness: k,
        radius_m: 0.03,
        yield_pressure_pa: 1.5e8,
        chi: 0.2,
        impact_speed_m_s: 1.0,
        unloading: None,
    };
    let laws = [
        ForceLaw::Hertz {
            stiffness: k,
            exponent: 1.5,
        },
        ForceLaw::AdamsImpact {
            stiffness: k,
            exponent: 1.5,
            c_max_n_s_m: 5000.0,
            d_m: 5e-5,
        },
        ForceLaw::restitution_law(RestitutionModel::Flores, k, 1.5, 0.5, 1.0).expect("valid"),
        ForceLaw::tsuji(k, h.mass_kg, 0.5).expect("valid"),
        ForceLaw::Thornton(thornton),
        ForceLaw::Thornton(thornton).turned_at(1e-4),
    ];
    let mut checked = 0;
    for law in laws {
        for delta in [2e-5, 4e-5, 8e-5, 1.1e-4] {
            for rate in [0.8, 0.1, -0.05, -0.3] {
                let f = law.force(delta, rate);
                let (gd, gv) = law.force_gradient(delta, rate);
                if f == 0.0 {
                    assert_eq!((gd, gv), (0.0, 0.0), "{law:?} clamped at {delta}, {rate}");
                    continue;
                }
                let (hd, hv) = (1e-6 * delta, 1e-6);
                let fd = (law.force(delta + hd, rate) - law.force(delta - hd, rate)) / (2.0 * hd);
                let fv = (law.force(delta, rate + hv) - law.force(delta, rate - hv)) / (2.0 * hv);
                let scale_d = fd.abs().max(k * delta.sqrt() * 1e-6);
                let scale_v = fv.abs().max(f / rate.abs() * 1e-6);
                assert!(
                    (gd - fd).abs() <= 1e-5 * scale_d,
                    "{law:?} d/ddelta {gd} vs {fd}"
                );
                assert!(
                    (gv - fv).abs() <= 1e-5 * scale_v,
                    "{law:?} d/drate {gv} vs {fv}"
                );
                checked += 1;
            }
        }
    }
    eprintln!("{checked} gradients checked");
    assert!(checked >= 40, "{checked}");
}

/// Dop853 on the undamped Hertz contact over 37 tolerances from 1e-13 to 1e-7 (six per
/// decade), against the closed forms: the largest relative error of `F_max`, `t_c` and the
/// rebound stays within 6 x rtol at every tolerance and within 2 x rtol in geometric mean
/// (one tolerance's error is partly chance, so a sweep, not a point, states the control).
#[test]
fn dop853_error_follows_the_tolerance() {
    let h = paper();
    let p = hertz_problem(&h, 0.0);
    let mut ln_sum = 0.0;
    for k in 0..=36 {
        let tol = 1e-13 * 10f64.powf(f64::from(k) / 6.0);
        let s = run(&p, Method::Dop853, tol);
        let err = rel(s.peak_force_n, h.peak_force_n)
            .max(rel(s.duration_s, h.duration_s))
            .max(rel(s.rebound_speed_m_s, 1.0));
        assert!(err <= 6.0 * tol, "rtol {tol:.2e}: error {err:.2e}");
        ln_sum += (err / tol).ln();
    }
    let geo = (ln_sum / 37.0).exp();
    eprintln!("Dop853 error / rtol, geometric mean over 37 tolerances: {geo:.2}");
    assert!(geo <= 2.0, "{geo}");
}
