//! The walking lookups (a cursor that moves forward with time) give the searching lookups'
//! values bit for bit: the sensor chain sampling a train of pulses (rigid chain, and beam
//! modes with an accelerometer), and a contact's force series sampled from its continuous
//! output. The searching path is the signal's own `force_n` / `is_zero_on` (binary search over
//! every pulse) and the solution's `force_at` (binary search over every step).

mod common;

use common::shipped_scene;
use host_sim::generate::hertz_sine_pulse;
use host_sim::hertz64::Material64;
use host_sim::impact::{ImpactSpec, simulate};
use host_sim::law_spec::LawSpec;
use host_sim::sensor::{ForcePulse, ForceSignal, ForceTrack, PulseShape, Sensor};

/// A signal that only searches: the walking calls fall back to `force_n` and `is_zero_on`.
struct Searching<'a>(&'a ForceTrack);

impl ForceSignal for Searching<'_> {
    fn force_n(&self, t_s: f64) -> f64 {
        self.0.force_n(t_s)
    }

    fn is_zero_on(&self, t0_s: f64, t1_s: f64) -> bool {
        self.0.is_zero_on(t0_s, t1_s)
    }
}

/// 120 pulses as a stream lays them out: integrated Adams pulses recorded at 512 points and
/// closed-form Hertz pulses, 1-4 ms apart, every fifth one piled onto the one before.
fn pulse_train() -> ForceTrack {
    let mut pulses: Vec<ForcePulse> = Vec::new();
    let mut t = 1e-3;
    for i in 0..120u32 {
        let x = f64::from(i);
        let radius_m = 0.01 + 0.04 * (0.5 + 0.5 * (1.7 * x).sin());
        let speed_m_s = 0.5 + 2.5 * (0.5 + 0.5 * (2.3 * x).cos());
        let mut spec = ImpactSpec::new(
            Material64::COAL,
            Material64::CARBON_STEEL,
            radius_m,
            speed_m_s,
        );
        let hertz = spec.hertz().expect("a valid impact");
        let start_s = match pulses.last() {
            Some(prev) if i % 5 == 0 => prev.start_s + 0.3 * prev.duration_s,
            _ => t,
        };
        let pulse = if i % 3 == 0 {
            hertz_sine_pulse(&hertz, start_s)
        } else {
            spec.law = LawSpec::AdamsRestitution {
                restitution: 0.5,
                d_m: 1e-5,
            };
            let step_s = hertz.duration_s / 512.0;
            spec.record = Some(step_s);
            let r = simulate(&spec).expect("integrates");
            ForcePulse {
                start_s,
                duration_s: r.duration_s,
                scale: if i % 7 == 0 { 3.0 } else { 1.0 },
                shape: PulseShape::Series {
                    step_s,
                    force_n: r
                        .force_series
                        .expect("recorded")
                        .iter()
                        .map(|p| p.1)
                        .collect(),
                },
            }
        };
        t = start_s + pulse.duration_s + 1e-3 * (1.0 + 3.0 * (0.5 + 0.5 * (0.9 * x).sin()));
        pulses.push(pulse);
    }
    ForceTrack::new(pulses)
}

#[test]
fn sensor_walk_equals_search_bit_for_bit() {
    let track = pulse_train();
    let end_s = track
        .pulses()
        .iter()
        .map(|p| p.start_s + p.duration_s)
        .fold(0.0, f64::max);
    for name in ["paper.toml", "piezo_chain.toml"] {
        let sensor = Sensor::new(&shipped_scene(name).sensor).expect("a chain");
        let fs = sensor.sample_rate_hz();
        let n = (end_s * fs).ceil() as usize + 100;
        let phase_s = 0.37 / fs;
        let walked = sensor.analog_counts(&track, n, phase_s);
        let searched = sensor.analog_counts(&Searching(&track), n, phase_s);
        assert_eq!(walked.len(), n);
        let differ = walked
            .iter()
            .zip(&searched)
            .filter(|(a, b)| a.to_bits() != b.to_bits())
            .count();
        assert_eq!(differ, 0, "{name}: {differ} of {n} samples differ");
        assert!(
            walked.iter().filter(|v| **v != 0.0).count() > 1000,
            "{name}"
        );
        let codes = sensor.sample(&track, n, phase_s, 11);
        assert_eq!(
            codes,
            sensor.sample(&Searching(&track), n, phase_s, 11),
            "{name}"
        );
    }
}

#[test]
fn force_series_walk_equals_force_at_bit_for_bit() {
    // A clamped law with a kink, and a history-dependent one (Thornton's plastic contact turns
    // to its elastic unloading at the largest penetration).
    let laws = [
        LawSpec::AdamsRestitution {
            restitution: 0.5,
            d_m: 1e-5,
        },
        LawSpec::Thornton {
            yield_pressure_pa: 1e8,
            damping: None,
        },
    ];
    for spec_law in laws {
        let mut spec = ImpactSpec::paper_scene();
        spec.law = spec_law;
        let hertz = spec.hertz().expect("a valid impact");
        let law = spec.law.build(&hertz).expect("a law");
        let problem = host_sim::integrate::ContactProblem {
            law,
            mass_kg: hertz.mass_kg,
            speed_m_s: hertz.speed_m_s,
            gravity_m_s2: 0.0,
        };
        let sol = host_sim::integrate::integrate_contact(
            &problem,
            spec.method,
            spec.tolerance,
            &spec.limits,
        )
        .expect("integrates");
        if let LawSpec::Thornton { .. } = spec.law {
            assert!(sol.turned().is_some(), "the plastic contact turns");
        }
        let dt = sol.duration_s / 777.0;
        let series = sol.sample_force(dt).expect("a series");
        assert!(series.len() >= 777);
        for (i, &(t, f)) in series.iter().enumerate() {
            assert_eq!(t, i as f64 * dt);
            let want = sol.force_at(t).expect("inside the contact");
            assert_eq!(
                f.to_bits(),
                want.to_bits(),
                "{:?}: point {i} at {t} s",
                spec.law
            );
        }
    }
}
