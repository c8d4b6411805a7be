//! The kernel's fit of a calibration pulse seen through a sensor chain and the kernel's own
//! equaliser, at every sampling phase: what [`crate::bridge::sampled_phase`] calibrates a
//! damped contact on behind a chain that is not rigid.
//!
//! Behind a chain the detector fits the equalised samples, not the force's. The equaliser
//! gives the force back only within the sampled band (its accelerometer inverse is
//! regularised there), so at a few samples per pulse it reshapes the pulse, and how depends on
//! the pulse's spectrum. The kernel's own residual (`coalshock::chain_residual`) is the Hertz
//! pulse's, and is added to the correction by samples per pulse alone; a damped pulse is
//! shorter and skewed, and through the MEMS band at 3-12 samples per pulse its fit moves
//! otherwise. The phase table so calibrated holds the equaliser's residual itself, and the
//! kernel adds nothing to it.
//!
//! At `n` samples per pulse a pulse of duration `t` (from its area) is stretched in time by
//! `n / (f_s t)`, so that it lasts `n` samples of the chain's rate `f_s`; every ratio the
//! table holds is scale free. host-sim's exact chain (`crate::sim::sensor`, noise-free, no
//! ADC) integrates it, sampled [`EqualisedChain::phases`] times per sample of `f_s`, so one
//! run gives every phase: phase `j` is every `phases`-th fine sample from `j`, and lies
//! `(j + offset) / phases` of a sample after the pulse's start, as the rigid fit's
//! (`crate::bridge::sampled_fit::sample_series`). Each phase's samples, rounded to integer
//! counts at a peak of [`PEAK_COUNTS`], go through a fresh `coalshock::Equaliser` and are
//! fitted as the detector fits them (`crate::bridge::sampled_fit::fit_samples`).

use coalshock::Equaliser;
use coalshock::equaliser::{ChainDynamics, EqualiserDesign};
use coalshock::math::DefaultBackend;

use crate::bridge::sampled_fit::{ContinuousPulse, fit_samples, force_at};
use crate::scene::SensorSpec;
use crate::sim::sensor::{FnForce, Sensor};

/// Peak of the stretched pulse in counts of the rigid beam: rounding the chain's output to
/// integer counts (as the equaliser takes them) then costs 5e-7 of it.
pub const PEAK_COUNTS: f64 = 1e6;

/// Fine steps per fine sample of the chain's integration (its `oversample`): the force is
/// linear between steps, and a pulse of 1.6 samples spans 100 of them at 32 phases.
const FINE_OVERSAMPLE: u32 = 2;

/// Samples run after the stretched pulse's end, beyond the equaliser's delay: the fit takes
/// two samples either side of the largest, and the sum what the equaliser leaves after it.
const TAIL_SAMPLES: usize = 4;

/// A non-rigid chain as the kernel equalises it: host-sim's exact chain sampled
/// [`EqualisedChain::phases`] times per sample, and the kernel's equaliser design at the
/// chain's rate.
pub struct EqualisedChain {
    fine: Sensor,
    design: EqualiserDesign,
    sample_rate_hz: f64,
    phases: usize,
}

impl EqualisedChain {
    /// The chain of `spec`, whose kernel dynamics are `dynamics`, sampled `phases` times per
    /// sample; `None` for a rigid chain (the equaliser is the identity) or one the kernel
    /// cannot equalise (its scene build refuses it, naming the stage).
    pub fn new(spec: &SensorSpec, dynamics: &ChainDynamics, phases: usize) -> Option<Self> {
        let fs = spec.sample_rate_hz;
        let design = EqualiserDesign::new::<DefaultBackend>(dynamics, fs as f32).ok()?;
        if design.is_identity() || phases == 0 {
            return None;
        }
        let fine_spec = SensorSpec {
            sample_rate_hz: fs * phases as f64,
            noise_rms_counts: 0.0,
            dc_offset_counts: 0.0,
            dc_drift_counts_per_s: 0.0,
            oversample: FINE_OVERSAMPLE,
            ..spec.clone()
        };
        let fine = Sensor::new(&fine_spec).ok()?;
        Some(Self {
            fine,
            design,
            sample_rate_hz: fs,
            phases,
        })
    }

    /// Fine samples per sample of the chain's rate.
    pub fn phases(&self) -> usize {
        self.phases
    }

    /// The kernel's equaliser design for the chain.
    pub fn design(&self) -> &EqualiserDesign {
        &self.design
    }

    /// `pulse` stretched to `n` samples per pulse, through the chain and the equaliser, fitted
    /// at the phases `(j + offset) / phases`, `j = 0..phases` (`0 <= offset < 1`): per phase
    /// the fit's peak over `pulse.peak_n`, its duration in samples and the neighbour asymmetry
    /// (`None` where the fit fails).
    pub fn fits(&self, pulse: &ContinuousPulse, n: f64, offset: f64) -> Vec<Option<[f64; 3]>> {
        let samples = self.samples(pulse, n, offset);
        samples.iter().map(|v| fit_samples(v, pulse.five)).collect()
    }

    /// `pulse` stretched to `n` samples per pulse, through the chain and the equaliser, at the
    /// phases `(j + offset) / phases`: per phase the equalised samples over `pulse.peak_n`,
    /// from one sample before the pulse (the equaliser's delay included).
    pub fn samples(&self, pulse: &ContinuousPulse, n: f64, offset: f64) -> Vec<Vec<f64>> {
        let (Some(&(t_first, _)), Some(&(t_last, _))) = (pulse.series.first(), pulse.series.last())
        else {
            return vec![Vec::new(); self.phases];
        };
        let t_s = 1.0 / self.sample_rate_hz;
        let stretch = n * t_s / pulse.duration_s;
        // The pulse starts one sample in: the chain is at rest before it.
        let scale = PEAK_COUNTS / (pulse.peak_n * self.fine.counts_per_newton());
        let force = FnForce(|t: f64| scale * force_at(pulse.series, t_first + (t - t_s) / stretch));
        let samples = 1
            + ((t_last - t_first) * stretch / t_s).ceil() as usize
            + self.design.delay_samples() as usize
            + TAIL_SAMPLES;
        let p = self.phases;
        let fine = self
            .fine
            .analog_counts(&force, samples * p, offset * t_s / p as f64);
        (0..p)
            .map(|j| {
                let raw: Vec<i32> = fine
                    .iter()
                    .skip(j)
                    .step_by(p)
                    .map(|v| v.round() as i32)
                    .collect();
                let mut out = vec![0.0f32; raw.len()];
                Equaliser::new(&self.design).process(&raw, &mut out);
                out.iter().map(|&x| f64::from(x) / PEAK_COUNTS).collect()
            })
            .collect()
    }
}
