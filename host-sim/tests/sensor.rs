//! Checks of the sensor chain against closed forms written out here, independently of
//! `host_sim::sensor`: the rigid chain is the pure scale `round(S F / M)`; the accelerometer's
//! step response, overshoot and gain (`|H| = 1 / (2 zeta)` at `f_n`) are those of a
//! second-order low-pass; a beam mode rings at its damped frequency and carries no net impulse;
//! noise RMS and mean match the settings; saturation clips at the ADC range; a seed gives one
//! stream; absent stages cost nothing.

use std::cell::Cell;
use std::f64::consts::PI;

use host_sim::scene::{BeamMode, Resonance, SensorSpec};
use host_sim::sensor::{FnForce, ForcePulse, ForceSignal, ForceTrack, PulseShape, Sensor};

/// A pulse `F_max sin^(3/2)(pi t / t_c)` starting at `start_s`, written out independently.
fn hertz_sine(t_s: f64, start_s: f64, peak_n: f64, tc_s: f64) -> f64 {
    let tau = t_s - start_s;
    if tau <= 0.0 || tau >= tc_s {
        0.0
    } else {
        peak_n * (PI * tau / tc_s).sin().powf(1.5)
    }
}

fn pulse(start_s: f64, peak_n: f64, tc_s: f64) -> ForcePulse {
    ForcePulse {
        start_s,
        duration_s: tc_s,
        scale: 1.0,
        shape: PulseShape::HertzSine {
            peak_force_n: peak_n,
        },
    }
}

/// Unit chain (1 kg, 1 count per m/s^2: counts = newtons), 16 bits, no noise.
fn unit_spec(sample_rate_hz: f64) -> SensorSpec {
    SensorSpec::rigid(sample_rate_hz, 1.0, 1.0, 0.0, 16)
}

/// Amplitude and phase (rad) of the component at `f_hz` of `y` sampled at `fs`, by least
/// squares on `a cos + b sin` over whole periods.
fn fit_sine(y: &[f64], t0_s: f64, fs: f64, f_hz: f64) -> (f64, f64) {
    let (mut cc, mut ss, mut cs, mut yc, mut ys) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for (n, &v) in y.iter().enumerate() {
        let w = 2.0 * PI * f_hz * (t0_s + n as f64 / fs);
        let (s, c) = w.sin_cos();
        cc += c * c;
        ss += s * s;
        cs += c * s;
        yc += v * c;
        ys += v * s;
    }
    let det = cc * ss - cs * cs;
    let a = (yc * ss - ys * cs) / det;
    let b = (ys * cc - yc * cs) / det;
    // y = a cos + b sin = A sin(w t + phi)
    ((a * a + b * b).sqrt(), a.atan2(b))
}

#[test]
fn rigid_chain_is_the_pure_scale() {
    // Paper chain without noise: S / M = 30 / 50 counts per N.
    let spec = SensorSpec::rigid(100_000.0, 50.0, 30.0, 0.0, 16);
    let sensor = Sensor::new(&spec).expect("valid");
    assert!(sensor.is_rigid());
    let pulses = [(1.0e-3, 1673.0, 343e-6), (2.7e-3, 20_000.0, 101e-6)];
    let track = ForceTrack::new(pulses.iter().map(|&(s, f, t)| pulse(s, f, t)).collect());
    let phase = 3.7e-6;
    let got = sensor.sample(&track, 500, phase, 1);
    let mut checked_nonzero = 0;
    for (n, &g) in got.iter().enumerate() {
        let t = phase + n as f64 / 100_000.0;
        let f: f64 = pulses
            .iter()
            .map(|&(s, p, tc)| hertz_sine(t, s, p, tc))
            .sum();
        let want = (f * 30.0 / 50.0).round();
        assert_eq!(g as f64, want, "sample {n}");
        checked_nonzero += usize::from(want != 0.0);
    }
    assert!(checked_nonzero > 40, "{checked_nonzero}");
}

