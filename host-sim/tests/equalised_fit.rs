//! A calibration pulse through a chain and the kernel's equaliser (`host_sim::equalised_fit`)
//! against a second method: for the kernel's Hertz pulse `cos^(3/2)(pi x)`, the mean over
//! sample phases of the equalised fit over the rigid one is what `coalshock::chain_residual`
//! computes in the frequency domain (Poisson's summation over the chain's response, in f32);
//! here it comes from host-sim's exact chain integrated in time on a fine grid and the
//! kernel's equaliser run sample by sample. And a rigid-enough chain leaves the samples the
//! force's own.

use coalshock::chain_residual::residual;
use coalshock::detector::shape_fit;
use coalshock::math::Libm;
use coalshock::scene::{SAMPLED_FIRST_N, SAMPLED_POINTS, SAMPLED_STEP};
use coalshock::shape_fit::five_about;
use host_sim::calibrate::ContinuousPulse;
use host_sim::convert::dynamics_to_kernel;
use host_sim::equalised_fit::EqualisedChain;
use host_sim::sampled_fit::sample_series;
use host_sim::scene::SensorSpec;

mod common;

/// The kernel's Hertz pulse `cos^(3/2)(pi (t / t_c - 1/2))` on `0 <= t <= t_c`, of unit peak
/// and `t_c` = 1 s, in 4001 points.
fn hertz_series() -> Vec<(f64, f64)> {
    (0..=4000)
        .map(|i| {
            let t = i as f64 / 4000.0;
            (
                t,
                (std::f64::consts::PI * (t - 0.5)).cos().max(0.0).powf(1.5),
            )
        })
        .collect()
}

/// `series` as a pulse of unit peak lasting 1 s.
fn unit_pulse(series: &[(f64, f64)]) -> ContinuousPulse<'_> {
    ContinuousPulse {
        series,
        peak_n: 1.0,
        duration_s: 1.0,
        five: true,
    }
}

/// The chain of `spec` as the kernel equalises it, sampled `phases` times per sample.
fn equalised(spec: &SensorSpec, phases: usize) -> EqualisedChain {
    let dynamics = dynamics_to_kernel(spec).unwrap();
    EqualisedChain::new(spec, &dynamics, phases).expect("not rigid")
}

/// The detector's fit of an undamped Hertz pulse (five samples about the largest and the
/// sum): `[ln F, ln t]`, `t` in samples.
fn hertz_fit(v: &[f64]) -> Option<[f64; 2]> {
    let (i, _) = v.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1))?;
    let v32: Vec<f32> = v.iter().map(|&x| x as f32).collect();
    let (f, t) = shape_fit::<Libm>(five_about(&v32, i), v.iter().sum::<f64>() as f32, true)?;
    Some([f64::from(f).ln(), f64::from(t).ln()])
}

/// `scenes/mems_chain.toml`'s chain: three beam modes and the 6.3 kHz MEMS band at 26.7 kS/s.
fn mems_chain() -> SensorSpec {
    common::chain_spec(
        26_667.0,
        &[(180.0, 0.02, 0.1), (650.0, 0.01, 0.05), (2100.0, 0.02, 0.1)],
        Some((6300.0, 0.7)),
    )
}

