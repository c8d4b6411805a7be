//! The detector on sampled Hertz pulses `F_max sin^(3/2)(pi t / t_c)`: peak and duration
//! errors over sample phases and rates, from ~3 to ~400 samples per pulse.

use coalshock::detector::{C_AREA, Detection, Detector, shape_fit};
use coalshock::{Material, Range, Scene, SensorChain, Settings, Speed, ParticleClass};

/// `sin^(3/2)` pulse value at time `t` (s) of a pulse starting at `t0` with peak `a`.
fn hertz_pulse(t: f64, t0: f64, tc: f64, a: f64) -> f64 {
    let x = (t - t0) / tc;
    if (0.0..=1.0).contains(&x) {
        a * (std::f64::consts::PI * x).sin().powf(1.5)
    } else {
        0.0
    }
}

fn scene(rate_hz: f32, noise: f32) -> Scene {
    let r = Range::new(0.015, 0.04);
    let u = Speed::Uniform(Range::new(1.0, 5.0));
    Scene::new(
        Material::CARBON_STEEL,
        &[
            ParticleClass::new("coal", Material::COAL, r, u),
            ParticleClass::new("gangue", Material::SANDSTONE, r, u),
        ],
        SensorChain {
            sample_rate_hz: rate_hz,
            force_per_count_n: 1.0,
            noise_rms_counts: noise,
            adc_min: -32768,
            adc_max: 32767,
        },
        Settings::default(),
    )
    .expect("valid scene")
}

#[test]
fn area_constant_matches_quadrature() {
    // Midpoint rule on integral_0^1 sin^1.5(pi x) dx with 2e6 cells (independent of C_AREA).
    let n = 2_000_000;
    let s: f64 = (0..n)
        .map(|i| (std::f64::consts::PI * (i as f64 + 0.5) / n as f64).sin().powf(1.5))
        .sum::<f64>()
        / n as f64;
    assert!((s - C_AREA as f64).abs() < 1e-7, "{s}");
}

/// Worst relative peak and duration error of `shape_fit` over 64 sample phases of noiseless
/// samples (no quantisation), at `spp` samples per pulse.
fn fit_errors(spp: f64) -> (f64, f64) {
    let (mut ep, mut ed) = (0.0f64, 0.0f64);
    for k in 0..64 {
        let t0 = k as f64 / 64.0;
        let ys: Vec<f64> = (0..(spp as usize + 4)).map(|i| hertz_pulse(i as f64, t0, spp, 1000.0)).collect();
        let (imax, &y0) = ys.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1)).unwrap();
        let before = if imax > 0 { ys[imax - 1] } else { 0.0 };
        let after = ys.get(imax + 1).copied().unwrap_or(0.0);
        let sum: f64 = ys.iter().sum();
        let (p, d) = shape_fit(y0 as f32, before as f32, after as f32, sum as f32).unwrap();
        ep = ep.max((p as f64 / 1000.0 - 1.0).abs());
        ed = ed.max((d as f64 / spp - 1.0).abs());
    }
    (ep, ed)
}

#[test]
fn shape_fit_errors_by_rate() {
    for spp in [3.0, 4.0, 5.0, 7.0, 10.0, 15.0, 30.0, 100.0, 400.0] {
        let (ep, ed) = fit_errors(spp);
        println!("{spp:6} samples/pulse: peak {ep:.2e} duration {ed:.2e}");
    }
}
