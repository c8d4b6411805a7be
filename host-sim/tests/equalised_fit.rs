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
