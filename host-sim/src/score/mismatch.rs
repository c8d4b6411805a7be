//! A sensor chain as the node believes it to be, off from the truth by stated relative errors
//! or by errors drawn within the scene's chain tolerance: how evaluations measure what a
//! wrongly identified beam or accelerometer costs, and whether the posteriors the kernel
//! widens by that tolerance are calibrated.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::scene::SceneFile;

/// Relative errors of the chain the kernel is given: each of its beam modes' and its
/// accelerometer's frequency is multiplied by `1 + frequency`, each damping ratio by
/// `1 + damping`, each mode's gain by `1 + gain` (all 0: the true chain).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ChainMismatch {
    /// Relative error of every frequency (e.g. 0.02: the kernel's are 2 % high).
    pub frequency: f64,
    /// Relative error of every damping ratio.
    pub damping: f64,
    /// Relative error of every beam mode's gain.
    pub gain: f64,
}

impl ChainMismatch {
    /// `true` when the kernel is given the true chain.
    pub fn is_none(&self) -> bool {
        *self == Self::default()
    }

    /// The scene with its chain as the kernel is told it (the simulation keeps the true one).
    pub fn applied_to(&self, scene: &SceneFile) -> SceneFile {
        scaled_chain(scene, |_, parameter| {
            1.0 + match parameter {
                Parameter::Frequency => self.frequency,
                Parameter::Damping => self.damping,
                Parameter::Gain => self.gain,
            }
        })
    }
}

/// A stage of the sensor chain.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Stage {
    /// One of the tail beam's modes.
    BeamMode,
    /// The accelerometer's resonance.
    Accelerometer,
}

/// A parameter of a stage (the accelerometer has no gain).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Parameter {
    /// Natural frequency.
    Frequency,
    /// Damping ratio.
    Damping,
    /// Gain (beam modes only).
    Gain,
}

/// The scene with every stage's chain parameter multiplied by `factor(stage, parameter)`;
/// called mode by mode (frequency, damping, gain), then for the accelerometer (frequency,
/// damping).
fn scaled_chain(scene: &SceneFile, mut factor: impl FnMut(Stage, Parameter) -> f64) -> SceneFile {
    let mut s = scene.clone();
    for m in &mut s.sensor.beam_modes {
        m.frequency_hz *= factor(Stage::BeamMode, Parameter::Frequency);
        m.damping_ratio *= factor(Stage::BeamMode, Parameter::Damping);
        m.gain *= factor(Stage::BeamMode, Parameter::Gain);
    }
    if let Some(a) = &mut s.sensor.accelerometer {
        a.frequency_hz *= factor(Stage::Accelerometer, Parameter::Frequency);
        a.damping_ratio *= factor(Stage::Accelerometer, Parameter::Damping);
    }
    s
}

/// The tolerance the kernel is told its chain has: the scene's `chain_tolerance`, or the
/// kernel's `ChainTolerance::IDENTIFIED` when unset; `[frequency, damping, gain]`, relative.
pub fn chain_tolerance(scene: &SceneFile) -> [f64; 3] {
    match &scene.sensor.chain_tolerance {
        Some(t) => [t.frequency, t.damping, t.gain],
        None => {
            let t = coalshock::equaliser::ChainTolerance::IDENTIFIED;
            [t.frequency, t.damping, t.gain].map(f64::from)
        }
    }
}

/// The accelerometer's tolerance, `[frequency, damping]` relative: the scene's
/// `accelerometer_tolerance`, else the chain's ([`chain_tolerance`]).
pub fn accelerometer_tolerance(scene: &SceneFile) -> [f64; 2] {
    match &scene.sensor.accelerometer_tolerance {
        Some(t) => [t.frequency, t.damping],
        None => {
            let [f, z, _] = chain_tolerance(scene);
            [f, z]
        }
    }
}

/// The scene with its chain as one node might have identified it: every stage's frequency,
/// damping ratio and (beam modes) gain multiplied by `1 + e`, each `e` drawn independently and
/// uniformly in `+-` its tolerance ([`chain_tolerance`], and [`accelerometer_tolerance`] for
/// the accelerometer) from a ChaCha8 generator seeded with `seed` (the errors the kernel's
/// widening takes as its noise: `coalshock::chain_bias`).
pub fn drawn_chain(scene: &SceneFile, seed: u64) -> SceneFile {
    let [f, z, g] = chain_tolerance(scene);
    let [af, az] = accelerometer_tolerance(scene);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    scaled_chain(scene, |stage, parameter| {
        let tolerance = match (stage, parameter) {
            (Stage::Accelerometer, Parameter::Frequency) => af,
            (Stage::Accelerometer, Parameter::Damping) => az,
            (_, Parameter::Frequency) => f,
            (_, Parameter::Damping) => z,
            (_, Parameter::Gain) => g,
        };
        1.0 + tolerance * (2.0 * rng.random::<f64>() - 1.0)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scales_every_stage_and_nothing_else() {
        let scene = crate::scene::load(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../scenes/piezo_chain.toml"
        ))
        .unwrap();
        let m = ChainMismatch {
            frequency: 0.02,
            damping: -0.3,
            gain: 0.2,
        };
        let s = m.applied_to(&scene);
        let (a, b) = (&scene.sensor.beam_modes[0], &s.sensor.beam_modes[0]);
        assert_eq!(b.frequency_hz, a.frequency_hz * 1.02);
        assert_eq!(b.damping_ratio, a.damping_ratio * 0.7);
        assert_eq!(b.gain, a.gain * 1.2);
        let acc = s.sensor.accelerometer.as_ref().unwrap();
        assert_eq!(acc.frequency_hz, 35_000.0 * 1.02);
        assert_eq!(s.sensor.sample_rate_hz, scene.sensor.sample_rate_hz);
        assert!(ChainMismatch::default().is_none());
    }

    #[test]
    fn drawn_chains_stay_within_the_tolerance_and_differ_by_seed() {
        let scene = crate::scene::load(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../scenes/piezo_chain.toml"
        ))
        .unwrap();
        let [tf, td, tg] = chain_tolerance(&scene);
        let [af, ad] = accelerometer_tolerance(&scene);
        let (a, b) = (drawn_chain(&scene, 1), drawn_chain(&scene, 2));
        assert_ne!(a.sensor, b.sensor);
        assert_eq!(a.sensor, drawn_chain(&scene, 1).sensor);
        for s in [&a, &b] {
            for (m, t) in s.sensor.beam_modes.iter().zip(&scene.sensor.beam_modes) {
                assert!((m.frequency_hz / t.frequency_hz - 1.0).abs() <= tf);
                assert!((m.damping_ratio / t.damping_ratio - 1.0).abs() <= td);
                assert!((m.gain / t.gain - 1.0).abs() <= tg);
            }
            let (m, t) = (
                s.sensor.accelerometer.unwrap(),
                scene.sensor.accelerometer.unwrap(),
            );
            assert!((m.frequency_hz / t.frequency_hz - 1.0).abs() <= af);
            assert!((m.damping_ratio / t.damping_ratio - 1.0).abs() <= ad);
        }
    }
}
