//! Shared by host-sim's test files: a sensor chain of beam modes and an accelerometer.
#![allow(dead_code)]

use host_sim::scene::{BeamMode, Resonance, SensorSpec};

/// A chain at `fs` (Hz) on a 500 kg beam read at 100 counts per m/s^2, without noise, with
/// the beam `modes` `(frequency_hz, damping_ratio, gain)` and the accelerometer `acc`
/// `(frequency_hz, damping_ratio)`.
pub fn chain_spec(fs: f64, modes: &[(f64, f64, f64)], acc: Option<(f64, f64)>) -> SensorSpec {
    let mut s = SensorSpec::rigid(fs, 500.0, 100.0, 0.0, 16);
    s.beam_modes = modes
        .iter()
        .map(|&(frequency_hz, damping_ratio, gain)| BeamMode {
            frequency_hz,
            damping_ratio,
            gain,
        })
        .collect();
    s.accelerometer = acc.map(|(frequency_hz, damping_ratio)| Resonance {
        frequency_hz,
        damping_ratio,
    });
    s
}

/// One Hertz pulse (`sin^(3/2)`) of `peak_counts` from `start_s` for `duration_s` through
/// `chain`, equalised by the kernel's equaliser for `believed`: `samples` equalised counts.
pub fn equalised_hertz_pulse(
    chain: &SensorSpec,
    believed: &SensorSpec,
    (start_s, duration_s, peak_counts): (f64, f64, f64),
    samples: usize,
) -> (Vec<f32>, coalshock::EqualiserDesign) {
    use host_sim::sensor::{ForcePulse, ForceTrack, PulseShape, Sensor};
    let sensor = Sensor::new(chain).unwrap();
    let pulse = ForcePulse {
        start_s,
        duration_s,
        scale: 1.0,
        shape: PulseShape::HertzSine {
            peak_force_n: peak_counts / sensor.counts_per_newton(),
        },
    };
    let analog = sensor.analog_counts(&ForceTrack::new(vec![pulse]), samples, 0.0);
    let raw: Vec<i32> = analog.iter().map(|v| v.round() as i32).collect();
    let dynamics = host_sim::convert::sensor_to_kernel(believed)
        .unwrap()
        .dynamics;
    let fs = chain.sample_rate_hz as f32;
    let design = coalshock::EqualiserDesign::new::<coalshock::math::Libm>(&dynamics, fs).unwrap();
    let mut out = vec![0.0f32; samples];
    coalshock::Equaliser::new(&design).process(&raw, &mut out);
    (out, design)
}

/// The scene file `name` shipped in the workspace's `scenes/` folder.
pub fn shipped_scene(name: &str) -> host_sim::scene::SceneFile {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("scenes")
        .join(name);
    host_sim::scene::load(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}
