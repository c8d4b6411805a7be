//! `SampledPhase`'s lookup: a table filled from a plane `p(ln n, a) = c0 + c1 ln n + c2 a`
//! (every row with its own asymmetry range) reads the plane back exactly between its points
//! (bilinear interpolation is exact on a plane), holds it at the ends of a row's range and
//! below the first row, and reads nothing beyond the last row; the scene check refuses
//! values out of range; the neighbour asymmetry is `(after - before) / max`; the measured
//! duration's noise, which moves where the table is read, is stated.
#![cfg(feature = "sampled_phase")]

use coalshock::sampled_phase::{
    PHASE_COLUMNS, PHASE_FIRST_N, PHASE_ROWS, PHASE_STEP, SampledPhase, neighbour_asymmetry,
};
use coalshock::{Measurement, Scene};

mod common;

fn plane(ln_n: f32, a: f32) -> f32 {
    0.05 - 0.02 * ln_n + 0.1 * a
}

fn table() -> SampledPhase {
    let mut t = SampledPhase::NONE;
    for k in 0..PHASE_ROWS {
        let ln_n = (PHASE_FIRST_N * PHASE_STEP.powi(k as i32)).ln();
        let (lo, hi) = (-0.5 + 0.03 * k as f32, 0.4 - 0.02 * k as f32);
        t.asymmetry[k] = [lo, hi];
        for j in 0..PHASE_COLUMNS {
            let a = lo + (hi - lo) * j as f32 / (PHASE_COLUMNS - 1) as f32;
            t.ln_force[k][j] = plane(ln_n, a);
            t.ln_duration[k][j] = -plane(ln_n, a);
            t.sigma_ln_force[k][j] = 0.01;
            t.sigma_ln_duration[k][j] = 0.02;
        }
    }
    t
}

#[test]
fn lookup_is_exact_on_a_plane_and_held_at_the_ends() {
    let t = table();
    // Between rows 2 and 3 (n 2.5 .. 3.125), a inside both rows' ranges: the plane, to f32
    // rounding, as the row ranges differ and each row interpolates on its own axis.
    for (n, a) in [(2.8f32, 0.1f32), (2.6, -0.3), (5.0, 0.0), (11.0, 0.2)] {
        let (lf, lt, sf, st) = t.at(n.ln(), a).expect("inside the table");
        assert!((lf - plane(n.ln(), a)).abs() < 1e-5, "{n} {a} {lf}");
        assert!((lt + plane(n.ln(), a)).abs() < 1e-5);
        assert!((sf - 0.01).abs() < 1e-7 && (st - 0.02).abs() < 1e-7);
    }
    // Below the first row: held at row 0; beyond a row's asymmetry range: held at its end.
    let first = PHASE_FIRST_N.ln();
    let (lf, ..) = t.at((1.2f32).ln(), 0.0).unwrap();
    assert!((lf - plane(first, 0.0)).abs() < 1e-5);
    let (lf, ..) = t.at(first, 0.9).unwrap();
    assert!((lf - plane(first, 0.4)).abs() < 1e-5);
    // Beyond the last row (11.9 samples) and for the empty table: nothing.
    assert!(t.at((12.5f32).ln(), 0.0).is_none());
    assert!(t.at(f32::NAN, 0.0).is_none());
    assert!(SampledPhase::NONE.at((3.0f32).ln(), 0.0).is_none());
}

#[test]
fn check_refuses_out_of_range_tables() {
    assert!(table().check().is_ok());
    let mut t = table();
    t.sigma_ln_force[3][4] = -0.1;
    assert!(t.check().is_err());
    let mut t = table();
    t.ln_duration[0][0] = f32::NAN;
    assert!(t.check().is_err());
    let mut t = table();
    t.asymmetry[5] = [0.3, -0.3];
    assert!(t.check().is_err());
}

#[test]
fn neighbour_asymmetry_is_the_normalised_difference() {
    assert_eq!(neighbour_asymmetry(2.0, 10.0, 7.0), 0.5);
    assert_eq!(neighbour_asymmetry(7.0, 10.0, 2.0), -0.5);
    assert_eq!(neighbour_asymmetry(1.0, 0.0, 3.0), 0.0);
    assert_eq!(neighbour_asymmetry(-50.0, 1.0, 50.0), 1.0);
}