#[test]
fn accelerometer_step_response_and_overshoot() {
    for zeta in [0.05, 0.1, 0.3] {
        let (fs, fn_hz, step) = (1.0e6, 10_000.0, 10_000.0);
        let mut spec = unit_spec(fs);
        spec.accelerometer = Some(Resonance {
            frequency_hz: fn_hz,
            damping_ratio: zeta,
        });
        let sensor = Sensor::new(&spec).expect("valid");
        let force = FnForce(move |t: f64| if t >= 0.0 { step } else { 0.0 });
        let got = sensor.analog_counts(&force, 2_000, 0.0);
        let w = 2.0 * PI * fn_hz;
        let wd = w * (1.0 - zeta * zeta).sqrt();
        let mut worst = 0.0f64;
        for (n, &g) in got.iter().enumerate() {
            let t = n as f64 / fs;
            let y = 1.0
                - (-zeta * w * t).exp()
                    * ((wd * t).cos() + zeta / (1.0 - zeta * zeta).sqrt() * (wd * t).sin());
            worst = worst.max((g - step * y).abs());
        }
        println!(
            "step zeta {zeta}: worst |error| {worst:.2e} counts of {step}, overshoot {:.6} (closed form {:.6})",
            got.iter().cloned().fold(f64::MIN, f64::max) / step - 1.0,
            (-PI * zeta / (1.0 - zeta * zeta).sqrt()).exp()
        );
        // The exact discretisation leaves only rounding.
        assert!(worst < 1e-6 * step, "zeta {zeta}: worst {worst}");
        // Overshoot exp(-pi zeta / sqrt(1 - zeta^2)) at t_p = pi / w_d, from the samples.
        let (n_max, max) = got
            .iter()
            .enumerate()
            .fold((0, f64::MIN), |b, (i, &v)| if v > b.1 { (i, v) } else { b });
        let overshoot = (-PI * zeta / (1.0 - zeta * zeta).sqrt()).exp();
        let t_p = PI / wd;
        assert!(
            (max / step - 1.0 - overshoot).abs() < 1e-3,
            "zeta {zeta}: {max} vs {}",
            1.0 + overshoot
        );
        assert!(
            (n_max as f64 / fs - t_p).abs() <= 0.5 / fs,
            "peak at {n_max}"
        );
        // The digitised output agrees to the rounding.
        let digital = sensor.digitise(&got, 0.0, 1);
        for (d, a) in digital.iter().zip(&got) {
            assert!((*d as f64 - a).abs() <= 0.5);
        }
    }
}

#[test]
fn accelerometer_gain_follows_the_second_order_low_pass() {
    let (fs, fn_hz, zeta, amp) = (200_000.0, 5_000.0, 0.05, 1_000.0);
    let mut spec = unit_spec(fs);
    spec.accelerometer = Some(Resonance {
        frequency_hz: fn_hz,
        damping_ratio: zeta,
    });
    let sensor = Sensor::new(&spec).expect("valid");
    for r in [0.1, 0.5, 1.0, 2.0] {
        let f = r * fn_hz;
        let force = FnForce(move |t: f64| amp * (2.0 * PI * f * t).sin());
        // 40 ms settle (about 63 decay times 1/(zeta w)), then 100 whole periods.
        let settle = (0.04 * fs) as usize;
        let periods = (100.0 * fs / f).round() as usize;
        let got = sensor.analog_counts(&force, settle + periods, 0.0);
        let (a, phi) = fit_sine(&got[settle..], settle as f64 / fs, fs, f);
        let h = 1.0 / ((1.0 - r * r).powi(2) + (2.0 * zeta * r).powi(2)).sqrt();
        let phase = -(2.0 * zeta * r).atan2(1.0 - r * r);
        println!(
            "f/f_n {r}: gain {:.6} (closed form {h:.6}), phase {phi:.6} rad ({phase:.6})",
            a / amp
        );
        assert!(
            (a / amp / h - 1.0).abs() < 1e-4,
            "r {r}: gain {} vs {h}",
            a / amp
        );
        assert!((phi - phase).abs() < 1e-3, "r {r}: phase {phi} vs {phase}");
        if r == 1.0 {
            assert!((a / amp - 1.0 / (2.0 * zeta)).abs() < 1e-3 * 10.0);
        }
    }
}

