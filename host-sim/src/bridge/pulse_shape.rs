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
/// largest of the unit pulse's 4096 points). `None` for the Hertz law (the kernel has its
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

/// The largest `|F(t) / F_peak - g(u)|` of the force series `series` (`(t_s, force_n)` of one
/// impact, from first touch) against the table as the kernel reads it ([`PulseShape::at`], f32),
/// over `CHECK_POINTS` (1000) points of the range the flank fit reads (`SHAPE_STEP..=1 - SHAPE_STEP`
/// of the contact, which ends where the force first returns to 0). `None` for a series without
/// a positive force.
pub fn shape_error(shape: &PulseShape, series: &[(f64, f64)]) -> Option<f64> {
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
    let step = SHAPE_STEP as f64;
    let mut worst = 0.0f64;
    for i in 0..=CHECK_POINTS {
        let u = step + (1.0 - 2.0 * step) * i as f64 / CHECK_POINTS as f64;
        let measured = crate::bridge::sampled_fit::force_at(series, t0 + u * span) / peak;
        let table = f64::from(shape.at(u as f32).0);
        worst = worst.max((measured - table).abs());
    }
    Some(worst)
}

/// The table of `law` ([`law_shape`]) when every one of `series` (a scene's impacts under it)
/// stays within the kernel's [`SHAPE_ERROR`] of it ([`shape_error`]), with that largest error;
/// `None` otherwise, and then the scene's clipped damped pulses stay `Saturated`.
pub fn scene_shape<'a>(
    law: LawSpec,
    series: impl IntoIterator<Item = &'a [(f64, f64)]>,
) -> Option<(PulseShape, f64)> {
    let shape = law_shape(law)?;
    let mut worst = 0.0f64;
    for s in series {
        worst = worst.max(shape_error(&shape, s)?);
    }
    (worst <= f64::from(SHAPE_ERROR)).then_some((shape, worst))
}