/// The phase table is read at the samples per pulse the measured duration gives, so the
/// duration's noise moves the correction: the Hertz-equivalent measurement states the noise
/// carried through the table's slopes in `ln n` (with the table's own spreads in quadrature).
/// Against a Monte Carlo of `hertz_equivalent` itself on a steep table (`ln F` falls 0.25 and
/// `ln t_c` rises 0.2 per unit `ln n`, at 4 samples per pulse): 20 000 measurements drawn with
/// the stated noise (`sigma ln F` 0.05, `sigma ln t_c` 0.08, covariance -0.002) give the
/// spreads and the covariance of the corrected logs within 5 % of what it states, less the
/// table's spreads. Taking the measurement's noise through unchanged, as before, misses the
/// force's spread by over 10 %.
#[test]
fn the_duration_noise_moves_the_sampling_correction_and_is_stated() {
    let paper = Scene::<4>::paper().unwrap();
    let mut settings = *paper.settings();
    let mut table = SampledPhase::NONE;
    let ln_mid = 6.0f32.ln();
    for k in 0..PHASE_ROWS {
        let ln_n = (PHASE_FIRST_N * PHASE_STEP.powi(k as i32)).ln();
        table.asymmetry[k] = [-0.5, 0.5];
        for j in 0..PHASE_COLUMNS {
            table.ln_force[k][j] = -0.25 * (ln_n - ln_mid);
            table.ln_duration[k][j] = 0.2 * (ln_n - ln_mid);
            table.sigma_ln_force[k][j] = 0.01;
            table.sigma_ln_duration[k][j] = 0.02;
        }
    }
    settings.sampled_phase = table;
    let scene =
        Scene::<4>::new(*paper.plate(), paper.classes(), *paper.sensor(), settings).unwrap();
    let rate = paper.sensor().sample_rate_hz;
    let (sf, st, c) = (0.05f32, 0.08f32, -0.002f32);
    let m = Measurement {
        peak_force_n: 2000.0,
        duration_s: 4.0 / rate,
        sigma_ln_force: sf,
        sigma_ln_duration: st,
        cov_ln: c,
        asymmetry: 0.0,
        trigger_margin: f32::INFINITY,
        #[cfg(feature = "pulse_shape")]
        shape_fitted: false,
    };
    let stated = scene.hertz_equivalent(&m);
    let mut rng = common::Rng::new(0x51A7_E5EE_D5EE_D001);
    let (mut xs, mut ys) = (Vec::new(), Vec::new());
    let rho = (c / (sf * st)) as f64;
    for _ in 0..20_000 {
        let (z1, z2) = (rng.normal(), rng.normal());
        let e = sf as f64 * z1;
        let d = st as f64 * (rho * z1 + (1.0 - rho * rho).sqrt() * z2);
        let drawn = Measurement {
            peak_force_n: (2000.0 * e.exp()) as f32,
            duration_s: (4.0 / rate as f64 * d.exp()) as f32,
            ..m
        };
        let h = scene.hertz_equivalent(&drawn);
        xs.push((h.peak_force_n as f64).ln());
        ys.push((h.duration_s as f64).ln());
    }
    let (vx, vy, cxy) = common::variances_and_covariance(&xs, &ys);
    // The stated noise less the table's own spreads (0.01 and 0.02, and -0.01^2 of covariance).
    let sx = (stated.sigma_ln_force as f64).powi(2) - 1e-4;
    let sy = (stated.sigma_ln_duration as f64).powi(2) - 4e-4;
    let sc = stated.cov_ln as f64 + 1e-4;
    println!(
        "spread ln F {:.4} stated {:.4}; ln t {:.4} stated {:.4}; cov {cxy:+.2e} stated {sc:+.2e}",
        vx.sqrt(),
        sx.sqrt(),
        vy.sqrt(),
        sy.sqrt()
    );
    assert!((sx.sqrt() / vx.sqrt() - 1.0).abs() < 0.05);
    assert!((sy.sqrt() / vy.sqrt() - 1.0).abs() < 0.05);
    assert!((sc - cxy).abs() < 0.05 * (vx * vy).sqrt());
    assert!((sf as f64 / vx.sqrt() - 1.0).abs() > 0.1);
}
