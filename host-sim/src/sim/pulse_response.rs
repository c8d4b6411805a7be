//! The contact's force pulse through the sensor chain (beam modes and accelerometer band
//! `A(s) = w_a^2 / (s^2 + 2 zeta_a w_a s + w_a^2)`), sampled: the model that
//! `host-sim identify --hertz-pulses` (or `--pulse-law`) fits to every pulse
//! ([`crate::sim::band_fit`]).
//!
//! The pulse is `F_max h((t - t_0) / t_c)` (counts), `h` the contact law's unit shape, the same
//! for every size, speed and material: the universal undamped Hertz shape
//! (`h(x) = s(2 tau x)^(3/2)` with `s'' = -(5/4) s^(3/2)`, `s(0) = 0`, `s'(0) = 1`,
//! `tau = HERTZ_TAU`), or that of a restitution-parametrised law at its restitution
//! ([`LawSpec::self_similar`]). It is tabulated once from host-sim's own integrator (the paper
//! scene under the law, [`SHAPE_POINTS`] points per contact time, linear between them as a
//! stream's recorded pulses are). The chain is the sensor's own
//! ([`crate::sim::sensor::Sensor`], one count per N): exact first-order-hold discretisation on
//! a grid of `oversample` (32) steps per sample aligned with the samples, from rest at the
//! record's first sample, a whole sample at a time once the force is over.

use crate::physics::impact::{ImpactSpec, simulate};
use crate::physics::law_spec::LawSpec;
use crate::scene::{BeamMode, Resonance, SensorSpec};
use crate::sim::sensor::{ForcePulse, ForceSignal, PulseShape, Sensor};

/// Points of the tabulated unit pulse per contact time.
pub const SHAPE_POINTS: f64 = 4096.0;

/// The unit pulse of `law`: `h(x)` for `x` in `[0, 1]` (`F_max = 1`, `t_c = 1` the contact time
/// to the force's first zero, start 0), from the integrator on the paper scene; `None` for a
/// law whose pulse shape changes with the impact ([`LawSpec::self_similar`]) or if the
/// integrator fails (it does not on the paper scene).
pub fn unit_pulse(law: LawSpec) -> Option<ForcePulse> {
    if !law.self_similar() {
        return None;
    }
    let mut spec = ImpactSpec::paper_scene();
    spec.law = law;
    let t_c = spec.hertz().ok()?.duration_s;
    spec.record = Some(t_c / SHAPE_POINTS);
    let report = simulate(&spec).ok()?;
    let scale = 1.0 / report.peak_force_n;
    let force_n = report
        .force_series?
        .into_iter()
        .map(|(_, f)| f * scale)
        .collect();
    Some(ForcePulse {
        start_s: 0.0,
        duration_s: 1.0,
        scale: 1.0,
        shape: PulseShape::Series {
            step_s: t_c / SHAPE_POINTS / report.duration_s,
            force_n,
        },
    })
}

/// `integral_0^1 h(x) dx` of a unit pulse (`C_AREA` for Hertz): its area over `F_max t_c`,
/// by the midpoint rule on 10^4 points.
pub fn unit_area(unit: &ForcePulse) -> f64 {
    const POINTS: usize = 10_000;
    (0..POINTS)
        .map(|i| unit.force_at((i as f64 + 0.5) / POINTS as f64))
        .sum::<f64>()
        / POINTS as f64
}

/// Where a pulse sits in its record.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PulseTiming {
    /// First contact `t_0` in s after the record's first sample.
    pub onset_s: f64,
    /// Contact time `t_c` in s.
    pub duration_s: f64,
}

/// The unit pulse placed at a timing, as a force signal (N) for the sensor.
struct Placed<'a> {
    unit: &'a ForcePulse,
    timing: PulseTiming,
}

impl ForceSignal for Placed<'_> {
    fn force_n(&self, t_s: f64) -> f64 {
        let t = self.timing;
        self.unit.force_at((t_s - t.onset_s) / t.duration_s)
    }

    fn is_zero_on(&self, t0_s: f64, t1_s: f64) -> bool {
        let t = self.timing;
        t1_s <= t.onset_s || t0_s >= t.onset_s + t.duration_s
    }
}

/// The chain a pulse is seen through, discretised at a sample rate.
#[derive(Debug, Clone)]
pub struct ChainModel {
    sensor: Sensor,
}

