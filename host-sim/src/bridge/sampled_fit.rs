//! The kernel's fit of a continuous pulse sampled at a given rate and phase: what the
//! calibrations of the sampled pulse ([`crate::bridge::calibrate::sampled_calibration`], by
//! samples per pulse, and [`crate::bridge::sampled_phase`], by samples per pulse and phase)
//! are built from.

use coalshock::detector::shape_fit;
use coalshock::math::Libm;
use coalshock::sampled_phase::neighbour_asymmetry;
use coalshock::shape_fit::five_about;

use crate::scene::SceneFile;

/// One calibration impact's continuous pulse: its force series `(t_s, force_n)`, its peak (N)
/// and its duration from the area `area / (C_AREA F_peak)` (s).
pub struct ContinuousPulse<'a> {
    /// `(t_s, force_n)`, sorted by time.
    pub series: &'a [(f64, f64)],
    /// Largest force.
    pub peak_n: f64,
    /// `area / (C_AREA peak_n)`.
    pub duration_s: f64,
    /// The kernel reads the scene's pulses by the five samples' fit
    /// ([`reads_five_samples`]).
    pub five: bool,
}

/// Whether the kernel reads `scene`'s pulses by the five samples' fit about the top
/// (`coalshock::shape_fit::peak_fit`'s `five`): when every pulse of the scene has one shape,
/// its law self-similar ([`crate::physics::law_spec::LawSpec::self_similar`]) and no class
/// yielding. The kernel decides it from what these give it: no class's envelope bent by a
/// ratio table, and no broad top (`coalshock::detector`'s `one_shape`).
pub fn reads_five_samples(scene: &SceneFile) -> bool {
    scene.contact.self_similar() && !scene.yields()
}

/// `series` (`(t_s, force_n)`) sampled every `dt` (s) from `phase * dt` after its start while
/// before its end (N); `None` for an empty series.
pub fn sample_series(series: &[(f64, f64)], dt: f64, phase: f64) -> Option<Vec<f64>> {
    let last = series.last()?.0;
    let mut t = series.first()?.0 + dt * phase;
    let mut v = Vec::new();
    while t < last {
        v.push(force_at(series, t));
        t += dt;
    }
    Some(v)
}

/// The kernel's fit of `series` sampled every `dt` from `phase * dt` after its start
/// (`0 <= phase < 1`): peak (N), duration (samples) and the neighbour asymmetry the detector
/// reports (`coalshock::sampled_phase::neighbour_asymmetry`); `five` as [`fit_samples`].
pub fn fit_sampled_at(
    series: &[(f64, f64)],
    dt: f64,
    phase: f64,
    five: bool,
) -> Option<(f64, f64, f64)> {
    let [peak, samples, a] = fit_samples(&sample_series(series, dt, phase)?, five)?;
    Some((peak, samples, a))
}

/// The kernel's fit of the samples `v` of one pulse, as the detector fits a calibrated
/// (damped or yielding) contact's: `[peak, duration (samples), neighbour asymmetry]` from the
/// largest sample, two either side of it and the sum; the peak in the unit of `v`. `five`: the
/// scene's pulses are read by the five samples' fit ([`reads_five_samples`]), else through
/// three.
pub fn fit_samples(v: &[f64], five: bool) -> Option<[f64; 3]> {
    let (i, _) = v.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1))?;
    let sum: f64 = v.iter().sum();
    let v32: Vec<f32> = v.iter().map(|&x| x as f32).collect();
    let top = five_about(&v32, i);
    let (peak, samples) = shape_fit::<Libm>(top, sum as f32, five)?;
    let a = neighbour_asymmetry(top[1], top[2], top[3]);
    Some([f64::from(peak), f64::from(samples), f64::from(a)])
}

/// Mean and standard deviation of `v` (0 and 0 when empty).
pub fn mean_and_sigma(v: &[f64]) -> (f64, f64) {
    if v.is_empty() {
        return (0.0, 0.0);
    }
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / n;
    (m, var.sqrt())
}

/// The force of the series `series` (`(t_s, force_n)`, sorted by time) at `t_s`, linearly
/// interpolated and clamped at zero; 0 outside the series.
pub fn force_at(series: &[(f64, f64)], t_s: f64) -> f64 {
    let (Some(first), Some(last)) = (series.first(), series.last()) else {
        return 0.0;
    };
    if t_s <= first.0 || t_s >= last.0 {
        return 0.0;
    }
    let i = series
        .partition_point(|p| p.0 <= t_s)
        .clamp(1, series.len() - 1);
    let (a, b) = (series[i - 1], series[i]);
    (a.1 + (b.1 - a.1) * (t_s - a.0) / (b.0 - a.0)).max(0.0)
}
