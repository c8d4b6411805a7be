//! The tolerance `host-sim identify` states for the chain it found: a bound on each identified
//! parameter's relative error, printed as the scene's `chain_tolerance` (the beam modes) and
//! `accelerometer_tolerance`.
//!
//! Each bound is the larger of [`TOLERANCE_SIGMAS`] jackknife standard errors relative to the
//! value and a floor measured on host-sim's simulated streams (the jackknife does not see the
//! estimates' bias), rounded up to two significant digits. It works on plain values and
//! standard errors; [`crate::sim::identify`] hands them in.

/// A stated chain tolerance is a bound on each parameter's error: this many jackknife standard
/// errors.
pub const TOLERANCE_SIGMAS: f64 = 3.0;

/// The smallest relative tolerance stated for `[frequency, damping, gain]`: the largest errors
/// measured on host-sim's streams of 60 impacts (0.14 % in frequency, 13 % in damping, 4.5 % in
/// gain; `docs/chain.md`, "Identification"), with a margin. The jackknife does not see the
/// bias behind them: the slowest mode's damping comes out 5-13 % high with a standard error
/// of about 1.5 % (a gap of 2-10 ms covers a third to two of its periods).
pub const TOLERANCE_FLOOR: [f64; 3] = [2e-3, 0.15, 0.05];

/// The smallest relative tolerance stated for `[frequency, damping]` of a band fitted to the
/// Hertz pulses (`--hertz-pulses`): on host-sim's MEMS streams at 60-240 impacts it comes
/// within -0.035 to +0.16 % in frequency and -0.02 to +0.05 % in damping, the frequency a
/// little above its jackknife error (0.17-0.43 % low and 0.05-0.31 % low in damping before
/// the pulses were taken about the quiet level rather than the median). The same floor
/// stands for a restitution law's pulses (`--pulse-law`): Flores e 0.5 on one such stream
/// came within -0.023 % and +0.000 % (`docs/chain.md`).
pub const BAND_FIT_FLOOR: [f64; 2] = [5e-3, 1e-2];

/// The smallest relative tolerance stated for `[frequency, damping]` of a resonance found from
/// its ring: within 0.03 % and 2.2 % on host-sim's streams (40 kHz, zeta 0.05; 35 kHz, zeta
/// 0.02), with a margin.
pub const RING_FLOOR: [f64; 2] = [2e-3, 0.05];

/// The beam modes' tolerance, `[frequency, damping, gain]` (relative), from each identified
/// mode's `[frequency, damping, gain]` as `(value, standard error)`: for each parameter, the
/// largest [`TOLERANCE_SIGMAS`] `sigma / |value|` over the modes, at least
/// [`TOLERANCE_FLOOR`], rounded up to two digits.
pub fn modes_tolerance(modes: impl IntoIterator<Item = [(f64, f64); 3]>) -> [f64; 3] {
    let mut t = TOLERANCE_FLOOR;
    for m in modes {
        let moved = m.map(relative_bound);
        t = [t[0].max(moved[0]), t[1].max(moved[1]), t[2].max(moved[2])];
    }
    t.map(round_up_2)
}

/// An identified resonance's tolerance, `[frequency, damping]` (relative), from its frequency
/// and damping ratio as `(value, standard error)`: for each, the larger of
/// [`TOLERANCE_SIGMAS`] `sigma / |value|` and `floor` (its method's: [`RING_FLOOR`],
/// [`BAND_FIT_FLOOR`]), rounded up to two digits.
pub fn resonance_tolerance(estimates: [(f64, f64); 2], floor: [f64; 2]) -> [f64; 2] {
    let moved = estimates.map(relative_bound);
    [moved[0].max(floor[0]), moved[1].max(floor[1])].map(round_up_2)
}

/// The tolerance, `[frequency, damping]` (relative), of an accelerometer asked for and not
/// identified, whose datasheet value stays: the kernel's default (`ChainTolerance::IDENTIFIED`,
/// 2 % and 30 %), stated in f64 (the kernel's f32 values are not two-digit numbers once
/// converted: `0.3f32` is 0.30000001).
pub const UNIDENTIFIED_RESONANCE_TOLERANCE: [f64; 2] = [0.02, 0.3];

// The default above is the kernel's, to f32 precision.
const _: () = {
    let kernel = coalshock::ChainTolerance::IDENTIFIED;
    let [frequency, damping] = UNIDENTIFIED_RESONANCE_TOLERANCE;
    assert!(frequency as f32 == kernel.frequency && damping as f32 == kernel.damping);
};

/// [`TOLERANCE_SIGMAS`] standard errors relative to the value, for `(value, std_error)`.
fn relative_bound((value, std_error): (f64, f64)) -> f64 {
    TOLERANCE_SIGMAS * std_error / value.abs()
}

/// `x` rounded up to two significant digits.
fn round_up_2(x: f64) -> f64 {
    if !(x.is_finite() && x > 0.0) {
        return x;
    }
    let scale = 10f64.powi(1 - x.log10().floor() as i32);
    (x * scale).ceil() / scale
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floors_and_default_are_stated_as_they_are_and_bounds_round_up() {
        let stated = TOLERANCE_FLOOR
            .into_iter()
            .chain(BAND_FIT_FLOOR)
            .chain(RING_FLOOR)
            .chain(UNIDENTIFIED_RESONANCE_TOLERANCE);
        for x in stated {
            assert_eq!(round_up_2(x), x);
        }
        assert_eq!(round_up_2(0.02001), 0.021);
        assert_eq!(round_up_2(0.1234), 0.13);
        assert_eq!(round_up_2(0.0), 0.0);
    }
}
