//! The kernel's bound on what a chain known to a tolerance does to a pulse's peak
//! (`coalshock::chain_bias`, a first-order spectral integral) against a second method: a Hertz
//! pulse through host-sim's exact chain with the parameter moved, equalised by the kernel's
//! equaliser designed for the unmoved chain, and its peak compared with the same pulse through
//! the unmoved chain.

mod common;

use coalshock::chain_bias::ChainSpread;
use coalshock::math::Libm;
use coalshock::{ChainBias, ChainTolerance};
use host_sim::convert::sensor_to_kernel;
use host_sim::scene::SensorSpec;

const FS: f64 = 100_000.0;
const PEAK_COUNTS: f64 = 20_000.0;

/// Start of the test pulse (s).
const START_S: f64 = 0.002;

/// The pulse of `duration_s` through the chain `truth`, equalised for the chain `believed`
/// (6 ms of samples), the index of its largest sample and its peak from a parabola through
/// the top three samples.
fn equalised_top(
    truth: &SensorSpec,
    believed: &SensorSpec,
    duration_s: f64,
) -> (Vec<f64>, usize, f64) {
    let n = (0.006 * FS) as usize;
    let (out, _) =
        common::equalised_hertz_pulse(truth, believed, (START_S, duration_s, PEAK_COUNTS), n);
    let out: Vec<f64> = out.iter().map(|&v| v as f64).collect();
    let i = (1..n - 1).fold(1, |b, i| if out[i] > out[b] { i } else { b });
    let (a, b, c) = (out[i - 1], out[i], out[i + 1]);
    let peak = b + 0.125 * (a - c) * (a - c) / (2.0 * b - a - c);
    (out, i, peak)
}

/// Peak and area (counts, counts s) of the pulse of `duration_s` through the chain `truth`,
/// equalised for the chain `believed` ([`equalised_top`]).
fn equalised_peak_and_area(
    truth: &SensorSpec,
    believed: &SensorSpec,
    duration_s: f64,
) -> (f64, f64) {
    let (out, _, peak) = equalised_top(truth, believed, duration_s);
    // The pulse and its accelerometer ring-down, not the slow modes' ringing after it.
    let lo = ((START_S - 2e-4) * FS) as usize;
    let hi = ((START_S + duration_s + 2e-4) * FS) as usize;
    (peak, out[lo..hi].iter().sum::<f64>() / FS)
}

fn spec(modes: &[(f64, f64, f64)], acc: Option<(f64, f64)>) -> SensorSpec {
    common::chain_spec(FS, modes, acc)
}

/// The kernel's bound at one duration for `believed` known to `tolerance`.
fn bound(believed: &SensorSpec, tolerance: ChainTolerance, duration_s: f64) -> f64 {
    let dynamics = sensor_to_kernel(believed)
        .unwrap()
        .dynamics
        .with_tolerance(tolerance)
        .unwrap();
    let t = duration_s as f32;
    chain_spread(&dynamics, t).sigma_ln_force() as f64
}

/// The kernel's spread at one duration, the sum's window as the detector's at `FS`.
fn chain_spread(dynamics: &coalshock::ChainDynamics, t: f32) -> ChainSpread {
    let window = (
        coalshock::pulse_window::PRE_TRIGGER as f32,
        coalshock::pulse_window::hold_samples(2, t, FS as f32) as f32,
    );
    ChainBias::new::<Libm>(dynamics, FS as f32, (t, t), window).spread(t.ln())
}

/// Largest `|d ln F_max|` over the two signs of one relative move, and the largest
/// `|d ln area|` (the area does not move to first order).
fn measured(
    believed: &SensorSpec,
    moved: impl Fn(f64) -> SensorSpec,
    step: f64,
    duration_s: f64,
) -> (f64, f64) {
    let (f0, a0) = equalised_peak_and_area(believed, believed, duration_s);
    let mut worst = (0.0f64, 0.0f64);
    for sign in [1.0, -1.0] {
        let (f, a) = equalised_peak_and_area(&moved(sign * step), believed, duration_s);
        worst = (
            worst.0.max((f / f0).ln().abs()),
            worst.1.max((a / a0).ln().abs()),
        );
    }
    worst
}

