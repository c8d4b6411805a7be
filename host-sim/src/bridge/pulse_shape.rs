//! A damped contact's pulse shape as the kernel's flank fit of a clipped pulse takes it
//! (`coalshock::PulseShape`): `g(u) = F / F_peak` and `dg/du` at the kernel's points over the
//! contact (`u` from first touch to the force's first zero), from the integrator's unit pulse
//! of a self-similar law, and how far a scene's own impacts stray from it as the kernel reads
//! the table.

use coalshock::pulse_shape::{PulseShape, SHAPE_ERROR, SHAPE_POINTS, SHAPE_STEP};

use crate::physics::law_spec::LawSpec;
use crate::sim::pulse_response::{SHAPE_POINTS as UNIT_POINTS, unit_area, unit_pulse};
use crate::sim::sensor::ForcePulse;

/// Points per contact time at which [`shape_error`] compares a pulse with the table.
const CHECK_POINTS: usize = 1000;

/// The table of `law`'s unit pulse ([`unit_pulse`], over the contact to its separation)
/// rescaled to the force pulse, from first touch to the force's first zero (a law that clamps
/// the force at 0, as Tsuji's, ends it before the separation): its value at each point, its
/// slope by a central difference over two of the unit pulse's own steps (one-sided at the
/// ends, held within the kernel's `|dg/du| <= 1e3`), its area (the unit pulse's,
/// [`unit_area`], over the force pulse's share of the contact) and where it peaks (the
/// largest of the unit pulse's 4096 points), with the reach that leaves out both end intervals
/// ([`scene_shape`] widens it where a scene's impacts allow). `None` for the Hertz law (the kernel has its
/// shape) and for a law that is not self-similar.
pub fn law_shape(law: LawSpec) -> Option<PulseShape> {
    if law == LawSpec::Hertz {
        return None;
    }
    let unit = unit_pulse(law)?;
    let (peak_x, end_x) = peak_and_end(&unit);
    let g = |u: f64| unit.force_at(u * end_x);
    let h = 2.0 / UNIT_POINTS / end_x;
    let mut shape = PulseShape {
        area: (unit_area(&unit) / end_x) as f32,
        peak_at: (peak_x / end_x) as f32,
        reach: [SHAPE_STEP, 1.0 - SHAPE_STEP],
        ..PulseShape::NONE
    };
    let last = SHAPE_POINTS - 1;
    for j in 0..SHAPE_POINTS {
        let u = j as f64 * f64::from(SHAPE_STEP);
        // At an end the force is 0 outside, so the difference is taken inside the pulse.
        let (a, b, span) = match j {
            0 => (g(h), g(2.0 * h), h),
            j if j == last => (g(1.0 - 2.0 * h), g(1.0 - h), h),
            _ => (g(u - h), g(u + h), 2.0 * h),
        };
        let value = if j == 0 || j == last { 0.0 } else { g(u) };
        shape.values[j] = value as f32;
        shape.slopes[j] = ((b - a) / span).clamp(-1e3, 1e3) as f32;
    }
    Some(shape)
}

/// Where the unit pulse peaks and where its force first returns to 0 after the peak, in its
/// own time (contact times), over its tabulated points.
fn peak_and_end(unit: &ForcePulse) -> (f64, f64) {
    let points = UNIT_POINTS as usize;
    let at = |i: usize| unit.force_at(i as f64 / UNIT_POINTS);
    let mut peak = (0, f64::MIN);
    for i in 1..points {
        if at(i) > peak.1 {
            peak = (i, at(i));
        }
    }
    let end = (peak.0..=points).find(|&i| at(i) <= 0.0).unwrap_or(points);
    (peak.0 as f64 / UNIT_POINTS, end as f64 / UNIT_POINTS)
}

/// The largest `|F(t) / F_peak - g(u)|` of one impact's pulse against a table as the kernel
/// reads it ([`PulseShape::at`], f32), in the table's first interval, between, and in its
/// last (`u` in `0..SHAPE_STEP`, `SHAPE_STEP..=1 - SHAPE_STEP`, `1 - SHAPE_STEP..=1` of the
/// contact, which ends where the force first returns to 0).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ShapeError {
    /// In the first interval.
    pub first: f64,
    /// Between the first and the last interval.
    pub inner: f64,
    /// In the last interval.
    pub last: f64,
}

/// [`ShapeError`] of the force series `series` (`(t_s, force_n)` of one impact, from first
/// touch) against `shape`, over `CHECK_POINTS` (1000) points per contact; `None` for a series
/// without a positive force.
pub fn shape_error(shape: &PulseShape, series: &[(f64, f64)]) -> Option<ShapeError> {
    let (&(t0, _), peak) = (
        series.first()?,
        series.iter().map(|p| p.1).fold(0.0, f64::max),
    );
    if peak <= 0.0 {
        return None;
    }
    let first_zero = series
        .iter()
        .skip_while(|p| p.1 <= 0.0)
        .find(|p| p.1 <= 0.0)
        .or(series.last())?
        .0;
    let span = first_zero - t0;
    let step = f64::from(SHAPE_STEP);
    let mut e = ShapeError::default();
    for i in 0..=CHECK_POINTS {
        let u = i as f64 / CHECK_POINTS as f64;
        let measured = crate::bridge::sampled_fit::force_at(series, t0 + u * span) / peak;
        let err = (measured - f64::from(shape.at(u as f32).0)).abs();
        let slot = if u < step {
            &mut e.first
        } else if u > 1.0 - step {
            &mut e.last
        } else {
            &mut e.inner
        };
        *slot = slot.max(err);
    }
    Some(e)
}

/// The table of `law` ([`law_shape`]) when every one of `series` (a scene's impacts under it)
/// stays within the kernel's [`SHAPE_ERROR`] of it between its first and last interval
/// ([`shape_error`]), with its reach (each end interval in it where every impact stays within
/// that error there too), its stated error (twice the largest of the impacts' between the end
/// intervals and in the reach's, at least 1e-5 and at most `SHAPE_ERROR`) and the largest
/// error in the reach; `None` otherwise, and then the
/// scene's clipped damped pulses stay `Saturated`.
pub fn scene_shape<'a>(
    law: LawSpec,
    series: impl IntoIterator<Item = &'a [(f64, f64)]>,
) -> Option<(PulseShape, f64)> {
    let mut shape = law_shape(law)?;
    let mut worst = ShapeError::default();
    for s in series {
        let e = shape_error(&shape, s)?;
        worst = ShapeError {
            first: worst.first.max(e.first),
            inner: worst.inner.max(e.inner),
            last: worst.last.max(e.last),
        };
    }
    let bound = f64::from(SHAPE_ERROR);
    if worst.inner > bound {
        return None;
    }
    let (first, last) = (worst.first <= bound, worst.last <= bound);
    shape.reach = [
        if first { 0.0 } else { SHAPE_STEP },
        if last { 1.0 } else { 1.0 - SHAPE_STEP },
    ];
    let held = |e: f64, ok: bool| if ok { e } else { 0.0 };
    let ends = held(worst.first, first).max(held(worst.last, last));
    // Twice what the grid's impacts show, to a floor of 1e-5, within the kernel's bound.
    let stated = |e: f64| (2.0 * e).clamp(1e-5, bound) as f32;
    shape.error = [stated(worst.inner), stated(ends)];
    Some((shape, worst.inner.max(ends)))
}