/// Behind the MEMS chain, at every point of the sampling correction below 24 samples per
/// pulse (2.5 to 16.4), the mean over 32 phases of `ln(equalised fit / rigid fit)` of the
/// Hertz pulse agrees with `coalshock::chain_residual` within 2 % of its size plus 2e-4 (the
/// kernel's is a trapezoid rule in f32 over 8 phases; they differ by at most 1e-4).
#[test]
fn hertz_pulse_through_the_mems_band_matches_the_kernels_residual() {
    let spec = mems_chain();
    let chain = equalised(&spec, 32);
    let series = hertz_series();
    let pulse = unit_pulse(&series);
    let dynamics = dynamics_to_kernel(&spec).unwrap();
    let residual = residual(&dynamics, chain.design(), spec.sample_rate_hz as f32);
    let mut n = f64::from(SAMPLED_FIRST_N);
    let mut checked = 0;
    for k in 0..SAMPLED_POINTS {
        if n < 24.0 {
            let equalised = chain.samples(&pulse, n, 0.5);
            let mut sum = [0.0; 2];
            for (j, v) in equalised.iter().enumerate() {
                let phase = (j as f64 + 0.5) / 32.0;
                let rigid = sample_series(&series, 1.0 / n, phase).unwrap();
                let (e, r) = (hertz_fit(v).unwrap(), hertz_fit(&rigid).unwrap());
                sum[0] += e[0] - r[0];
                sum[1] += e[1] - r[1];
            }
            let ours = sum.map(|s| s / 32.0);
            let kernel = [residual.ln_force[k], residual.ln_duration[k]].map(f64::from);
            println!(
                "n {n:5.2}: ln F {:+.4} (kernel {:+.4}), ln t {:+.4} (kernel {:+.4})",
                ours[0], kernel[0], ours[1], kernel[1]
            );
            for m in 0..2 {
                let bound = 0.02 * kernel[m].abs() + 2e-4;
                assert!((ours[m] - kernel[m]).abs() <= bound, "n {n}, {m}");
            }
            checked += 1;
        }
        n *= f64::from(SAMPLED_STEP);
    }
    assert_eq!(checked, 5);
}

/// Beam modes alone (the tail beam's three) at 100 kS/s: the equaliser inverts them to 1e-3
/// of the peak (`tests/equaliser.rs`), so at 8 samples per pulse every phase's equalised
/// samples are the force's own sampled at that phase, one sample after the start, within 5e-4
/// of the peak: the stretch and the phases are the rigid fit's.
#[test]
fn beam_modes_alone_give_back_the_force_at_every_phase() {
    let spec = common::chain_spec(
        100_000.0,
        &[(180.0, 0.02, 0.1), (650.0, 0.01, 0.05), (2100.0, 0.02, 0.1)],
        None,
    );
    let chain = equalised(&spec, 8);
    let series = hertz_series();
    let pulse = unit_pulse(&series);
    let mut worst = 0.0f64;
    for (j, v) in chain.samples(&pulse, 8.0, 0.25).iter().enumerate() {
        let rigid = sample_series(&series, 1.0 / 8.0, (j as f64 + 0.25) / 8.0).unwrap();
        assert_eq!(rigid.len(), 8);
        for (i, r) in rigid.iter().enumerate() {
            worst = worst.max((v[i + 1] - r).abs());
        }
        assert!(v[0].abs() < 1e-6, "before the pulse: {}", v[0]);
    }
    println!("largest |equalised - force| over the peak: {worst:.2e}");
    assert!(worst < 5e-4, "{worst}");
}

/// The largest error the equaliser leaves in one sample (`coalshock::chain_residual::
/// sample_error`, a frequency-domain integral in f32), which a clipped pulse's flank fit
/// counts behind an accelerometer, against host-sim's exact chain integrated in time: behind
/// three accelerometers, at 4 to 45 samples per pulse, the largest `|equalised - force|` over
/// 32 phases and every sample from a quarter of the pulse before it to a quarter after, within
/// three samples of an end of the pulse and farther, is at most 8 % above the kernel's (plus
/// 1e-5 of the peak: rounding), and the kernel's at most 1.5 times it (plus 1e-4: its
/// bound of the integral's tail, 7e-5).
#[test]
fn the_kernels_sample_error_matches_the_exact_chain() {
    use coalshock::chain_residual::{KINK_SAMPLES, sample_error};
    let series = hertz_series();
    let pulse = unit_pulse(&series);
    for (fs, acc) in [
        (100_000.0, (40_000.0, 0.05)),
        (200_000.0, (58_600.0, 0.52)),
        (50_000.0, (6_300.0, 0.7)),
    ] {
        let spec = common::chain_spec(fs, &[], Some(acc));
        let chain = equalised(&spec, 32);
        let dynamics = dynamics_to_kernel(&spec).unwrap();
        let delay = f64::from(chain.design().delay_samples());
        for n in [4.0, 8.0, 16.0, 45.0] {
            let (mut worst, mut points) = ([0.0f64; 2], [0usize; 2]);
            for (j, v) in chain.samples(&pulse, n, 0.5).iter().enumerate() {
                for (m, &y) in v.iter().enumerate() {
                    // The pulse starts one sample in; the equaliser lags by its delay.
                    let x = (m as f64 - delay - 1.0 + (j as f64 + 0.5) / 32.0) / n - 0.5;
                    let force = (std::f64::consts::PI * x).cos().max(0.0).powf(1.5);
                    let force = if x.abs() < 0.5 { force } else { 0.0 };
                    if x.abs() <= 0.75 {
                        let end = usize::from((x.abs() - 0.5).abs() * n <= f64::from(KINK_SAMPLES));
                        worst[end] = worst[end].max((y - force).abs());
                        points[end] += 1;
                    }
                }
            }
            let kernel =
                sample_error(&dynamics, chain.design(), fs as f32, n as f32).map(f64::from);
            println!(
                "{fs} {acc:?} n {n}: body {:.3e} (kernel {:.3e}), ends {:.3e} (kernel {:.3e})",
                worst[0], kernel[0], worst[1], kernel[1]
            );
            // At 4 samples per pulse every point lies within three samples of an end.
            for i in (0..2).filter(|&i| points[i] > 0) {
                let (w, k) = (worst[i], kernel[i]);
                assert!(
                    w <= 1.08 * k + 1e-5 && k <= 1.5 * w + 1e-4,
                    "{fs} {acc:?} n {n} {i}"
                );
            }
        }
    }
}

