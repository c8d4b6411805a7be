//! The predicted share of impacts that clip the ADC (`host_sim::saturation`) against the
//! share measured in generated streams: impacts with a raw code at an end of the ADC range;
//! and (rigid chain) what the kernel makes of them: measured from their unclipped flanks, or
//! rejected as `Saturated`. Also against a one-dimensional
//! quadrature of the closed-form clipping radius, and zero on the paper's scene.
//!
//! Tolerance: three binomial standard errors of the measured share plus 0.5 pp for the
//! prediction's grid and its neglect of noise.

use coalshock::classifier::RejectReason;
use coalshock::{Monitor, Verdict};
use host_sim::generate::generate;
use host_sim::hertz64::HertzImpact64;
use host_sim::kernel_scene::scene_to_kernel;
use host_sim::replay::{Matching, match_truth, replay};
use host_sim::saturation::predict;
use host_sim::scene::SceneFile;
use host_sim::stream::{ImpactFault, Stream, StreamOptions};

/// Roof sandstone against a hard coal up to R = 0.08 m, dropped 0.3-1.2 m, at the paper's
/// gain (30 counts per m/s^2 on 50 kg, 16 bits: full scale 54.6 kN).
const ROOF_TOML: &str = r#"
name = "roof_saturating"
plate = "carbon_steel"
[[classes]]
name = "hard_coal"
material = { density_kg_m3 = 1385.0, modulus_pa = 13.8e9, poisson = 0.26 }
radius_m = [0.015, 0.08]
drop_height_m = [0.3, 1.2]
[[classes]]
name = "roof_sandstone"
material = "roof_sandstone"
radius_m = [0.015, 0.08]
drop_height_m = [0.3, 1.2]
[sensor]
sample_rate_hz = 100000.0
effective_mass_kg = 50.0
counts_per_m_s2 = 30.0
noise_rms_counts = 4.0
adc_bits = 16
"#;

/// Share of `stream`'s impacts with a raw code at an end of the ADC range within their pulse
/// (first contact to the end of the force, plus 2 samples).
fn raw_clipped_share(scene: &SceneFile, stream: &Stream) -> f64 {
    assert!(stream.gaps.is_empty());
    let (lo, hi) = scene.sensor.adc_range();
    let fs = stream.sample_rate_hz;
    let at = |t_s: f64| ((t_s - stream.phase_s) * fs).max(0.0) as usize;
    let clipped = stream
        .truth
        .iter()
        .filter(|t| {
            let end = (at(t.time_s + t.duration_s) + 3).min(stream.samples.len());
            stream.samples[at(t.time_s)..end]
                .iter()
                .any(|&c| i32::from(c) >= hi || i32::from(c) <= lo)
        })
        .count();
    clipped as f64 / stream.truth.len() as f64
}

/// The kernel's reports on `stream` and their pairing with its impacts. A clipped top puts
/// the kernel's largest sample anywhere on the flat: they are paired within the longest
/// pulse.
fn replayed(scene: &SceneFile, stream: &Stream) -> (Vec<coalshock::Report>, Matching) {
    let mut monitor = Monitor::new(scene_to_kernel(scene).expect("kernel scene"));
    let reports = replay(stream, &mut monitor);
    let longest = stream
        .truth
        .iter()
        .map(|t| (t.duration_s * stream.sample_rate_hz).ceil() as u64)
        .max()
        .expect("impacts");
    let m = match_truth(&reports, &stream.truth, longest);
    (reports, m)
}

fn assert_close(predicted: f64, measured: f64, n: usize, what: &str) {
    let sigma = (predicted * (1.0 - predicted) / n as f64).sqrt();
    let allowed = 3.0 * sigma + 0.005;
    eprintln!("{what}: predicted {predicted:.4}, measured {measured:.4} over {n} impacts");
    assert!(
        (predicted - measured).abs() <= allowed,
        "{what}: predicted {predicted:.4}, measured {measured:.4} (allowed {allowed:.4})"
    );
}

