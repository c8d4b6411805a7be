//! `identify` on host-sim's own streams (4 counts RMS noise, integrated Hertz pulses): a tail
//! beam with three modes, alone at 100 kS/s and under an accelerometer resonance at 40 kHz
//! (paper scene), and the shipped MEMS chain at 26.7 kS/s (`scenes/mems_chain.toml`: pulses of
//! 3-12 samples, a 2.1 kHz mode of 13 samples a period, a 6.3 kHz zeta 0.7 band) and the
//! shipped piezo chain at 100 kS/s (a 35 kHz, zeta 0.02 resonance that rings into the free
//! windows). Asserted:
//! frequency within 1 %, damping within 20 %, gain within 10 % of the spec; the resonance's
//! frequency within 1 % and damping within 20 %, or, for the MEMS band, that it is reported as
//! not identified from its ring, and found within 0.6 % from the pulses' Hertz shape
//! (`--hertz-pulses`); and on every stream, that the `chain_tolerance` and
//! `accelerometer_tolerance` identify prints bound each of those errors. The measured errors
//! are printed (`cargo test -p host-sim --test identify -- --nocapture`).

mod common;

use host_sim::generate::generate;
use host_sim::identify::{IdentifyOptions, identify};
use host_sim::law_spec::LawSpec;
use host_sim::scene::{BeamMode, Resonance, SceneFile, load};
use host_sim::stream::StreamOptions;

fn tail_beam() -> Vec<BeamMode> {
    [
        (180.0, 0.02, 0.1),
        (650.0, 0.01, 0.05),
        (2100.0, 0.02, 0.03),
    ]
    .into_iter()
    .map(|(frequency_hz, damping_ratio, gain)| BeamMode {
        frequency_hz,
        damping_ratio,
        gain,
    })
    .collect()
}

/// Identifies a stream of `scene` and checks every mode (and the resonance if present).
fn check(scene: &SceneFile, impacts: usize, seed: u64, modes: Option<usize>) {
    check_resonance(scene, impacts, seed, modes, true);
}

/// As `check`; `resonance_seen`: whether the accelerometer's resonance (if any) must be
/// identified (else it must be reported as not identified, with the kernel's default damping
/// tolerance, 0.3). Every error must also be within the tolerance printed in the table.
fn check_resonance(
    scene: &SceneFile,
    impacts: usize,
    seed: u64,
    modes: Option<usize>,
    resonance_seen: bool,
) {
    let stream = generate(scene, impacts, seed, &StreamOptions::default()).expect("stream");
    let spec = &scene.sensor;
    let opts = IdentifyOptions {
        sample_rate_hz: spec.sample_rate_hz,
        modes,
        accelerometer: spec.accelerometer.is_some(),
        pulse_law: None,
        noise_rms_counts: None,
    };
    let id = identify(&stream.samples, &opts).expect("identified");
    println!("{}", id.to_toml());
    assert!(id.to_toml().contains("chain_tolerance = { frequency = "));
    let [tf, tz, tg] = id.chain_tolerance();
    let band = id.accelerometer_tolerance();
    assert_eq!(band.is_some(), spec.accelerometer.is_some());
    assert!(
        (id.noise_rms_counts / spec.noise_rms_counts - 1.0).abs() < 0.1,
        "noise {} counts",
        id.noise_rms_counts
    );
    assert_eq!(id.modes.len(), spec.beam_modes.len(), "{id:?}");
    println!("mode      | frequency | damping  | gain");
    for (m, t) in id.modes.iter().zip(&spec.beam_modes) {
        let ef = m.frequency_hz.value / t.frequency_hz - 1.0;
        let ez = m.damping_ratio.value / t.damping_ratio - 1.0;
        let eg = m.gain.value / t.gain - 1.0;
        println!(
            "{:7} Hz | {:+.4} % | {:+.3} % | {:+.3} %",
            t.frequency_hz,
            100.0 * ef,
            100.0 * ez,
            100.0 * eg
        );
        assert!(ef.abs() < 0.01, "frequency of {t:?}: {m:?}");
        assert!(ez.abs() < 0.2, "damping of {t:?}: {m:?}");
        assert!(eg.abs() < 0.1, "gain of {t:?}: {m:?}");
        assert!(
            ef.abs() <= tf && ez.abs() <= tz && eg.abs() <= tg,
            "tolerance {tf} / {tz} / {tg}: {t:?}: {m:?}"
        );
    }
    if !resonance_seen {
        assert!(id.accelerometer.is_none(), "{:?}", id.accelerometer);
        assert!(id.to_toml().contains("accelerometer: not identified"));
        if let Some([_, az]) = band {
            assert!(az >= 0.3, "damping tolerance {az} of an unidentified band");
        }
        return;
    }
    match (&spec.accelerometer, &id.accelerometer) {
        (None, None) => {}
        (Some(t), Some(a)) => {
            let ef = a.frequency_hz.value / t.frequency_hz - 1.0;
            let ez = a.damping_ratio.value / t.damping_ratio - 1.0;
            println!(
                "accel {} Hz | {:+.4} % | {:+.3} % | ({} rings)",
                t.frequency_hz,
                100.0 * ef,
                100.0 * ez,
                a.pulses
            );
            assert!(ef.abs() < 0.01, "accelerometer frequency: {a:?}");
            assert!(ez.abs() < 0.2, "accelerometer damping: {a:?}");
            let [af, az] = band.expect("asked for");
            assert!(
                ef.abs() <= af && ez.abs() <= az,
                "tolerance {af} / {az}: {t:?}: {a:?}"
            );
        }
        (t, a) => panic!("accelerometer: spec {t:?}, identified {a:?}"),
    }
}

