//! The bias the kernel's equaliser leaves in a short pulse (`coalshock::chain_residual`, a
//! spectral integral and Poisson's sum) against a second method: Hertz pulses sampled through
//! host-sim's exact chain (its state-space integration), equalised by the kernel's equaliser,
//! and fitted by the kernel's fit, against the same pulses on a rigid chain, at 16 sample
//! phases; and the spread over those phases of the equalised pulse's own fit, which the
//! kernel states as the correction's spread.

mod common;

use coalshock::EqualiserDesign;
use coalshock::chain_residual::{SMOOTH_FROM_SAMPLES, residual};
use coalshock::detector::shape_fit;
use coalshock::math::Libm;
use coalshock::scene::{SAMPLED_FIRST_N, SAMPLED_POINTS, SAMPLED_STEP};
use coalshock::shape_fit::five_about;
use host_sim::bridge::sampled_fit::mean_and_sigma;
use host_sim::convert::sensor_to_kernel;
use host_sim::scene::SensorSpec;

const PEAK_COUNTS: f64 = 1.0e6;
const PHASES: usize = 16;

/// The kernel's fit `(ln F, ln t)` of one pulse of `n` samples through `chain` (equalised by
/// the kernel), its start `phase` of a sample after a sample instant.
fn fitted(chain: &SensorSpec, n: f64, phase: f64) -> (f64, f64) {
    let fs = chain.sample_rate_hz;
    let duration_s = n / fs;
    let start_s = (64.0 + phase) / fs;
    let len = 64 + n.ceil() as usize + 64;
    let (out, design) =
        common::equalised_hertz_pulse(chain, chain, (start_s, duration_s, PEAK_COUNTS), len);
    // The equaliser's output lags by its delay: the pulse's samples are those after it.
    let delay = design.delay_samples() as usize;
    let pulse = &out[64 + delay - 2..64 + delay + n.ceil() as usize + 3];
    let (i, _) = pulse
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(b.1))
        .unwrap();
    let sum: f32 = pulse.iter().sum();
    let (f, t) = shape_fit::<Libm>(five_about(pulse, i), sum, true).unwrap();
    ((f as f64).ln(), (t as f64).ln())
}

/// Over phases: the mean of the chain's fit over the rigid one's, `(d ln F, d ln t)`, and the
/// spread of the chain's fit itself, `(sigma ln F, sigma ln t)`.
fn measured(chain: &SensorSpec, n: f64) -> ((f64, f64), (f64, f64)) {
    let rigid = common::chain_spec(chain.sample_rate_hz, &[], None);
    let (mut df, mut dt) = (0.0, 0.0);
    let (mut own_f, mut own_t) = (Vec::new(), Vec::new());
    for p in 0..PHASES {
        let phase = (p as f64 + 0.5) / PHASES as f64;
        let (cf, ct) = fitted(chain, n, phase);
        let (rf, rt) = fitted(&rigid, n, phase);
        df += cf - rf;
        dt += ct - rt;
        own_f.push(cf);
        own_t.push(ct);
    }
    (
        (df / PHASES as f64, dt / PHASES as f64),
        (mean_and_sigma(&own_f).1, mean_and_sigma(&own_t).1),
    )
}

/// Every point below the smoothed-top threshold: the bias within `rel` of the measured one
/// plus `abs`, and the spread within a fifth of the measured one plus `abs` (the kernel takes
/// 8 phases, this 16); the points above it 0.
fn check(chain: &SensorSpec, rel: f64, abs: f64) {
    let fs = chain.sample_rate_hz;
    let k = sensor_to_kernel(chain).unwrap();
    let design = EqualiserDesign::new::<Libm>(&k.dynamics, fs as f32).unwrap();
    let table = residual(&k.dynamics, &design, fs as f32);
    let mut n = SAMPLED_FIRST_N as f64;
    for i in 0..SAMPLED_POINTS {
        let (lf, lt) = (table.ln_force[i] as f64, table.ln_duration[i] as f64);
        let (sf, st) = (
            table.sigma_ln_force[i] as f64,
            table.sigma_ln_duration[i] as f64,
        );
        if n < SMOOTH_FROM_SAMPLES as f64 {
            let ((mf, mt), (msf, mst)) = measured(chain, n);
            println!(
                "n {n:5.2}: ln F {lf:+.4} (measured {mf:+.4}), ln t {lt:+.4} (measured {mt:+.4}); \
                 spread ln F {sf:.4} ({msf:.4}), ln t {st:.4} ({mst:.4})"
            );
            assert!(
                (lf - mf).abs() <= rel * mf.abs() + abs,
                "n {n}: ln F {lf} vs {mf}"
            );
            assert!(
                (lt - mt).abs() <= rel * mt.abs() + abs,
                "n {n}: ln t {lt} vs {mt}"
            );
            assert!(
                (sf - msf).abs() <= 0.2 * msf + abs,
                "n {n}: sigma ln F {sf} vs {msf}"
            );
            assert!(
                (st - mst).abs() <= 0.2 * mst + abs,
                "n {n}: sigma ln t {st} vs {mst}"
            );
        } else {
            assert_eq!((lf, lt), (0.0, 0.0));
        }
        n *= SAMPLED_STEP as f64;
    }
}

/// A MEMS part at 26.7 kS/s (maximally flat band at 6.3 kHz) under three beam modes: the
/// chain of `scenes/mems_chain.toml`.
#[test]
fn mems_band_and_modes() {
    let chain = common::chain_spec(
        26_667.0,
        &[(180.0, 0.02, 0.1), (650.0, 0.01, 0.05), (2100.0, 0.02, 0.1)],
        Some((6300.0, 0.7)),
    );
    check(&chain, 0.02, 3e-4);
}

/// A lightly damped piezo resonance at 35 kHz sampled at 100 kS/s, no modes.
#[test]
fn piezo_resonance() {
    let chain = common::chain_spec(100_000.0, &[], Some((35_000.0, 0.05)));
    check(&chain, 0.02, 3e-4);
}

/// A rigid chain has no residual at all.
#[test]
fn rigid_has_none() {
    let chain = common::chain_spec(26_667.0, &[], None);
    let k = sensor_to_kernel(&chain).unwrap();
    let design = EqualiserDesign::new::<Libm>(&k.dynamics, 26_667.0).unwrap();
    assert_eq!(
        residual(&k.dynamics, &design, 26_667.0),
        coalshock::SampledCalibration::NONE
    );
}
