//! The sampling correction by samples per pulse and sampling phase: for a damped contact's
//! skewed pulse at 1.6 to 12 samples per pulse the three-sample fit's error depends on where
//! the samples fall as much as on how many there are; the phase shows in the neighbour
//! asymmetry [`neighbour_asymmetry`] the detector reports, and a table over `n x asymmetry`
//! (host-sim's calibration) takes the place of [`crate::SampledCalibration`]'s `n`-only
//! correction there.

use crate::error::Error;
use crate::math;

/// Samples per pulse of the first row of a [`SampledPhase`].
pub const PHASE_FIRST_N: f32 = 1.6;

/// Ratio between consecutive rows of a [`SampledPhase`]: `n_k = 1.6 * 1.25^k`, `k = 0..10`
/// (1.6 to 11.9 samples per pulse).
pub const PHASE_STEP: f32 = 1.25;

/// Rows (`n` points) of a [`SampledPhase`].
pub const PHASE_ROWS: usize = 10;

/// Asymmetry points per row of a [`SampledPhase`].
pub const PHASE_COLUMNS: usize = 8;

/// The neighbour asymmetry of a pulse's largest sample `max` (counts): `a = (after - before) /
/// max` of the samples either side of it, within `-1..=1`; 0 when `max <= 0`. It follows the
/// sampling phase: negative when the largest sample comes after the true peak.
#[inline]
pub fn neighbour_asymmetry(before: f32, max: f32, after: f32) -> f32 {
    if max > 0.0 {
        ((after - before) / max).clamp(-1.0, 1.0)
    } else {
        0.0
    }
}

/// Per row `n_k` ([`PHASE_FIRST_N`], [`PHASE_STEP`]) and per asymmetry point
/// `a_j = a_min + (a_max - a_min) j / (PHASE_COLUMNS - 1)` of that row: the mean `ln` of the
/// fitted over the continuous peak force and duration of the pulses whose asymmetry falls
/// nearest `a_j`, and their residual spread there (log units). Bilinear in `(ln n, a)`, held
/// at the ends of each row's asymmetry range; beyond the last row the classifier uses the
/// `n`-only correction. All zero ([`SampledPhase::NONE`]): no table.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SampledPhase {
    /// `[a_min, a_max]` of each row.
    pub asymmetry: [[f32; 2]; PHASE_ROWS],
    /// Mean `ln(F_fit / F_peak)` per row and asymmetry point.
    pub ln_force: [[f32; PHASE_COLUMNS]; PHASE_ROWS],
    /// Mean `ln(t_fit / t_area)` per row and asymmetry point.
    pub ln_duration: [[f32; PHASE_COLUMNS]; PHASE_ROWS],
    /// Spread (standard deviation) of `ln F_fit` per row and asymmetry point.
    pub sigma_ln_force: [[f32; PHASE_COLUMNS]; PHASE_ROWS],
    /// Spread (standard deviation) of `ln t_fit` per row and asymmetry point.
    pub sigma_ln_duration: [[f32; PHASE_COLUMNS]; PHASE_ROWS],
}

impl SampledPhase {
    /// No table.
    pub const NONE: SampledPhase = SampledPhase {
        asymmetry: [[0.0; 2]; PHASE_ROWS],
        ln_force: [[0.0; PHASE_COLUMNS]; PHASE_ROWS],
        ln_duration: [[0.0; PHASE_COLUMNS]; PHASE_ROWS],
        sigma_ln_force: [[0.0; PHASE_COLUMNS]; PHASE_ROWS],
        sigma_ln_duration: [[0.0; PHASE_COLUMNS]; PHASE_ROWS],
    };

    /// `(ln force, ln duration, sigma ln force, sigma ln duration)` at `ln n` (`n` samples per
    /// pulse) and asymmetry `a`; `None` for [`SampledPhase::NONE`] or beyond the last row
    /// (held below the first).
    pub fn at(&self, ln_samples: f32, a: f32) -> Option<(f32, f32, f32, f32)> {
        const LN_FIRST: f32 = 0.470_003_6; // ln 1.6
        const LN_STEP: f32 = 0.223_143_55; // ln 1.25
        let x = (ln_samples - LN_FIRST) / LN_STEP;
        if *self == Self::NONE || x.is_nan() || x > (PHASE_ROWS - 1) as f32 {
            return None;
        }
        let (i, f) = math::table_position(x, PHASE_ROWS);
        let row = |t: &[[f32; PHASE_COLUMNS]; PHASE_ROWS]| {
            let at = |k: usize| {
                let [lo, hi] = self.asymmetry.get(k).copied().unwrap_or([0.0, 0.0]);
                let step = (hi - lo) / (PHASE_COLUMNS - 1) as f32;
                let pos = if step > 0.0 { (a - lo) / step } else { 0.0 };
                let cells = t.get(k).map_or(&[][..], |r| &r[..]);
                math::interpolate(cells, math::table_position(pos, PHASE_COLUMNS))
            };
            at(i) + (at(i + 1) - at(i)) * f
        };
        Some((
            row(&self.ln_force),
            row(&self.ln_duration),
            row(&self.sigma_ln_force),
            row(&self.sigma_ln_duration),
        ))
    }

    /// `Err` unless every axis lies within `-1..=1` in order, every mean within `|ln| <= 2`
    /// and every spread within `0..=2`.
    pub fn check(&self) -> Result<(), Error> {
        let all = |t: &[[f32; PHASE_COLUMNS]; PHASE_ROWS], lo: f32| {
            t.iter()
                .flatten()
                .all(|v| v.is_finite() && (lo..=2.0).contains(v))
        };
        let axes = self.asymmetry.iter().all(|&[lo, hi]| {
            lo.is_finite() && hi.is_finite() && -1.0 <= lo && lo <= hi && hi <= 1.0
        });
        if !(axes && all(&self.ln_force, -2.0) && all(&self.ln_duration, -2.0)) {
            return Err(Error::OutOfRange("contact.phase ln ratios (|ln| <= 2)"));
        }
        if !(all(&self.sigma_ln_force, 0.0) && all(&self.sigma_ln_duration, 0.0)) {
            return Err(Error::OutOfRange("contact.phase sigmas (0..=2)"));
        }
        Ok(())
    }
}