#[test]
fn tail_beam_modes_at_the_paper_scene_noise() {
    let mut scene = SceneFile::paper();
    scene.sensor.beam_modes = tail_beam();
    check(&scene, 60, 11, None);
}

/// The tail beam given `--modes 3`, two streams (seeds 12, 13).
#[test]
fn tail_beam_modes_given_their_number() {
    let mut scene = SceneFile::paper();
    scene.sensor.beam_modes = tail_beam();
    for seed in [12, 13] {
        check(&scene, 60, seed, Some(3));
    }
}

#[test]
fn modes_and_a_40_khz_accelerometer() {
    let mut scene = SceneFile::paper();
    scene.sensor.beam_modes = tail_beam();
    scene.sensor.accelerometer = Some(Resonance {
        frequency_hz: 40_000.0,
        damping_ratio: 0.05,
    });
    check(&scene, 60, 13, None);
}

/// The shipped MEMS chain at 26.7 kS/s and its noise, five streams of 60 impacts. Its 6.3 kHz,
/// zeta 0.7 band decays to a third per sample: after a pulse it rings for a sample or two,
/// which no ring-down method can fit, and must be reported as not identified.
#[test]
fn mems_chain_modes_at_26_7_ks_s() {
    let scene = common::shipped_scene("mems_chain.toml");
    for seed in 1..=5 {
        check_resonance(&scene, 60, seed, Some(3), false);
    }
}

/// The shipped piezo chain at 100 kS/s: a 35 kHz, zeta 0.02 resonance rings for about 1 ms
/// into every free window. Its pole is annihilated before the modes' pencil, whose lag then
/// suits the 180 Hz mode (which a lag of 1 sample lost), and it is identified on its own.
#[test]
fn piezo_chain_modes_behind_a_ringing_35_khz_resonance() {
    let scene = common::shipped_scene("piezo_chain.toml");
    for seed in 1..=2 {
        check(&scene, 60, seed, None);
    }
}

/// The same modes at 26.7 kS/s without the accelerometer stage, found without `--modes`.
#[test]
fn mems_rate_modes_without_a_band() {
    let mut scene = load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../scenes/mems_chain.toml"
    ))
    .expect("scene");
    scene.sensor.accelerometer = None;
    for seed in 6..=8 {
        check(&scene, 60, seed, None);
    }
}

#[test]
fn no_resonance_is_reported_when_the_chain_has_none() {
    let mut scene = SceneFile::paper();
    scene.sensor.beam_modes = tail_beam();
    let stream = generate(&scene, 40, 14, &StreamOptions::default()).expect("stream");
    let opts = IdentifyOptions {
        sample_rate_hz: scene.sensor.sample_rate_hz,
        modes: Some(2),
        accelerometer: true,
        pulse_law: None,
        noise_rms_counts: Some(4.0),
    };
    let id = identify(&stream.samples, &opts).expect("identified");
    assert!(id.accelerometer.is_none(), "{:?}", id.accelerometer);
    assert!(id.to_toml().contains("accelerometer: not identified"));
    // The two that ring strongest.
    assert_eq!(id.modes.len(), 2);
}