#[test]
fn predicted_clipping_matches_a_generated_stream_and_the_kernel() {
    let scene = SceneFile::from_toml_str(ROOF_TOML).expect("scene");
    let p = predict(&scene).expect("prediction");
    assert!(p.share > 0.1, "this scene clips: {}", p.share);
    assert!(p.warning().is_some());
    let n = 3000;
    let stream = generate(&scene, n, 12, &StreamOptions::default()).expect("stream");
    let raw = raw_clipped_share(&scene, &stream);
    assert_close(p.share, raw, n, "raw codes at full scale");

    let (reports, m) = replayed(&scene, &stream);
    assert_eq!(m.pairs.len(), n, "one report per impact");
    // The kernel measures a clipped pulse from its unclipped flanks when enough of them is
    // left, and rejects it `Saturated` otherwise: no more rejections than clipped impacts,
    // and among the clipped ones measured, a confident class at most 1 % wrong.
    let clipped: Vec<bool> = stream
        .truth
        .iter()
        .map(|t| {
            let one = Stream {
                truth: vec![t.clone()],
                ..stream.clone()
            };
            raw_clipped_share(&scene, &one) > 0.0
        })
        .collect();
    let (mut saturated, mut measured, mut confident, mut wrong) = (0, 0, 0, 0);
    for pair in &m.pairs {
        let verdict = reports[pair.report].verdict;
        if verdict == Verdict::Rejected(RejectReason::Saturated) {
            saturated += 1;
            assert!(
                clipped[pair.truth],
                "an unclipped impact rejected Saturated"
            );
        } else if clipped[pair.truth] {
            measured += 1;
            if let Verdict::Class { class, .. } = verdict {
                confident += 1;
                wrong += usize::from(class as usize != stream.truth[pair.truth].class);
            }
        }
    }
    let clipped_n = clipped.iter().filter(|&&c| c).count();
    eprintln!(
        "clipped impacts: {clipped_n}; rejected Saturated {saturated}, measured from their \
         flanks {measured}, of those given a confident class {confident}, wrong {wrong}"
    );
    assert_eq!(saturated + measured, clipped_n);
    assert!(
        measured * 2 > clipped_n,
        "most clipped impacts are measured"
    );
    assert!(
        wrong * 100 <= confident,
        "{wrong} of {confident} confident classes wrong"
    );

    // Per class, on the impacts of that class.
    for (c, (name, share)) in p.per_class.iter().enumerate() {
        let mine: Vec<_> = stream.truth.iter().filter(|t| t.class == c).collect();
        let sub = Stream {
            truth: mine.iter().map(|t| (*t).clone()).collect(),
            ..stream.clone()
        };
        assert_close(*share, raw_clipped_share(&scene, &sub), mine.len(), name);
    }
}

#[test]
fn predicted_clipping_follows_a_yielding_class() {
    // The roof sandstone yields at 300 MPa (Thornton): its peak force is capped, and fewer of
    // its impacts clip than elastic ones would.
    let text = ROOF_TOML.replace(
        "material = \"roof_sandstone\"",
        "material = \"roof_sandstone\"\nyield_pressure_pa = 300e6",
    );
    let scene = SceneFile::from_toml_str(&text).expect("scene");
    let elastic = predict(&SceneFile::from_toml_str(ROOF_TOML).expect("scene")).expect("elastic");
    let p = predict(&scene).expect("prediction");
    assert!(p.per_class[1].1 < elastic.per_class[1].1 - 0.05, "{p:?}");
    let n = 1500;
    let stream = generate(&scene, n, 7, &StreamOptions::default()).expect("stream");
    assert_close(
        p.share,
        raw_clipped_share(&scene, &stream),
        n,
        "yielding roof sandstone",
    );
}

#[test]
fn predicted_clipping_follows_a_resonant_chain() {
    // The piezo chain (accelerometer at 35 kHz, three beam modes) behind a 12-bit ADC: full
    // scale 3.4 kN on the rigid beam, the modes raising the peak.
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/piezo_chain.toml");
    let mut scene = host_sim::scene::load(path).expect("scene");
    scene.sensor.adc_bits = 12;
    let p = predict(&scene).expect("prediction");
    assert!(p.peak_gain > 1.1, "{}", p.peak_gain);
    assert!(p.share > 0.05 && p.share < 0.95, "{}", p.share);
    let n = 2000;
    let stream = generate(&scene, n, 5, &StreamOptions::default()).expect("stream");
    assert_close(
        p.share,
        raw_clipped_share(&scene, &stream),
        n,
        "resonant chain",
    );
}

