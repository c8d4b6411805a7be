//! The equaliser's state re-estimation (`coalshock::settle`) against a chain written out
//! here: after samples that are not the chain's output (a clipped top), the beam's free
//! ring-down `sum_j A_j e^(-zeta_j w_j t) cos(w_dj t + phi_j)` (its poles from the modes'
//! frequency and damping, independent of the kernel's discretisation) must come out of the
//! equaliser as the baseline and its noise; and a window with a pulse in it is not believed.
#![cfg(feature = "settle")]

mod common;

use coalshock::equaliser::{BeamMode, ChainDynamics, Equaliser, EqualiserDesign};
use coalshock::math::Libm;
use coalshock::settle::{Settler, WARM_UP, WINDOW_S};

const FS: f32 = 100_000.0;
const BASELINE: f64 = 120.0;
const NOISE_RMS: f64 = 4.0;
/// The tail beam of `scenes/tail_beam.toml`: frequency (Hz), damping ratio, gain.
const MODES: [(f64, f64, f64); 3] = [(180.0, 0.02, 0.1), (650.0, 0.01, 0.05), (2100.0, 0.02, 0.1)];

fn design() -> EqualiserDesign {
    let mut d = ChainDynamics::RIGID;
    for &(f, z, g) in &MODES {
        d = d
            .with_mode(BeamMode {
                frequency_hz: f as f32,
                damping_ratio: z as f32,
                gain: g as f32,
            })
            .unwrap();
    }
    EqualiserDesign::new::<Libm>(&d, FS).unwrap()
}

/// The beam ringing freely from `t = 0` with 2000, 1500 and 800 counts in its modes, plus the
/// baseline, noise and (when given) a `sin^(3/2)` pulse of `pulse.1` counts over 20 samples
/// from sample `pulse.0`; rounded to counts.
fn ring_down(n: usize, seed: u64, pulse: Option<(usize, f64)>) -> Vec<i32> {
    let mut rng = common::Rng::new(seed);
    let amps = [2000.0, 1500.0, 800.0];
    let phases = [0.3, 1.9, -0.7];
    (0..n)
        .map(|i| {
            let t = i as f64 / FS as f64;
            let mut v = BASELINE + NOISE_RMS * rng.normal();
            for ((&(f, z, _), a), p) in MODES.iter().zip(amps).zip(phases) {
                let w = core::f64::consts::TAU * f;
                let wd = w * (1.0 - z * z).sqrt();
                v += a * (-z * w * t).exp() * (wd * t + p).cos();
            }
            if let Some((at, peak)) = pulse {
                if i > at && i < at + 20 {
                    let s = (core::f64::consts::PI * (i - at) as f64 / 20.0).sin();
                    v += peak * s * s.sqrt();
                }
            }
            v.round() as i32
        })
        .collect()
}

/// An equaliser that ran on quiet samples, then on ten samples at full scale (not the chain's
/// output): its sections are off the chain's state.
fn knocked_off(design: &EqualiserDesign) -> Equaliser {
    let mut eq = Equaliser::new(design);
    let mut rng = common::Rng::new(3);
    for _ in 0..2000 {
        eq.step((BASELINE + NOISE_RMS * rng.normal()).round() as i32);
    }
    for _ in 0..10 {
        eq.step(i16::MAX as i32);
    }
    eq
}

/// An observer armed by an event, its first window open on the baseline.
fn window_open() -> Settler {
    let mut settler = Settler::new(FS);
    settler.arm();
    settler.start(BASELINE as f32);
    settler
}

/// RMS of the equalised samples about the baseline.
fn rms_about_baseline(eq: &mut Equaliser, raw: &[i32]) -> f64 {
    let s: f64 = raw
        .iter()
        .map(|&x| {
            let d = eq.step(x) as f64 - BASELINE;
            d * d
        })
        .sum();
    (s / raw.len() as f64).sqrt()
}