#[test]
fn too_few_pulses_and_bad_options_are_errors() {
    let quiet = vec![0i16; 10_000];
    let opts = IdentifyOptions {
        sample_rate_hz: 100_000.0,
        modes: None,
        accelerometer: false,
        pulse_law: None,
        noise_rms_counts: None,
    };
    let e = identify(&quiet, &opts).expect_err("no pulses");
    assert!(e.to_string().contains("pulses"), "{e}");
    let bad = IdentifyOptions {
        sample_rate_hz: -1.0,
        ..opts
    };
    let e = identify(&quiet, &bad).expect_err("bad rate");
    assert!(e.to_string().starts_with("--sample-rate"), "{e}");
    let shape_without_band = IdentifyOptions {
        pulse_law: Some(LawSpec::Hertz),
        ..opts
    };
    let e = identify(&quiet, &shape_without_band).expect_err("no --accelerometer");
    assert!(e.to_string().starts_with("--hertz-pulses"), "{e}");
    let changing_shape = IdentifyOptions {
        accelerometer: true,
        pulse_law: Some(LawSpec::Adams {
            c_max_n_s_m: 687.16,
            d_m: 1e-5,
        }),
        ..opts
    };
    let e = identify(&quiet, &changing_shape).expect_err("not one shape");
    assert!(e.to_string().starts_with("--pulse-law"), "{e}");
}

/// A stream that ends inside a pulse (its last free window would start past the data) is
/// identified from the windows before it, not a panic.
#[test]
fn a_stream_ending_inside_a_pulse_is_identified() {
    let scene = common::shipped_scene("piezo_chain.toml");
    let mut options = StreamOptions::default();
    options.faults.end_mid_pulse = true;
    let stream = generate(&scene, 60, 4, &options).expect("stream");
    let opts = IdentifyOptions {
        sample_rate_hz: scene.sensor.sample_rate_hz,
        modes: None,
        accelerometer: true,
        pulse_law: None,
        noise_rms_counts: None,
    };
    let id = identify(&stream.samples, &opts).expect("identified");
    assert_eq!(id.modes.len(), scene.sensor.beam_modes.len(), "{id:?}");
}

/// The MEMS band fitted to the pulses' Hertz shape (`--hertz-pulses`): printed per seed.
fn mems_band(impacts: usize, seed: u64) -> (f64, f64, f64, f64) {
    mems_band_under(LawSpec::Hertz, impacts, seed)
}

/// The MEMS band of `scenes/mems_chain.toml` with its contact law set to `law`, fitted to the
/// pulses' shape of that law: its relative errors in frequency and damping and their
/// jackknife standard errors, each within the `accelerometer_tolerance` printed.
fn mems_band_under(law: LawSpec, impacts: usize, seed: u64) -> (f64, f64, f64, f64) {
    let mut scene = common::shipped_scene("mems_chain.toml");
    scene.contact = law;
    let stream = generate(&scene, impacts, seed, &StreamOptions::default()).expect("stream");
    let opts = IdentifyOptions {
        sample_rate_hz: scene.sensor.sample_rate_hz,
        modes: Some(3),
        accelerometer: true,
        pulse_law: Some(law),
        noise_rms_counts: None,
    };
    let t = std::time::Instant::now();
    let id = identify(&stream.samples, &opts).expect("identified");
    let band = scene.sensor.accelerometer.expect("band");
    let a = id.accelerometer.expect("band identified");
    let ef = a.frequency_hz.value / band.frequency_hz - 1.0;
    let ez = a.damping_ratio.value / band.damping_ratio - 1.0;
    let [tf, tz] = id.accelerometer_tolerance().expect("asked for");
    assert!(
        ef.abs() <= tf && ez.abs() <= tz,
        "tolerance {tf} / {tz}: {ef} {ez}"
    );
    println!(
        "{impacts} impacts, seed {seed}: band {:.1} Hz +- {:.1}, zeta {:.4} +- {:.4}: {:+.3} % / {:+.3} % ({} pulses, {:.1} s)",
        a.frequency_hz.value,
        a.frequency_hz.std_error,
        a.damping_ratio.value,
        a.damping_ratio.std_error,
        100.0 * ef,
        100.0 * ez,
        a.pulses,
        t.elapsed().as_secs_f64()
    );
    (
        ef,
        ez,
        a.frequency_hz.std_error / band.frequency_hz,
        a.damping_ratio.std_error / band.damping_ratio,
    )
}