#[test]
fn a_single_class_matches_the_closed_form_clipping_radius() {
    // One material, rigid chain, 10 MS/s (sampling changes nothing), uniform speed: F_max =
    // c R^2 u^1.2, so the impact clips for R >= R*(u) = sqrt(T / (S/M c u^1.2)), and with R
    // log-uniform on [R0, R1] the share is the mean over u of
    // clamp(ln(R1 / R*(u)) / ln(R1 / R0), 0, 1).
    let mut scene = SceneFile::from_toml_str(ROOF_TOML).expect("scene");
    scene.classes[0] = scene.classes[1].clone();
    scene.classes[0].name = "rock_a".into();
    scene.classes[0].speed =
        host_sim::scene::SpeedSpec::Uniform(host_sim::scene::Range64::new(1.0, 5.0));
    scene.classes[1] = scene.classes[0].clone();
    scene.classes[1].name = "rock_b".into();
    scene.sensor.sample_rate_hz = 1e7;
    let p = predict(&scene).expect("prediction");
    let m = scene.classes[0].material.material();
    let c = HertzImpact64::new(&m, &scene.plate.material(), 1.0, 1.0)
        .expect("closed forms")
        .peak_force_n;
    let full_scale_counts = 32767.0 - 0.5;
    let per_n = 30.0 / 50.0;
    let (r0, r1) = (0.015f64, 0.08f64);
    let steps = 100_000;
    let mut sum = 0.0;
    for k in 0..steps {
        let u = 1.0 + 4.0 * (k as f64 + 0.5) / steps as f64;
        let r_star = (full_scale_counts / (per_n * c * u.powf(1.2))).sqrt();
        sum += ((r1 / r_star).ln() / (r1 / r0).ln()).clamp(0.0, 1.0);
    }
    let want = sum / steps as f64;
    assert!(want > 0.05, "{want}");
    eprintln!(
        "closed form: predicted {:.5}, quadrature {want:.5}",
        p.share
    );
    assert!((p.share - want).abs() < 2e-3, "{} against {want}", p.share);
}

#[test]
fn the_paper_scene_does_not_clip() {
    let scene = SceneFile::paper();
    let p = predict(&scene).expect("prediction");
    assert_eq!(p.share, 0.0);
    assert!(p.warning().is_none());
    // Its largest impact (sandstone, R 0.04 m, 5 m/s) against the full scale.
    let hz = HertzImpact64::new(
        &scene.classes[1].material.material(),
        &scene.plate.material(),
        0.04,
        5.0,
    )
    .expect("closed forms");
    assert!(hz.peak_force_n < p.full_scale_force_n);
}

/// z-scores of `(ln F, ln t_c)` of the clipped impacts measured from their flanks, the
/// clipped impacts, those measured, and the confident classes and wrong ones among them.
fn clipped_behind(toml: &str, n: usize, seed: u64) -> (Vec<[f64; 2]>, usize, usize, usize, usize) {
    let scene = SceneFile::from_toml_str(toml).expect("scene");
    let stream = generate(&scene, n, seed, &StreamOptions::default()).expect("stream");
    let (reports, m) = replayed(&scene, &stream);
    let (mut z, mut clipped_n, mut confident, mut wrong) = (Vec::new(), 0, 0, 0);
    for pair in &m.pairs {
        let t = &stream.truth[pair.truth];
        let one = Stream {
            truth: vec![t.clone()],
            ..stream.clone()
        };
        if raw_clipped_share(&scene, &one) == 0.0 {
            continue;
        }
        clipped_n += 1;
        let r = &reports[pair.report];
        let Some(meas) = r.measurement else { continue };
        let zf =
            (f64::from(meas.peak_force_n) / t.peak_force_n).ln() / f64::from(meas.sigma_ln_force);
        let zt =
            (f64::from(meas.duration_s) / t.duration_s).ln() / f64::from(meas.sigma_ln_duration);
        z.push([zf, zt]);
        if let Verdict::Class { class, .. } = r.verdict {
            confident += 1;
            wrong += usize::from(class as usize != t.class);
        }
    }
    let measured = z.len();
    (z, clipped_n, measured, confident, wrong)
}