impl ChainModel {
    /// The chain of `modes` and the band `band` at `sample_rate_hz` (Hz), one count per N
    /// (`None` when the sensor refuses them, as for a damping ratio that is not positive).
    pub fn new(modes: &[BeamMode], band: Resonance, sample_rate_hz: f64) -> Option<Self> {
        let mut spec = SensorSpec::rigid(sample_rate_hz, 1.0, 1.0, 0.0, 16);
        spec.beam_modes = modes.to_vec();
        spec.accelerometer = Some(band);
        Some(ChainModel {
            sensor: Sensor::new(&spec).ok()?,
        })
    }

    /// The chain's output at samples `n = 0 .. len` (`t_n = n / f_s`, counts per count of
    /// `F_max`) for the unit pulse `unit` ([`unit_pulse`]) placed at `timing`.
    pub fn response(&self, unit: &ForcePulse, timing: PulseTiming, len: usize) -> Vec<f64> {
        self.sensor
            .analog_counts(&Placed { unit, timing }, len, 0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::hertz64::C_AREA;

    #[test]
    fn unit_pulse_peaks_at_one_mid_contact_with_the_hertz_area() {
        let unit = unit_pulse(LawSpec::Hertz).expect("integrator");
        assert!((unit.force_at(0.5) - 1.0).abs() < 1e-6);
        let area: f64 = (0..100_000)
            .map(|i| unit.force_at((i as f64 + 0.5) / 1e5))
            .sum();
        assert!((area / 1e5 - C_AREA).abs() < 1e-5, "{area}");
        assert!((unit_area(&unit) - C_AREA).abs() < 1e-5);
    }

    /// The premise of fitting one shape to every pulse: Flores e 0.5 scaled to unit peak and
    /// contact time is the same shape for a lump of another size, speed and material
    /// (sandstone, R 0.035 m, u 4.5 m/s) within 1e-4 of the peak, and so is its impulse over
    /// peak times contact time (the unit pulse's area), which lies below Hertz's `C_AREA` (the
    /// damped pulse peaks early and ends in a long low tail).
    #[test]
    fn a_restitution_law_has_one_unit_pulse() {
        let law = LawSpec::Flores { restitution: 0.5 };
        let unit = unit_pulse(law).expect("integrator");
        let mut spec = ImpactSpec::new(
            crate::physics::hertz64::Material64::SANDSTONE,
            crate::physics::hertz64::Material64::CARBON_STEEL,
            0.035,
            4.5,
        );
        spec.law = law;
        spec.record = Some(spec.hertz().unwrap().duration_s / 4096.0);
        let report = simulate(&spec).unwrap();
        let series = report.force_series.unwrap();
        let worst = series
            .iter()
            .map(|&(t, f)| (f / report.peak_force_n - unit.force_at(t / report.duration_s)).abs())
            .fold(0.0, f64::max);
        assert!(worst < 1e-4, "{worst}");
        // The other impact's impulse over its peak times its contact time, by the trapezoid.
        let impulse: f64 = series
            .windows(2)
            .map(|w| 0.5 * (w[1].0 - w[0].0) * (w[0].1 + w[1].1))
            .sum();
        let area = impulse / (report.peak_force_n * report.duration_s);
        assert!(
            (unit_area(&unit) - area).abs() < 1e-4,
            "{} {area}",
            unit_area(&unit)
        );
        assert!(area < C_AREA, "{area}");
        assert!(
            unit_pulse(LawSpec::Adams {
                c_max_n_s_m: 687.0,
                d_m: 1e-5
            })
            .is_none()
        );
    }

    #[test]
    fn a_wide_band_passes_the_pulse_and_a_narrow_one_keeps_its_area() {
        let unit = unit_pulse(LawSpec::Hertz).expect("integrator");
        let fs = 100_000.0;
        let timing = PulseTiming {
            onset_s: 2e-4,
            duration_s: 4e-4,
        };
        let band = |frequency_hz| Resonance {
            frequency_hz,
            damping_ratio: 0.7,
        };
        let wide = ChainModel::new(&[], band(1e6), fs).expect("chain");
        let y = wide.response(&unit, timing, 200);
        assert!((y[40] - 1.0).abs() < 1e-3, "{}", y[40]);
        let narrow = ChainModel::new(&[], band(5e3), fs).expect("chain");
        let area: f64 = narrow.response(&unit, timing, 200).iter().sum::<f64>() / fs;
        assert!((area / (C_AREA * 4e-4) - 1.0).abs() < 1e-3, "{area}");
    }
}
