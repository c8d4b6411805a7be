//! A sensor chain as the node believes it to be, off from the truth by stated relative errors:
//! how evaluations measure what a wrongly identified beam or accelerometer costs.

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
        let mut s = scene.clone();
        for m in &mut s.sensor.beam_modes {
            m.frequency_hz *= 1.0 + self.frequency;
            m.damping_ratio *= 1.0 + self.damping;
            m.gain *= 1.0 + self.gain;
        }
        if let Some(a) = &mut s.sensor.accelerometer {
            a.frequency_hz *= 1.0 + self.frequency;
            a.damping_ratio *= 1.0 + self.damping;
        }
        s
    }
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
}