/// Behind an accelerometer alone the kernel measures a clipped pulse from its flanks beyond
/// the samples its equaliser's FIR took from the clipped ones, counting the equaliser's own
/// error per sample (`coalshock::chain_residual::sample_error`). The roof scene's impacts
/// behind four accelerometers (a 40 kHz and a 35 kHz piezo, lightly damped, at 100 kS/s; a
/// 58.6 kHz one at 200 kS/s; a 6.3 kHz MEMS band at 50 kS/s): the errors of `ln F` and
/// `ln t_c` against the integrator's peak and contact time stay within the stated sigmas (z
/// RMS at most 1, none beyond 4), a confident class is at most 1 % wrong, and at least 90 %
/// of the clipped impacts are measured (40 % behind the MEMS band, 6-20 samples per pulse,
/// whose flanks lie four samples further out).
#[test]
fn clipped_pulses_behind_an_accelerometer_are_measured_within_their_sigmas() {
    for (rate, accel, share) in [
        (
            100000.0,
            "{ frequency_hz = 40000.0, damping_ratio = 0.05 }",
            0.9,
        ),
        (
            200000.0,
            "{ frequency_hz = 58600.0, damping_ratio = 0.52 }",
            0.9,
        ),
        (
            50000.0,
            "{ frequency_hz = 6300.0, damping_ratio = 0.7 }",
            0.4,
        ),
        (
            100000.0,
            "{ frequency_hz = 35000.0, damping_ratio = 0.02 }",
            0.9,
        ),
    ] {
        let toml = ROOF_TOML
            .replace(
                "sample_rate_hz = 100000.0",
                &format!("sample_rate_hz = {rate:.1}"),
            )
            .replace(
                "adc_bits = 16",
                &format!("adc_bits = 16\naccelerometer = {accel}"),
            );
        let (z, clipped, measured, confident, wrong) = clipped_behind(&toml, 1000, 3);
        let rms = |i: usize| (z.iter().map(|v| v[i] * v[i]).sum::<f64>() / z.len() as f64).sqrt();
        let worst = |i: usize| z.iter().fold(0.0f64, |m, v| m.max(v[i].abs()));
        eprintln!(
            "{rate} Hz, {accel}: clipped {clipped}, measured {measured}, confident {confident}, \
             wrong {wrong}; z of ln F: RMS {:.2}, worst {:.2}; of ln t_c: RMS {:.2}, worst {:.2}",
            rms(0),
            worst(0),
            rms(1),
            worst(1)
        );
        assert!(clipped > 150, "{clipped}");
        assert!(
            measured as f64 >= share * clipped as f64,
            "{measured} of {clipped}"
        );
        for i in 0..2 {
            assert!(
                rms(i) <= 1.0 && worst(i) <= 4.0,
                "{accel}: {}, {}",
                rms(i),
                worst(i)
            );
        }
        assert!(wrong * 100 <= confident, "{wrong} of {confident}");
    }
}

