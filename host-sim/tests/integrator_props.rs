//! Property tests of the contact integrator over the robustness domain: radius 1e-4 to 1 m,
//! speed 1e-3 to 100 m/s, Young's modulus 1e6 to 1e12 Pa, Poisson's ratio 0 to 0.499, density
//! 100 to 20 000 kg/m^3 (log-uniform but Poisson's ratio), sphere on a carbon-steel plate or on
//! a plate of a second drawn material. Undamped, every impact must stay finite, reproduce the
//! closed forms and conserve kinetic plus elastic energy `m v^2 / 2 + (2/5) k delta^(5/2)`
//! along the whole run to the tolerance's order; damped (Flores, restitution 0.2 to 0.95), it
//! must stay finite and lose energy, never gain it.

use host_sim::hertz64::{HertzImpact64, Material64};
use host_sim::integrate::{ContactProblem, Limits, Method, Tolerance, integrate_contact};
use host_sim::law_spec::LawSpec;
use host_sim::laws::ForceLaw;
use proptest::prelude::*;

fn log_uniform(lo: f64, hi: f64) -> impl Strategy<Value = f64> {
    (0.0f64..=1.0).prop_map(move |t| lo * (hi / lo).powf(t))
}

fn material() -> impl Strategy<Value = Material64> {
    (
        log_uniform(100.0, 20_000.0),
        log_uniform(1e6, 1e12),
        0.0f64..0.499,
    )
        .prop_map(|(density_kg_m3, modulus_pa, poisson)| Material64 {
            density_kg_m3,
            modulus_pa,
            poisson,
        })
}

fn impact() -> impl Strategy<Value = (Material64, Material64, f64, f64)> {
    (
        material(),
        prop_oneof![Just(Material64::CARBON_STEEL), material()],
        log_uniform(1e-4, 1.0),
        log_uniform(1e-3, 100.0),
    )
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, ..ProptestConfig::default() })]

    #[test]
    fn undamped_is_finite_exact_and_conserves_energy((sphere, plate, r, u) in impact()) {
        let h = HertzImpact64::new(&sphere, &plate, r, u).expect("valid inputs");
        let p = ContactProblem {
            law: ForceLaw::Hertz { stiffness: h.stiffness, exponent: 1.5 },
            mass_kg: h.mass_kg,
            speed_m_s: u,
            gravity_m_s2: 0.0,
        };
        let s = integrate_contact(&p, Method::Dopri5, Tolerance::new(1e-9), &Limits::default())
            .expect("integration succeeds");
        for v in [s.delta_max_m, s.peak_force_n, s.duration_s, s.rebound_speed_m_s] {
            prop_assert!(v.is_finite() && v > 0.0, "{s:?}");
        }
        let rel = |a: f64, b: f64| ((a - b) / b).abs();
        prop_assert!(rel(s.peak_force_n, h.peak_force_n) < 1e-7, "F {} {}", s.peak_force_n, h.peak_force_n);
        prop_assert!(rel(s.duration_s, h.duration_s) < 1e-7, "t_c {} {}", s.duration_s, h.duration_s);
        prop_assert!(rel(s.rebound_speed_m_s, u) < 1e-7, "rebound {}", s.rebound_speed_m_s);
        let e0 = 0.5 * h.mass_kg * u * u;
        let times = s.step_times_s();
        for w in times.windows(2) {
            for t in [w[0], 0.5 * (w[0] + w[1])] {
                let (d, dd) = s.state_at(t).expect("inside the contact");
                let e = 0.5 * h.mass_kg * dd * dd + 0.4 * h.stiffness * d * d * d.max(0.0).sqrt();
                prop_assert!(e.is_finite() && (e - e0).abs() <= 1e-7 * e0, "t {t}: E {e} E0 {e0}");
            }
        }
    }

    #[test]
    fn damped_is_finite_and_loses_energy(
        (sphere, plate, r, u) in impact(),
        restitution in 0.2f64..0.95,
    ) {
        let h = HertzImpact64::new(&sphere, &plate, r, u).expect("valid inputs");
        let law = LawSpec::Flores { restitution }.build(&h).expect("valid law");
        let p = ContactProblem { law, mass_kg: h.mass_kg, speed_m_s: u, gravity_m_s2: 0.0 };
        let s = integrate_contact(&p, Method::Dopri5, Tolerance::new(1e-9), &Limits::default())
            .expect("integration succeeds");
        for v in [s.delta_max_m, s.peak_force_n, s.duration_s, s.rebound_speed_m_s] {
            prop_assert!(v.is_finite() && v >= 0.0, "{s:?}");
        }
        prop_assert!(s.rebound_speed_m_s < u, "rebound {} >= {u}", s.rebound_speed_m_s);
        prop_assert!(s.peak_force_n < h.peak_force_n * 1.5, "F {} against {}", s.peak_force_n, h.peak_force_n);
    }
}
