//! The sampling correction: what a pulse of few samples does to the peak force and the
//! duration the detector reports, per number of samples per pulse, as a table the classifier
//! divides out (a damped contact's skewed pulse, host-sim's calibration; the equaliser's
//! residual behind a chain, `chain_residual`).

use crate::error::Error;
use crate::math;

/// Samples per pulse of the first point of a [`SampledCalibration`].
pub const SAMPLED_FIRST_N: f32 = 2.5;

/// Ratio between consecutive points of a [`SampledCalibration`]: `n_k = 2.5 * 1.6^k`, `k = 0..8`
/// (2.5 to 67 samples per pulse).
pub const SAMPLED_STEP: f32 = 1.6;

/// Points of a [`SampledCalibration`].
pub const SAMPLED_POINTS: usize = 8;

/// A skewed (damped) pulse of few samples is fitted with the symmetric Hertz shape: the peak
/// and the duration the detector reports then move with the number of samples per pulse `n`
/// and with the sample's phase. Per point `n_k` ([`SAMPLED_FIRST_N`], [`SAMPLED_STEP`]): the
/// mean `ln` of the measured over the continuous ratio, and its spread over phases and impacts
/// (log units), which the classifier adds to the measurement's noise. Linear in `ln n` between
/// the points and held beyond them, and looked up at the pulse's true samples per pulse. For
/// a damped contact host-sim measures it with the kernel's own fit on its integrator's
/// pulses; behind a chain the scene adds what its equaliser leaves (`chain_residual`).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SampledCalibration {
    /// Mean `ln(F_sampled / F_continuous)` at each point.
    pub ln_force: [f32; SAMPLED_POINTS],
    /// Mean `ln(t_sampled / t_continuous)` at each point.
    pub ln_duration: [f32; SAMPLED_POINTS],
    /// Spread (standard deviation) of `ln F_sampled` at each point.
    pub sigma_ln_force: [f32; SAMPLED_POINTS],
    /// Spread (standard deviation) of `ln t_sampled` at each point.
    pub sigma_ln_duration: [f32; SAMPLED_POINTS],
}

impl SampledCalibration {
    /// No sampling correction.
    pub const NONE: SampledCalibration = SampledCalibration {
        ln_force: [0.0; SAMPLED_POINTS],
        ln_duration: [0.0; SAMPLED_POINTS],
        sigma_ln_force: [0.0; SAMPLED_POINTS],
        sigma_ln_duration: [0.0; SAMPLED_POINTS],
    };

    /// `(ln force, ln duration, sigma ln force, sigma ln duration)` at `ln n` (`n` samples per
    /// pulse), linear between the points and held beyond them.
    pub fn at(&self, ln_samples: f32) -> (f32, f32, f32, f32) {
        const LN_FIRST: f32 = 0.916_290_7; // ln 2.5
        const LN_STEP: f32 = 0.470_003_6; // ln 1.6
        let at = math::table_position((ln_samples - LN_FIRST) / LN_STEP, SAMPLED_POINTS);
        let lerp = |t: &[f32; SAMPLED_POINTS]| math::interpolate(t, at);
        (
            lerp(&self.ln_force),
            lerp(&self.ln_duration),
            lerp(&self.sigma_ln_force),
            lerp(&self.sigma_ln_duration),
        )
    }

    /// Both corrections at once: the means added, the spreads in quadrature (each kept within
    /// the ranges a scene accepts, `|ln| <= 2` and `sigma <= 2`).
    pub fn combined(&self, other: &SampledCalibration) -> SampledCalibration {
        let mut out = *self;
        for (mine, theirs) in [
            (&mut out.ln_force, &other.ln_force),
            (&mut out.ln_duration, &other.ln_duration),
        ] {
            for (a, b) in mine.iter_mut().zip(theirs) {
                *a = (*a + b).max(-2.0).min(2.0);
            }
        }
        for (mine, theirs) in [
            (&mut out.sigma_ln_force, &other.sigma_ln_force),
            (&mut out.sigma_ln_duration, &other.sigma_ln_duration),
        ] {
            for (a, b) in mine.iter_mut().zip(theirs) {
                *a = libm::sqrtf(*a * *a + b * b).min(2.0);
            }
        }
        out
    }

    pub(crate) fn check(&self) -> Result<(), Error> {
        let all = |t: &[f32; SAMPLED_POINTS], lo: f32| {
            t.iter().all(|v| v.is_finite() && (lo..=2.0).contains(v))
        };
        if !(all(&self.ln_force, -2.0) && all(&self.ln_duration, -2.0)) {
            return Err(Error::OutOfRange("contact.sampled ln ratios (|ln| <= 2)"));
        }
        if !(all(&self.sigma_ln_force, 0.0) && all(&self.sigma_ln_duration, 0.0)) {
            return Err(Error::OutOfRange("contact.sampled sigmas (0..=2)"));
        }
        Ok(())
    }
}