#[test]
fn beam_mode_rings_at_its_frequency_and_carries_no_impulse() {
    // 1 MS/s: the sampled sums below converge as T^2.5 to the integrals (the pulse starts as
    // t^1.5); at 100 kS/s the sum alone would be off by 0.5 %.
    let (fs, f_mode, zeta, gain) = (1.0e6, 2_000.0, 0.01, 0.5);
    let mut spec = unit_spec(fs);
    spec.beam_modes = vec![BeamMode {
        frequency_hz: f_mode,
        damping_ratio: zeta,
        gain,
    }];
    let sensor = Sensor::new(&spec).expect("valid");
    let (start, peak, tc) = (1.0e-3, 10_000.0, 50e-6);
    let track = ForceTrack::new(vec![pulse(start, peak, tc)]);
    let n = (0.5 * fs) as usize; // 0.5 s: 63 decay times of the mode
    let got = sensor.analog_counts(&track, n, 0.0);
    let rigid: Vec<f64> = (0..n)
        .map(|i| hertz_sine(i as f64 / fs, start, peak, tc))
        .collect();
    // Net impulse: the mode's term integrates to zero; the rigid one to C F_max t_c with
    // C = integral_0^1 sin^(3/2)(pi x) dx = 0.5564179.
    let area_mode: f64 = got.iter().zip(&rigid).map(|(g, r)| g - r).sum::<f64>() / fs;
    let area_rigid: f64 = rigid.iter().sum::<f64>() / fs;
    println!(
        "mode: net impulse / rigid impulse {:.2e}, rigid impulse error {:.2e}",
        area_mode / area_rigid,
        area_rigid / (0.556_417_9 * peak * tc) - 1.0
    );
    assert!((area_rigid / (0.556_417_9 * peak * tc) - 1.0).abs() < 1e-4);
    assert!(
        (area_mode / area_rigid).abs() < 1e-4,
        "{area_mode} / {area_rigid}"
    );
    // During the pulse (period of the mode 10 x the pulse) the peak is about (1 + g) F / M.
    let max = got.iter().cloned().fold(f64::MIN, f64::max);
    assert!(
        (max / (peak * (1.0 + gain)) - 1.0).abs() < 0.05,
        "{max} vs {}",
        peak * (1.0 + gain)
    );
    // After the pulse it rings at f_d = f sqrt(1 - zeta^2): count rising zero crossings
    // over 100 ms, interpolated.
    let from = (2.0e-3 * fs) as usize;
    let to = from + (0.1 * fs) as usize;
    let mut crossings = Vec::new();
    for i in from..to {
        let (a, b) = (got[i], got[i + 1]);
        if a < 0.0 && b >= 0.0 {
            crossings.push((i as f64 + a / (a - b)) / fs);
        }
    }
    let f_measured = (crossings.len() - 1) as f64 / (crossings[crossings.len() - 1] - crossings[0]);
    let f_d = f_mode * (1.0 - zeta * zeta).sqrt();
    assert!(
        (f_measured / f_d - 1.0).abs() < 1e-4,
        "{f_measured} vs {f_d}"
    );
    // And it decays as exp(-zeta w t): the envelope over 10 ms.
    let period = (fs / f_mode) as usize;
    let env = |t0: f64| {
        let i = (t0 * fs) as usize;
        got[i..i + period]
            .iter()
            .fold(0.0f64, |m, v| m.max(v.abs()))
    };
    let decay = env(0.012) / env(0.002);
    let want = (-zeta * 2.0 * PI * f_mode * 0.010).exp();
    assert!((decay / want - 1.0).abs() < 1e-3, "{decay} vs {want}");
}

#[test]
fn quiet_stream_noise_and_offset_match_the_settings() {
    let (sigma, offset, n) = (4.0, 100.3, 200_000usize);
    let mut spec = SensorSpec::rigid(100_000.0, 50.0, 30.0, sigma, 16);
    spec.dc_offset_counts = offset;
    let sensor = Sensor::new(&spec).expect("valid");
    let got = sensor.sample(&ForceTrack::default(), n, 0.0, 42);
    let nf = n as f64;
    let mean = got.iter().map(|&v| v as f64).sum::<f64>() / nf;
    let var = got.iter().map(|&v| (v as f64 - mean).powi(2)).sum::<f64>() / (nf - 1.0);
    // Rounding adds 1/12 count^2 of variance (Sheppard); 5 standard errors.
    let rms_want = (sigma * sigma + 1.0 / 12.0).sqrt();
    println!(
        "quiet: mean {mean:.4} (set {offset}), rms {:.4} (expected {rms_want:.4})",
        var.sqrt()
    );
    assert!(
        (mean - offset).abs() < 5.0 * sigma / nf.sqrt(),
        "mean {mean} vs {offset}"
    );
    assert!(
        (var.sqrt() - rms_want).abs() < 5.0 * rms_want / (2.0 * nf).sqrt(),
        "rms {} vs {rms_want}",
        var.sqrt()
    );
}

#[test]
fn drift_is_a_ramp_in_stream_time() {
    let (drift, fs, n) = (1_000.0, 10_000.0, 10_000usize);
    let mut spec = SensorSpec::rigid(fs, 50.0, 30.0, 2.0, 16);
    spec.dc_drift_counts_per_s = drift;
    let sensor = Sensor::new(&spec).expect("valid");
    let got = sensor.sample(&ForceTrack::default(), n, 0.0, 3);
    // Least-squares slope in counts per s.
    let nf = n as f64;
    let t_mean = (nf - 1.0) / 2.0 / fs;
    let y_mean = got.iter().map(|&v| v as f64).sum::<f64>() / nf;
    let (mut sxy, mut sxx) = (0.0, 0.0);
    for (i, &v) in got.iter().enumerate() {
        let dt = i as f64 / fs - t_mean;
        sxy += dt * (v as f64 - y_mean);
        sxx += dt * dt;
    }
    assert!(
        (sxy / sxx / drift - 1.0).abs() < 0.01,
        "slope {}",
        sxy / sxx
    );
}

