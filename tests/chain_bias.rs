//! The Hertz pulse spectrum the chain-bias bound integrates against, recomputed here by
//! quadrature in f64; and the bound's classification side: a chain's tolerance widens the
//! noise (lower posteriors) and leaves the chosen class alone.

mod common;

use coalshock::chain_bias::{ChainSpread, HERTZ_SPECTRUM, STEP_V};
use coalshock::{
    Accelerometer, ChainDynamics, ChainTolerance, Measurement, Scene, SensorChain, Verdict,
};

/// `int_{-1/2}^{1/2} cos^(3/2)(pi x) cos(v x) dx` by composite Simpson on `x = sin`-stretched
/// nodes: with `x = (1 - cos(pi s)) / 4` on `s in [0, 1]` the end point singularity of the
/// `3/2` power is smoothed, and 4000 panels reach 1e-12.
fn spectrum(v: f64) -> f64 {
    let n = 4000;
    let f = |s: f64| {
        let x = 0.25 * (1.0 - (std::f64::consts::PI * s).cos());
        let dx = 0.25 * std::f64::consts::PI * (std::f64::consts::PI * s).sin();
        2.0 * (std::f64::consts::PI * x).sin().powf(1.5) * (v * (0.5 - x)).cos() * dx
    };
    common::simpson(f, n)
}

#[test]
fn hertz_spectrum_table_is_the_quadrature() {
    for (k, &s) in HERTZ_SPECTRUM.iter().enumerate() {
        let v = k as f64 * STEP_V as f64;
        let exact = spectrum(v);
        assert!(
            (s as f64 - exact).abs() < 2e-7,
            "v {v}: {s} against {exact}"
        );
    }
    // The pulse's peak is 1: (1 / pi) int_0^inf S dv = 1; the table's range holds 1 - 1e-4.
    let trapezoid: f64 = HERTZ_SPECTRUM.iter().map(|&s| s as f64).sum::<f64>()
        - 0.5 * (HERTZ_SPECTRUM[0] + HERTZ_SPECTRUM[128]) as f64;
    assert!((trapezoid * STEP_V as f64 / std::f64::consts::PI - 1.0).abs() < 2e-4);
}

fn mems_scene(tolerance: ChainTolerance) -> Scene {
    let paper: Scene = Scene::paper().unwrap();
    let dynamics = ChainDynamics::RIGID
        .with_accelerometer(Accelerometer {
            frequency_hz: 6300.0,
            damping_ratio: 0.7,
        })
        .with_tolerance(tolerance)
        .unwrap();
    let sensor: SensorChain = SensorChain {
        sample_rate_hz: 26_667.0,
        ..*paper.sensor()
    }
    .with_dynamics(dynamics)
    .unwrap();
    Scene::new(*paper.plate(), paper.classes(), sensor, *paper.settings()).unwrap()
}

#[test]
fn a_tolerance_lowers_the_posterior_and_keeps_the_class() {
    let exact = mems_scene(ChainTolerance::EXACT);
    let known = mems_scene(ChainTolerance::IDENTIFIED);
    assert!(
        exact
            .chain_bias()
            .points()
            .iter()
            .all(|b| *b == ChainSpread::ZERO)
    );
    // Shorter pulses lie nearer the accelerometer's resonance: larger bias.
    let p = known.chain_bias().points().map(|b| b.sigma_ln_force());
    assert!(p.windows(2).all(|w| w[0] > w[1]) && p[0] > 0.05, "{p:?}");
    let mut lowered = 0;
    for (force_n, duration_s) in [(2000.0, 1.6e-4), (9000.0, 2.0e-4), (30_000.0, 3.0e-4)] {
        let m = Measurement {
            peak_force_n: force_n,
            duration_s,
            sigma_ln_force: 0.01,
            sigma_ln_duration: 0.01,
            cov_ln: -1e-4,
            asymmetry: 0.0,
            trigger_margin: f32::INFINITY,
            #[cfg(feature = "pulse_shape")]
            shape_fitted: false,
        };
        let (a, b) = (exact.classify(&m), known.classify(&m));
        assert_eq!(a.forced_choice(), b.forced_choice());
        let post = |v: Verdict| match v {
            Verdict::Class { posterior, .. } | Verdict::Ambiguous { posterior, .. } => posterior,
            _ => panic!("{v:?}"),
        };
        // Inside the classes' overlap the posterior is the priors' and densities' ratio;
        // widening the noise moves it there by a few thousandths either way, and lowers it
        // wherever one class's edge is near.
        assert!(
            post(b) <= post(a) + 5e-3,
            "{force_n} {duration_s}: {a:?} {b:?}"
        );
        lowered += (post(b) < post(a) - 1e-3) as usize;
    }
    assert!(lowered >= 1);
}