#[test]
fn accelerometer_damping_moves_the_peak_as_bounded() {
    // A MEMS accelerometer (6.3 kHz, damping 0.7), its damping known to 30 %.
    let believed = spec(&[], Some((6300.0, 0.7)));
    let tol = ChainTolerance {
        frequency: 0.0,
        damping: 0.3,
        gain: 0.0,
    };
    for duration_s in [1.5e-4, 2.5e-4, 5e-4] {
        let moved = |r: f64| spec(&[], Some((6300.0, 0.7 * (1.0 + r))));
        let (d_force, d_area) = measured(&believed, moved, 0.3, duration_s);
        // One parameter: its move at the tolerance is sqrt(3) standard deviations.
        let b = 3f64.sqrt() * bound(&believed, tol, duration_s);
        println!("t_c {duration_s:.1e}: measured {d_force:.4}, bound {b:.4}, area {d_area:.1e}");
        assert!((d_force / b - 1.0).abs() < 0.25, "{d_force} against {b}");
        assert!(d_area < 0.1 * d_force, "the area moved by {d_area}");
    }
}

#[test]
fn beam_mode_gains_move_the_peak_as_bounded() {
    // Three beam modes whose gains are known to 20 %, each error uniform and independent:
    // the spread is sqrt(sum b_i^2 / 3) of the three modes' moves b_i, each moved alone.
    let modes = [(180.0, 0.02, 0.1), (650.0, 0.01, 0.05), (2100.0, 0.02, 0.1)];
    let believed = spec(&modes, None);
    let tol = ChainTolerance {
        frequency: 0.0,
        damping: 0.0,
        gain: 0.2,
    };
    for duration_s in [1.5e-4, 5e-4] {
        let mut squares = 0.0;
        for i in 0..modes.len() {
            let moved = |r: f64| {
                let mut m = modes.to_vec();
                m[i].2 *= 1.0 + r;
                spec(&m, None)
            };
            squares += measured(&believed, moved, 0.2, duration_s).0.powi(2);
        }
        let d_force = (squares / 3.0).sqrt();
        let b = bound(&believed, tol, duration_s);
        println!("t_c {duration_s:.1e}: measured {d_force:.4}, bound {b:.4}");
        assert!((d_force / b - 1.0).abs() < 0.25, "{d_force} against {b}");
    }
}

/// `(ln F_max, ln t_c)` of the pulse of `duration_s` through `truth`, equalised for
/// `believed`, as the detector reads them: the peak from a parabola through the top three
/// samples, the duration the sum over the detector's window (the contact, the
/// [`coalshock::pulse_window::PRE_TRIGGER`] samples before it and the hold after it, about
/// the largest sample) over `C_AREA F_max`, up to a constant.
fn windowed_ln(truth: &SensorSpec, believed: &SensorSpec, duration_s: f64) -> (f64, f64) {
    let (out, i, peak) = equalised_top(truth, believed, duration_s);
    let half = 0.5 * duration_s * FS;
    let hold = coalshock::pulse_window::hold_samples(2, duration_s as f32, FS as f32) as f64;
    let lo = (i as f64 - half - coalshock::pulse_window::PRE_TRIGGER as f64).round() as usize;
    let hi = (i as f64 + half + hold).round() as usize;
    let area = out[lo..=hi].iter().sum::<f64>();
    (peak.ln(), (area / peak).ln())
}

/// Points of the midpoint rule over a parameter's error in [`measured_moments`].
const ERROR_POINTS: usize = 16;

/// The second moments of `(d ln F_max, d ln t_c)` over one parameter's error: the given
/// (believed) value the truth's times `1 + e`, `e` uniform within `+-tolerance` (the frame of a
/// stated tolerance and of `host-sim evaluate --chain-drawn`), by the midpoint rule over
/// [`ERROR_POINTS`] points; `moved(r)` is the believed chain with the parameter times `1 + r`,
/// here the truth, `r = 1 / (1 + e) - 1`.
fn measured_moments(
    believed: &SensorSpec,
    moved: impl Fn(f64) -> SensorSpec,
    tolerance: f64,
    duration_s: f64,
) -> [f64; 3] {
    let (f0, t0) = windowed_ln(believed, believed, duration_s);
    let mut m = [0.0; 3];
    for i in 0..ERROR_POINTS {
        let e = tolerance * (2.0 * (i as f64 + 0.5) / ERROR_POINTS as f64 - 1.0);
        let (f, t) = windowed_ln(&moved(1.0 / (1.0 + e) - 1.0), believed, duration_s);
        let (df, dt) = (f - f0, t - t0);
        m[0] += df * df / ERROR_POINTS as f64;
        m[1] += dt * dt / ERROR_POINTS as f64;
        m[2] += df * dt / ERROR_POINTS as f64;
    }
    m
}