/// Behind beam modes a clipped run leaves the equaliser's sections off the chain's state, and
/// that error rings under the rest of the pulse. The kernel waits for the re-estimation after
/// the pulse (`coalshock::settle_clip`), takes the error it states off the flank samples and
/// the sum, and counts its variance beside the noise. The roof scene's impacts behind four
/// chains (two lightly damped modes at 180 and 300 Hz at 40 kS/s; one at 900 Hz at 100 kS/s;
/// the same behind a 40 kHz piezo; three modes at 180, 650 and 2 100 Hz behind a 35 kHz one,
/// the chain of `docs/chain/clipping_chain.toml`): the errors of `ln F` and `ln t_c` stay within the stated
/// sigmas (z RMS at most 1, none beyond 4), a confident class is at most 1 % wrong, and at
/// least 80 % of the clipped impacts are measured.
#[test]
fn clipped_pulses_behind_beam_modes_are_measured_within_their_sigmas() {
    let low = "[[sensor.beam_modes]]\nfrequency_hz = 180.0\ndamping_ratio = 0.008\ngain = 0.105\n\
               [[sensor.beam_modes]]\nfrequency_hz = 300.0\ndamping_ratio = 0.016\ngain = 0.022\n";
    let mid = "[[sensor.beam_modes]]\nfrequency_hz = 900.0\ndamping_ratio = 0.038\ngain = 0.137\n";
    let three = "[[sensor.beam_modes]]\nfrequency_hz = 180.0\ndamping_ratio = 0.02\ngain = 0.1\n\
                 [[sensor.beam_modes]]\nfrequency_hz = 650.0\ndamping_ratio = 0.01\ngain = 0.05\n\
                 [[sensor.beam_modes]]\nfrequency_hz = 2100.0\ndamping_ratio = 0.02\ngain = 0.1\n";
    let piezo = "accelerometer = { frequency_hz = 40000.0, damping_ratio = 0.05 }\n";
    for (rate, accelerometer, modes) in [
        (40000.0, "", low),
        (100000.0, "", mid),
        (100000.0, piezo, mid),
        (
            100000.0,
            "accelerometer = { frequency_hz = 35000.0, damping_ratio = 0.02 }\n",
            three,
        ),
    ] {
        let toml = ROOF_TOML
            .replace(
                "sample_rate_hz = 100000.0",
                &format!("sample_rate_hz = {rate:.1}"),
            )
            .replace(
                "adc_bits = 16\n",
                &format!("adc_bits = 16\n{accelerometer}"),
            )
            + modes;
        let (z, clipped, measured, confident, wrong) = clipped_behind(&toml, 1000, 3);
        let rms = |i: usize| (z.iter().map(|v| v[i] * v[i]).sum::<f64>() / z.len() as f64).sqrt();
        let worst = |i: usize| z.iter().fold(0.0f64, |m, v| m.max(v[i].abs()));
        eprintln!(
            "{rate} Hz, {accelerometer}{} mode(s): clipped {clipped}, measured {measured}, confident {confident}, \
             wrong {wrong}; z of ln F: RMS {:.2}, worst {:.2}; of ln t_c: RMS {:.2}, worst {:.2}",
            modes.matches("[[").count(),
            rms(0),
            worst(0),
            rms(1),
            worst(1)
        );
        assert!(clipped > 150, "{clipped}");
        assert!(measured * 10 >= clipped * 8, "{measured} of {clipped}");
        for i in 0..2 {
            assert!(rms(i) <= 1.0 && worst(i) <= 4.0, "{}, {}", rms(i), worst(i));
        }
        assert!(wrong * 100 <= confident, "{wrong} of {confident}");
    }
}

/// Two deep clips behind beam modes, where nearly every impact passes full scale (the harder
/// class peaks at 2-9 times it). `GONTHIER`: e 0.38 at 100 kS/s behind a 41 kHz accelerometer
/// and modes at 120 and 1 500 Hz. `LANKARANI`: e 0.75 at 26.7 kS/s behind modes at 650 and
/// 2 100 Hz, 44-163 mm lumps of two rocks of 12 and 6.4 GPa, 25-34 samples at full
/// scale.
const DEEP_CLIPS: [&str; 2] = [
    r#"
name = "deep_clip_gonthier"
plate = "carbon_steel"
[[classes]]
name = "roof_sandstone"
material = "roof_sandstone"
radius_m = [0.0445, 0.0641]
drop_height_m = [0.327, 1.491]
[[classes]]
name = "coal"
material = "coal"
radius_m = [0.0445, 0.0641]
drop_height_m = [0.327, 1.491]
[contact]
law = "gonthier"
restitution = 0.38
[sensor]
sample_rate_hz = 100000.0
effective_mass_kg = 24.4
counts_per_m_s2 = 33.8
noise_rms_counts = 10.0
adc_bits = 16
accelerometer = { frequency_hz = 41008.0, damping_ratio = 0.34 }
[[sensor.beam_modes]]
frequency_hz = 120.0
damping_ratio = 0.014
gain = 0.116
[[sensor.beam_modes]]
frequency_hz = 1500.0
damping_ratio = 0.014
gain = 0.069
"#,
    r#"
name = "deep_clip_lankarani"
plate = "carbon_steel"
[[classes]]
name = "dense"
material = { density_kg_m3 = 2725, modulus_pa = 1.207e10, poisson = 0.10 }
radius_m = [0.0436, 0.1629]
speed_m_s = [2.72, 4.36]
[[classes]]
name = "light"
material = { density_kg_m3 = 1432, modulus_pa = 6.446e9, poisson = 0.27 }
radius_m = [0.0436, 0.1629]
speed_m_s = [2.72, 4.36]
[contact]
law = "lankarani_nikravesh"
restitution = 0.75
[sensor]
sample_rate_hz = 26667.0
effective_mass_kg = 25.5
counts_per_m_s2 = 28.8
noise_rms_counts = 10.0
adc_bits = 16
[[sensor.beam_modes]]
frequency_hz = 650.0
damping_ratio = 0.026
gain = 0.027
[[sensor.beam_modes]]
frequency_hz = 2100.0
damping_ratio = 0.021
gain = 0.025
"#,
];