/// The raw samples' error against the force `lag` samples before them
/// (`coalshock::chain_residual::raw_error`, a frequency-domain integral in f32), which a
/// clipped pulse's flank fit allows at a clipped sample, against host-sim's exact chain: the
/// Hertz pulse through three accelerometers (among them a 7.5 kHz MEMS band of zeta 0.43,
/// whose top overshoots a short pulse's) at 4-45 samples per pulse, output 64 times per
/// sample; over the pulse's middle half the largest `|y(t + lag) - F(t)|` over the peak is
/// at most 8 % above the kernel's (plus 1e-5) and the kernel's at most 1.5 times it plus 1e-4.
#[test]
fn the_kernels_raw_error_matches_the_exact_chain() {
    use coalshock::chain_residual::raw_error;
    use host_sim::scene::SensorSpec;
    use host_sim::sensor::{FnForce, Sensor};
    for (fs, (f_a, zeta)) in [
        (100_000.0, (40_000.0, 0.05)),
        (26_667.0, (7_500.0, 0.43)),
        (50_000.0, (6_300.0, 0.7)),
    ] {
        let spec = common::chain_spec(fs, &[], Some((f_a, zeta)));
        let dynamics = dynamics_to_kernel(&spec).unwrap();
        let lag = zeta * fs / (std::f64::consts::PI * f_a);
        let fine = Sensor::new(&SensorSpec {
            sample_rate_hz: fs * 64.0,
            noise_rms_counts: 0.0,
            ..spec.clone()
        })
        .unwrap();
        for n in [4.0, 8.0, 16.0, 45.0] {
            let t_c = n / fs;
            let shape = |t: f64| {
                let x = t / t_c - 0.5;
                if x.abs() < 0.5 {
                    (std::f64::consts::PI * x).cos().powf(1.5)
                } else {
                    0.0
                }
            };
            let k = fine.counts_per_newton();
            let force = FnForce(|t: f64| shape(t) / k);
            let samples = (2.0 * n * 64.0) as usize;
            let y = fine.analog_counts(&force, samples, 0.0);
            let mut worst = 0.0f64;
            for (i, &v) in y.iter().enumerate() {
                let t = i as f64 / (fs * 64.0) - lag / fs;
                if (t / t_c - 0.5).abs() <= 0.25 {
                    worst = worst.max((v - shape(t)).abs());
                }
            }
            let kernel = f64::from(raw_error(&dynamics, fs as f32, n as f32, lag as f32));
            println!("{fs} ({f_a}, {zeta}) n {n}: exact chain {worst:.3e}, kernel {kernel:.3e}");
            assert!(
                worst <= 1.08 * kernel + 1e-5 && kernel <= 1.5 * worst + 1e-4,
                "n {n}"
            );
        }
    }
}