/// The MEMS band, which rings for too short a time to be identified from its ring, fitted to
/// the pulses' known Hertz shape (`--hertz-pulses`), a stream of 60 impacts (seed 1): within
/// 0.2 % in frequency and 0.1 % in damping (about the stream's median rather than its quiet
/// level the band came 0.21 % and 0.12 % low), its jackknife errors within the bounds of an identified
/// resonance (1 %, 20 %), and both errors within the `accelerometer_tolerance` printed. The
/// fit takes about 4.5 minutes in a debug build (7 s optimised); the other seeds and longer
/// streams are in `mems_band_over_seeds_and_lengths`.
#[test]
fn mems_band_from_hertz_pulses() {
    check_mems_band(60, 1);
}

/// One MEMS band fit of `impacts` impacts, seed `seed`, checked as above.
fn check_mems_band(impacts: usize, seed: u64) {
    let (ef, ez, sf, sz) = mems_band(impacts, seed);
    assert!(
        ef.abs() < 0.002 && ez.abs() < 0.001,
        "seed {seed}: {ef} {ez}"
    );
    assert!(sf < 0.01 && sz < 0.2, "seed {seed}: {sf} {sz}");
}

/// The MEMS band under damped contact, fitted to the pulses' known shape of the law
/// (`--pulse-law flores --restitution 0.5`; the Hertz shape is not theirs): a stream of 60
/// impacts (seed 1) of `mems_chain` with Flores e 0.5, within the tolerance it prints and
/// within 0.5 % in frequency and 1 % in damping (the tolerance printed for a band fitted to
/// pulses), jackknife errors within the bounds of an identified resonance. Fitted with the
/// Hertz shape instead, the same stream's band is not identified (its groups scatter beyond
/// those bounds), or if it were, off by more than that tolerance.
#[test]
fn mems_band_from_damped_pulses() {
    let law = LawSpec::Flores { restitution: 0.5 };
    let (ef, ez, sf, sz) = mems_band_under(law, 60, 1);
    assert!(ef.abs() < 0.005 && ez.abs() < 0.01, "{ef} {ez}");
    assert!(sf < 0.01 && sz < 0.2, "{sf} {sz}");
    let mut scene = common::shipped_scene("mems_chain.toml");
    scene.contact = law;
    let stream = generate(&scene, 60, 1, &StreamOptions::default()).expect("stream");
    let opts = IdentifyOptions {
        sample_rate_hz: scene.sensor.sample_rate_hz,
        modes: Some(3),
        accelerometer: true,
        pulse_law: Some(LawSpec::Hertz),
        noise_rms_counts: None,
    };
    let id = identify(&stream.samples, &opts).expect("identified");
    let band = scene.sensor.accelerometer.expect("band");
    // The wrong shape leaves no band within an identified resonance's bounds, or one off by
    // more than the tolerance a band fitted to pulses states.
    if let Some(a) = id.accelerometer {
        let (ef, ez) = (
            a.frequency_hz.value / band.frequency_hz - 1.0,
            a.damping_ratio.value / band.damping_ratio - 1.0,
        );
        println!("Flores e 0.5 fitted with the Hertz shape: {ef:+.4} / {ez:+.4}");
        assert!(ef.abs() > 0.005 || ez.abs() > 0.01, "{ef} {ez}");
    } else {
        println!("Flores e 0.5 fitted with the Hertz shape: not identified");
    }
}

/// The same checks over seeds 2-5 at 60 impacts (measured: -0.035 to +0.161 % in frequency,
/// -0.018 to +0.040 % in damping) and seeds 1-3 at 120 and 240 impacts (+0.061 to +0.163 %
/// and -0.007 to +0.047 %; about the median: 0.17-0.43 % and 0.05-0.31 % low): `cargo test -p host-sim --release --test identify mems_band --
/// --include-ignored --nocapture` (about three minutes optimised).
#[test]
#[ignore]
fn mems_band_over_seeds_and_lengths() {
    for seed in 2..=5 {
        check_mems_band(60, seed);
    }
    for impacts in [120, 240] {
        for seed in 1..=3 {
            check_mems_band(impacts, seed);
        }
    }
}
