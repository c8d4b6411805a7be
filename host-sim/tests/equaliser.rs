//! The kernel's equaliser on host-sim's exact chain: a Hertz pulse through beam modes and an
//! accelerometer (first-order-hold integration on a fine grid), sampled, then equalised by
//! the kernel, must give back the force samples; and the ringing after it must vanish.

mod common;

use coalshock::{Equaliser, EqualiserDesign};
use host_sim::convert::sensor_to_kernel;
use host_sim::scene::SensorSpec;
use host_sim::sensor::{ForcePulse, ForceTrack, PulseShape, Sensor};

/// Peak force of the test pulse in counts of the rigid plate (large, so that rounding to
/// integer samples costs 2.5e-5 of it).
const PEAK_COUNTS: f64 = 20_000.0;

struct Outcome {
    /// Largest `|equalised - force|` during the pulse, over the peak.
    pulse_error: f64,
    /// RMS of the equalised signal from 0.5 ms after the pulse on (about 20 ms), over the peak.
    ringing: f64,
    /// RMS of the raw ringing over the same stretch, over the peak.
    raw_ringing: f64,
}

fn run(spec: &SensorSpec, duration_s: f64, phase: f64) -> Outcome {
    let sensor = Sensor::new(spec).unwrap();
    let fs = spec.sample_rate_hz;
    let start_s = 0.002 + phase / fs;
    let peak_n = PEAK_COUNTS / sensor.counts_per_newton();
    let pulse = ForcePulse {
        start_s,
        duration_s,
        scale: 1.0,
        shape: PulseShape::HertzSine {
            peak_force_n: peak_n,
        },
    };
    let force = |t: f64| pulse.force_at(t - start_s) * sensor.counts_per_newton();
    let track = ForceTrack::new(vec![pulse.clone()]);
    let n = (0.025 * fs) as usize;
    let analog = sensor.analog_counts(&track, n, 0.0);
    let raw: Vec<i32> = analog.iter().map(|v| v.round() as i32).collect();
    let chain = sensor_to_kernel(spec).unwrap();
    let design = EqualiserDesign::new::<coalshock::math::Libm>(&chain.dynamics, fs as f32).unwrap();
    let mut eq = Equaliser::new(&design);
    let mut out = vec![0.0f32; n];
    eq.process(&raw, &mut out);
    let delay = design.delay_samples() as usize;
    let end = ((start_s + duration_s) * fs).ceil() as usize + 1;
    let mut pulse_error = 0.0f64;
    for i in 0..end {
        let e = (out[i + delay] as f64 - force(i as f64 / fs)).abs();
        pulse_error = pulse_error.max(e / PEAK_COUNTS);
    }
    // From 0.5 ms after the pulse: the accelerometer's own ringing (80 us) is over.
    let tail = end + (5e-4 * fs) as usize..n - delay;
    let rms = |v: &mut dyn Iterator<Item = f64>| {
        let (s, c) = v.fold((0.0, 0usize), |(s, c), x| (s + x * x, c + 1));
        (s / c as f64).sqrt() / PEAK_COUNTS
    };
    Outcome {
        pulse_error,
        ringing: rms(&mut out[tail.start + delay..].iter().map(|&v| v as f64)),
        raw_ringing: rms(&mut raw[tail.clone()].iter().map(|&v| v as f64)),
    }
}

fn spec(fs: f64, modes: &[(f64, f64, f64)], acc: Option<(f64, f64)>) -> SensorSpec {
    common::chain_spec(fs, modes, acc)
}

/// A tail beam of three modes (100 Hz - 5 kHz band) at 100 kS/s and at 26.7 kS/s, pulses of
/// 4 to 40 samples: the force comes back within 2e-3 of its peak and the ringing left is at
/// least 100 times smaller than the raw ringing.
#[test]
fn beam_modes_give_back_the_force_and_kill_the_ringing() {
    let beam = [(180.0, 0.02, 0.1), (650.0, 0.01, 0.05), (2100.0, 0.02, 0.1)];
    for &fs in &[100_000.0, 26_667.0] {
        for &tc in &[150e-6, 400e-6] {
            for &phase in &[0.0, 0.37, 0.81] {
                let o = run(&spec(fs, &beam, None), tc, phase);
                println!(
                    "fs {fs} t_c {tc}: pulse error {:.2e}, ringing {:.2e} (raw {:.2e})",
                    o.pulse_error, o.ringing, o.raw_ringing
                );
                assert!(o.pulse_error < 2e-3, "{}", o.pulse_error);
                assert!(o.ringing * 100.0 < o.raw_ringing, "{}", o.ringing);
            }
        }
    }
}

/// A piezo accelerometer (40 kHz, zeta 0.05) behind two modes at 100 kS/s: the pulse's error
/// stays within the central differences' `(w T)^2 / 12` of the correction (about 1.5e-2 of
/// the peak at 15 samples per pulse, 3.5e-3 at 40).
#[test]
fn accelerometer_and_modes_give_back_the_force() {
    let beam = [(180.0, 0.02, 0.1), (2100.0, 0.02, 0.1)];
    for &(tc, bound) in &[(150e-6, 1.5e-2), (400e-6, 3.5e-3)] {
        let o = run(&spec(100_000.0, &beam, Some((40_000.0, 0.05))), tc, 0.3);
        println!(
            "t_c {tc}: pulse error {:.2e}, ringing {:.2e} (raw {:.2e})",
            o.pulse_error, o.ringing, o.raw_ringing
        );
        assert!(o.pulse_error < bound, "{}", o.pulse_error);
        assert!(o.ringing * 100.0 < o.raw_ringing, "{}", o.ringing);
    }
}