#[test]
fn beam_mode_gains_move_the_peak_not_the_duration() {
    // A beam mode's error leaves the pulse rescaled inside the detector's window and returns
    // the area it keeps in the mode's slow ringing after it: `ln t_c` moves far less than
    // `ln F_max`, not opposite to it.
    let modes = [(180.0, 0.02, 0.1), (650.0, 0.01, 0.05), (2100.0, 0.02, 0.1)];
    let tol = ChainTolerance {
        frequency: 0.0,
        damping: 0.0,
        gain: 0.2,
    };
    for duration_s in [1.5e-4, 3e-4, 5e-4] {
        let believed = spec(&modes, None);
        let mut m = [0.0; 3];
        for i in 0..modes.len() {
            let moved = |r: f64| {
                let mut ms = modes.to_vec();
                ms[i].2 *= 1.0 + r;
                spec(&ms, None)
            };
            let d = measured_moments(&believed, moved, tol.gain as f64, duration_s);
            (0..3).for_each(|k| m[k] += d[k]);
        }
        let corr = check_spread(&believed, tol, duration_s, m);
        // The area-kept reading (r = -1, sT = sF) is wrong for beam modes.
        assert!(corr > -0.7 && m[1] < 0.64 * m[0], "r {corr}, moments {m:?}");
    }
}

#[test]
fn accelerometer_damping_moves_the_duration_opposite_to_the_peak() {
    // The accelerometer's error answers within the window, which keeps the area.
    let (f, z) = (6300.0, 0.7);
    let tol = ChainTolerance {
        frequency: 0.0,
        damping: 0.3,
        gain: 0.0,
    };
    for duration_s in [1.5e-4, 3e-4, 5e-4] {
        let believed = spec(&[], Some((f, z)));
        let moved = |r: f64| spec(&[], Some((f, z * (1.0 + r))));
        let m = measured_moments(&believed, moved, tol.damping as f64, duration_s);
        let corr = check_spread(&believed, tol, duration_s, m);
        assert!(corr < -0.9, "r {corr}");
    }
}

/// Asserts the kernel's spread for `believed` known to `tolerance` at `duration_s` against
/// the measured moments `m` (`[var F, var T, cov]`): each standard deviation within 25 %
/// (`ln t_c`'s within a tenth of `ln F_max`'s beside), the correlation within 0.15. Returns
/// the measured correlation.
fn check_spread(
    believed: &SensorSpec,
    tolerance: ChainTolerance,
    duration_s: f64,
    m: [f64; 3],
) -> f64 {
    let dynamics = sensor_to_kernel(believed)
        .unwrap()
        .dynamics
        .with_tolerance(tolerance)
        .unwrap();
    let s = chain_spread(&dynamics, duration_s as f32);
    let (sf, st) = (m[0].sqrt(), m[1].sqrt());
    let kf = (s.var_ln_force as f64).sqrt();
    let kt = (s.var_ln_duration as f64).sqrt();
    let (corr, kcorr) = (m[2] / (sf * st), s.cov_ln as f64 / (kf * kt));
    println!(
        "t_c {duration_s:.1e}: measured sF {sf:.4} sT {st:.4} r {corr:+.2}; \
         kernel {kf:.4} {kt:.4} {kcorr:+.2}"
    );
    assert!((kf / sf - 1.0).abs() < 0.25, "sF {kf} against {sf}");
    assert!(
        (kt - st).abs() < 0.25 * st + 0.1 * sf,
        "sT {kt} against {st}"
    );
    assert!((kcorr - corr).abs() < 0.15, "r {kcorr} against {corr}");
    corr
}

#[test]
fn an_exact_or_rigid_chain_has_no_bias() {
    let rigid = spec(&[], None);
    assert_eq!(bound(&rigid, ChainTolerance::IDENTIFIED, 3e-4), 0.0);
    let acc = spec(&[], Some((6300.0, 0.7)));
    assert_eq!(bound(&acc, ChainTolerance::EXACT, 3e-4), 0.0);
}
