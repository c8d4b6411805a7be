//! The samples a pulse's sum takes beyond its contact: the [`PRE_TRIGGER`] samples before its
//! trigger and the [`hold_samples`] after its release. The detector cuts its pulses by them,
//! and a chain's bias ([`crate::chain_bias`]) is the error over that window.

/// Samples kept before the trigger and added to the pulse (a power of two: the detector's
/// ring is masked by it).
pub const PRE_TRIGGER: usize = 32;

/// Samples a pulse is held below its release before it ends:
/// `max(hold_setting, 0.05 t_c,min fs)` (`shortest_s` in s, `fs` in Hz), at most `u16::MAX`.
///
/// ```
/// use coalshock::pulse_window::hold_samples;
/// assert_eq!(hold_samples(2, 100e-6, 100_000.0), 2);
/// assert_eq!(hold_samples(2, 1e-3, 100_000.0), 5);
/// ```
pub fn hold_samples(hold_setting: u16, shortest_s: f32, fs: f32) -> u16 {
    (0.05 * shortest_s * fs)
        .max(hold_setting as f32)
        .min(u16::MAX as f32) as u16
}