/// After a deep clip behind beam modes the state error the run leaves rings at thousands of
/// counts under the rest of the pulse. It pushes the pulse's tail below the release level, so
/// the tail sits in the first window after the pulse, which is not believed: the pulse waits
/// for the next window, anchored afresh. And it falls and rises like a second impact (so do
/// the raw samples, by the modes' ringing), so the second-peak test is not made after the
/// run. On both `DEEP_CLIPS` at least 97 % of the clipped impacts are measured (63 % of the
/// first scene's were while the first window's verdict was final; 93 % of the second's with
/// the test made after the run), their `ln F`
/// within the stated sigmas against the integrator's peak (z RMS at most 1), and a
/// confident class is at most 1 % wrong.
#[test]
fn deep_clips_behind_beam_modes_are_measured() {
    for toml in DEEP_CLIPS {
        let (z, clipped, measured, confident, wrong) = clipped_behind(toml, 400, 5);
        let rms = (z.iter().map(|v| v[0] * v[0]).sum::<f64>() / z.len() as f64).sqrt();
        eprintln!(
            "clipped {clipped}, measured {measured}, confident {confident}, wrong {wrong}; \
             z of ln F: RMS {rms:.2}"
        );
        assert!(clipped > 300, "{clipped}");
        assert!(measured * 100 >= clipped * 97, "{measured} of {clipped}");
        assert!(rms <= 1.0, "{rms}");
        assert!(wrong * 100 <= confident, "{wrong} of {confident}");
    }
}

/// Without the second-peak test after a deep clip behind modes, what a second impact within
/// the pulse leaves is the flank fit's to catch (its sum takes the second impact), and one
/// after it the window's. With half the impacts piled up 0.5-0.95 contact times apart, at
/// most 2 % of the piled-up impacts get a wrong confident class (1 of 113 on the Gonthier
/// scene and none on the other, with the test made after the run and without it alike).
#[test]
fn deep_clips_piled_up_behind_beam_modes_are_not_confidently_wrong() {
    let opts = StreamOptions {
        pileup_share: 0.5,
        ..StreamOptions::default()
    };
    for toml in DEEP_CLIPS {
        let scene = SceneFile::from_toml_str(toml).expect("scene");
        let stream = generate(&scene, 400, 6, &opts).expect("stream");
        let (reports, m) = replayed(&scene, &stream);
        let (mut piled, mut confident, mut wrong) = (0, 0, 0);
        for pair in &m.pairs {
            let t = &stream.truth[pair.truth];
            if t.fault != ImpactFault::PileUp {
                continue;
            }
            piled += 1;
            if let Verdict::Class { class, .. } = reports[pair.report].verdict {
                confident += 1;
                wrong += usize::from(class as usize != t.class);
            }
        }
        eprintln!("piled up {piled}, confident {confident}, wrong {wrong}");
        assert!(piled > 100, "{piled}");
        assert!(wrong * 50 <= piled, "{wrong} of {piled}");
    }
}
