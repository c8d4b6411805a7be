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

/// The scene file `name` shipped in the workspace's `scenes/` folder.
pub fn shipped_scene(name: &str) -> host_sim::scene::SceneFile {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("scenes")
        .join(name);
    host_sim::scene::load(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}