#[test]
fn a_knocked_off_equaliser_is_set_back_on_the_chain() {
    let design = design();
    let noise = (NOISE_RMS as f32) * design.noise_gain();
    let raw = ring_down(4000, 5, None);
    // Without re-estimation: the error rings on at the sections' poles.
    let mut plain = knocked_off(&design);
    let before = rms_about_baseline(&mut plain, &raw[400..]);
    // With it: one window from the first sample on, then the same stretch.
    let mut eq = knocked_off(&design);
    let mut settler = window_open();
    let mut it = raw.iter().copied();
    let taken = settler.run(&mut eq, noise, (i16::MIN as i32, i16::MAX as i32), &mut it);
    assert!(
        taken.quiet_ms.is_some(),
        "the window is believed: {taken:?}"
    );
    let window = WARM_UP as u32 + (WINDOW_S * FS).round() as u32;
    assert_eq!(taken.samples, window, "the warm-up and one window");
    let mut rest = eq;
    for &x in &raw[taken.samples as usize..400] {
        rest.step(x);
    }
    let after = rms_about_baseline(&mut rest, &raw[400..]);
    println!(
        "equalised RMS about the baseline, 4-40 ms after: {before:.1} counts knocked off, \
         {after:.2} re-estimated (noise {noise:.2}); window residual {:.2}",
        taken.quiet_ms.unwrap().sqrt()
    );
    assert!(
        before > 300.0 * noise as f64,
        "the test's error is large: {before}"
    );
    // Within 2 noise sigmas: what the window could not tell apart in 1 ms (the slowest
    // section turns by a fifth of a period) rings on at a few counts.
    assert!(after < 2.0 * noise as f64, "{after} against noise {noise}");
}

#[test]
fn a_window_with_a_pulse_in_it_is_not_believed() {
    let design = design();
    let noise = (NOISE_RMS as f32) * design.noise_gain();
    let raw = ring_down(4000, 9, Some((50, 3000.0)));
    let mut eq = knocked_off(&design);
    let untouched = eq;
    let mut settler = window_open();
    let mut it = raw.iter().copied();
    let taken = settler.run(&mut eq, noise, (i16::MIN as i32, i16::MAX as i32), &mut it);
    assert_eq!(taken.quiet_ms, None, "a pulse in the window: discarded");
    // The sections ran on the window's samples and were not corrected.
    let mut same = untouched;
    for &x in &raw[..taken.samples as usize] {
        same.step(x);
    }
    assert_eq!(eq, same);
    assert!(settler.is_armed(), "another window may follow");
}

#[test]
fn a_sample_at_full_scale_ends_the_window_untaken() {
    let design = design();
    let mut eq = knocked_off(&design);
    let mut settler = window_open();
    let mut raw = ring_down(50, 1, None);
    raw[30] = i16::MAX as i32;
    let mut it = raw.iter().copied();
    let taken = settler.run(&mut eq, 4.0, (i16::MIN as i32, i16::MAX as i32), &mut it);
    assert_eq!(taken.samples, 30);
    assert_eq!(taken.quiet_ms, None);
    assert!(settler.is_armed() && !settler.in_window());
}

/// Windows are bounded: after three discarded ones the observer gives up.
#[test]
fn at_most_three_windows_per_event() {
    let design = design();
    let mut eq = knocked_off(&design);
    let mut settler = Settler::new(FS);
    settler.arm();
    // Pulses every 60 samples: every window holds one.
    let raw: Vec<i32> = (0..2000)
        .map(|i| if i % 60 < 20 { 3000 } else { BASELINE as i32 })
        .collect();
    let mut rest = &raw[..];
    let mut windows = 0;
    while settler.is_armed() {
        settler.start(BASELINE as f32);
        if !settler.in_window() {
            break;
        }
        windows += 1;
        let mut it = rest.iter().copied();
        let taken = settler.run(&mut eq, 4.0, (i16::MIN as i32, i16::MAX as i32), &mut it);
        assert_eq!(taken.quiet_ms, None);
        rest = &rest[taken.samples as usize..];
    }
    assert_eq!(windows, 3);
    assert!(!settler.is_armed() && !settler.in_window());
}