#[test]
fn saturation_clips_at_the_adc_range() {
    for bits in [12u8, 16] {
        let mut spec = unit_spec(100_000.0);
        spec.adc_bits = bits;
        let sensor = Sensor::new(&spec).expect("valid");
        let (lo, hi) = sensor.adc_range();
        assert_eq!((lo, hi), (-(1 << (bits - 1)), (1 << (bits - 1)) - 1));
        let amp = 4.0 * hi as f64;
        let force = FnForce(move |t: f64| amp * (2.0 * PI * 1_000.0 * t).sin());
        let analog = sensor.analog_counts(&force, 1_000, 0.0);
        let got = sensor.digitise(&analog, 0.0, 0);
        for (a, &g) in analog.iter().zip(&got) {
            let want = a.round().clamp(lo as f64, hi as f64);
            assert_eq!(g as f64, want);
        }
        assert_eq!(*got.iter().max().expect("samples") as i32, hi);
        assert_eq!(*got.iter().min().expect("samples") as i32, lo);
    }
}

#[test]
fn the_same_seed_gives_the_same_stream() {
    let mut spec = SensorSpec::rigid(100_000.0, 50.0, 30.0, 4.0, 16);
    spec.accelerometer = Some(Resonance {
        frequency_hz: 30_000.0,
        damping_ratio: 0.1,
    });
    let sensor = Sensor::new(&spec).expect("valid");
    let track = ForceTrack::new(vec![pulse(1e-3, 2_000.0, 200e-6)]);
    let a = sensor.sample(&track, 5_000, 2e-6, 7);
    let b = sensor.sample(&track, 5_000, 2e-6, 7);
    let c = sensor.sample(&track, 5_000, 2e-6, 8);
    assert_eq!(a, b);
    assert_ne!(a, c);
}

/// A force that counts how often it is evaluated and says it is zero everywhere.
struct Counting<'a>(&'a Cell<usize>);

impl ForceSignal for Counting<'_> {
    fn force_n(&self, _t_s: f64) -> f64 {
        self.0.set(self.0.get() + 1);
        0.0
    }
    fn is_zero_on(&self, _t0_s: f64, _t1_s: f64) -> bool {
        true
    }
}

#[test]
fn absent_stages_cost_nothing() {
    let calls = Cell::new(0);
    // Rigid: one force evaluation per sample, no fine grid.
    let rigid = Sensor::new(&SensorSpec::rigid(100_000.0, 50.0, 30.0, 0.0, 16)).expect("valid");
    rigid.analog_counts(&Counting(&calls), 1_000, 0.0);
    assert_eq!(calls.get(), 1_000);
    // Linear stages at rest on a quiet stretch: nothing evaluated at all.
    calls.set(0);
    let mut spec = SensorSpec::rigid(100_000.0, 50.0, 30.0, 0.0, 16);
    spec.accelerometer = Some(Resonance {
        frequency_hz: 30_000.0,
        damping_ratio: 0.1,
    });
    let resonant = Sensor::new(&spec).expect("valid");
    let out = resonant.analog_counts(&Counting(&calls), 1_000, 0.0);
    assert_eq!(calls.get(), 0);
    assert!(out.iter().all(|&v| v == 0.0));
}

#[test]
fn invalid_chains_are_refused_by_name() {
    let base = SensorSpec::rigid(100_000.0, 50.0, 30.0, 4.0, 16);
    let cases: Vec<(SensorSpec, &str)> = vec![
        (
            SensorSpec {
                adc_bits: 17,
                ..base.clone()
            },
            "sensor.adc_bits",
        ),
        (
            SensorSpec {
                effective_mass_kg: -1.0,
                ..base.clone()
            },
            "sensor.effective_mass_kg",
        ),
        (
            SensorSpec {
                noise_rms_counts: f64::NAN,
                ..base.clone()
            },
            "sensor.noise_rms_counts",
        ),
        (
            SensorSpec {
                accelerometer: Some(Resonance {
                    frequency_hz: 1e4,
                    damping_ratio: 0.0,
                }),
                ..base.clone()
            },
            "sensor.accelerometer.damping_ratio",
        ),
        (
            SensorSpec {
                oversample: 0,
                ..base.clone()
            },
            "sensor.oversample",
        ),
    ];
    for (spec, field) in cases {
        let e = Sensor::new(&spec).expect_err(field).to_string();
        assert!(e.contains(field), "{e}");
    }
}
