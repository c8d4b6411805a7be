//! Labelled sample streams, the data: the options a stream is made with (pulse model,
//! faults), the truth of every impact and fault, the gaps, and the errors of making, reading
//! or writing one (`FORMATS.md`). Made by [`crate::sim::generate`], stored by
//! [`crate::sim::stream_file`].
//!
//! Time line: sample `n` is taken at `t_n = phase_s + n / f_s`, `phase_s` uniform in
//! `[0, 1 / f_s)`. Sample indices (`at_sample`, `peak_sample`) count every sample of the time
//! line, dropped ones included, as the kernel counts them after `Monitor::gap`; `position`
//! indexes the stored samples (dropped ones removed).

use std::path::PathBuf;

use serde::{Deserialize, Serialize};

use crate::physics::integrate::SimError;
use crate::scene::SceneError;

/// Samples kept clear of any pulse on both sides when a quiet-stretch fault is placed (more
/// than the kernel's 32-sample pre-trigger ring).
pub const QUIET_MARGIN_SAMPLES: u64 = 64;

/// Longest time line a stream may have, in samples (2^30, 3 hours at 100 kS/s, 2 GiB).
pub const MAX_STREAM_SAMPLES: u64 = 1 << 30;

/// Why a stream could not be made, read or written.
#[derive(Debug, thiserror::Error)]
pub enum StreamError {
    /// The scene is invalid.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// An option is out of range.
    #[error("stream option {field} {problem}")]
    Option {
        /// The option.
        field: &'static str,
        /// What is wrong with it.
        problem: String,
    },
    /// The integrator failed on one impact.
    #[error("impact {impact} (R = {radius_m} m, u = {speed_m_s} m/s): {error}")]
    Simulation {
        /// Index of the impact.
        impact: usize,
        /// Its radius in m.
        radius_m: f64,
        /// Its speed in m/s.
        speed_m_s: f64,
        /// The integrator's error.
        error: SimError,
    },
    /// The stream would be longer than [`MAX_STREAM_SAMPLES`].
    #[error("the stream would have {0} samples or more, more than the limit of 2^30")]
    TooLong(u64),
    /// Reading or writing a file failed.
    #[error("{}: {error}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        error: std::io::Error,
    },
    /// A truth file is malformed.
    #[error("{}: {message}", path.display())]
    Format {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
}

/// A [`StreamError::Option`] on `field`.
pub(crate) fn opt_err(field: &'static str, problem: impl Into<String>) -> StreamError {
    StreamError::Option {
        field,
        problem: problem.into(),
    }
}

/// How each impact's force pulse is made.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum PulseModel {
    /// `impact::simulate` with the scene's contact law, force recorded on a fine grid.
    #[default]
    Integrator,
    /// The closed-form undamped shape `F_max sin^(3/2)(pi t / t_c)`
    /// ([`crate::sim::generate::hertz_sine_pulse`]), ignoring the scene's contact law: fast,
    /// within 2.4 % of `F_max` of the exact pulse.
    HertzSine,
}

/// Injected faults. Shares are probabilities in `[0, 1]`; "per impact" faults hit only impacts
/// that are not part of a pile-up, "per quiet stretch" faults are placed in the stretch
/// between two pulses (at least [`QUIET_MARGIN_SAMPLES`] plus the fault's length from either
/// pulse; a stretch too short gets none), at most one per stretch.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FaultOptions {
    /// Per impact: scale the pulse so that its rigid peak reaches `saturate_overdrive` times
    /// the ADC's full scale (on a rigid beam the kernel measures it from its flanks where it
    /// can, else rejects it as `Saturated`).
    pub saturate_share: f64,
    /// Peak over full scale of a saturated impact (`> 1`).
    pub saturate_overdrive: f64,
    /// Per quiet stretch: one sample gets `spike_counts` added (EMI; the kernel should reject
    /// it as `Spike`).
    pub spike_share: f64,
    /// Amplitude of a spike in counts, uniform on `[min, max]` (sign as given).
    pub spike_counts: [f64; 2],
    /// Per quiet stretch: the sensor holds its value for `stuck_samples` samples (the kernel
    /// reports `Stuck` once the run reaches its `stuck_samples` setting, 64 by default).
    pub stuck_share: f64,
    /// Length of a stuck run in samples (`>= 2`).
    pub stuck_samples: u32,
    /// Per impact: `drop_samples` samples are lost starting near the pulse's peak (within a
    /// quarter of the pulse); the gap is recorded (the kernel should reject it as `Gap`).
    pub drop_share: f64,
    /// Per quiet stretch: `drop_samples` samples are lost between pulses (the kernel should
    /// count the gap and report nothing).
    pub drop_quiet_share: f64,
    /// Samples lost per drop (`>= 1`).
    pub drop_samples: u32,
    /// DC drift in counts per s added to the sensor's own `dc_drift_counts_per_s`.
    pub drift_counts_per_s: f64,
    /// The stream ends right after the peak sample of the last impact (the kernel should
    /// reject it as `Truncated` at `finish`).
    pub end_mid_pulse: bool,
}

impl Default for FaultOptions {
    /// No faults; when switched on: 1.5 x full scale, spikes of 500-5000 counts, stuck runs of
    /// 100 samples, drops of 8 samples.
    fn default() -> Self {
        Self {
            saturate_share: 0.0,
            saturate_overdrive: 1.5,
            spike_share: 0.0,
            spike_counts: [500.0, 5000.0],
            stuck_share: 0.0,
            stuck_samples: 100,
            drop_share: 0.0,
            drop_quiet_share: 0.0,
            drop_samples: 8,
            drift_counts_per_s: 0.0,
            end_mid_pulse: false,
        }
    }
}

/// How a stream is laid out.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StreamOptions {
    /// Quiet time before the first impact in s (the kernel primes its baseline on the first
    /// 32 samples).
    pub lead_in_s: f64,
    /// Quiet time after the end of the last pulse in s.
    pub tail_s: f64,
    /// Quiet gap from the end of one pulse to the start of the next in s, uniform on
    /// `[min, max]`.
    pub gap_s: [f64; 2],
    /// Share of impacts (after the first) that start while the previous one is still on.
    pub pileup_share: f64,
    /// Start of a piled-up impact after the previous impact's start, in units of the previous
    /// impact's Hertz contact time, uniform on `[min, max]` with `0 <= min <= max <= 1`.
    pub pileup_offset_tc: [f64; 2],
    /// How each force pulse is made.
    pub pulse_model: PulseModel,
    /// Points of the recorded force series per Hertz contact time (at least 16); the interval
    /// is also at most the sensor's fine step `1 / (oversample f_s)` when the chain has linear
    /// stages.
    pub record_points_per_pulse: u32,
    /// Injected faults.
    pub faults: FaultOptions,
}

impl Default for StreamOptions {
    /// 10 ms lead-in and tail, gaps of 2-10 ms, no pile-ups (offset 0.5-0.95 t_c when on), the
    /// integrator with 512 points per pulse, no faults.
    fn default() -> Self {
        Self {
            lead_in_s: 0.01,
            tail_s: 0.01,
            gap_s: [0.002, 0.010],
            pileup_share: 0.0,
            pileup_offset_tc: [0.5, 0.95],
            pulse_model: PulseModel::Integrator,
            record_points_per_pulse: 512,
            faults: FaultOptions::default(),
        }
    }
}

impl StreamOptions {
    /// Checks every option.
    pub fn validate(&self) -> Result<(), StreamError> {
        nonneg("lead_in_s", self.lead_in_s)?;
        nonneg("tail_s", self.tail_s)?;
        range("gap_s", self.gap_s)?;
        nonneg("gap_s[0]", self.gap_s[0])?;
        share("pileup_share", self.pileup_share)?;
        range("pileup_offset_tc", self.pileup_offset_tc)?;
        if !(self.pileup_offset_tc[0] >= 0.0 && self.pileup_offset_tc[1] <= 1.0) {
            return Err(opt_err(
                "pileup_offset_tc",
                "must lie in [0, 1] contact times",
            ));
        }
        if self.record_points_per_pulse < 16 {
            return Err(opt_err(
                "record_points_per_pulse",
                format!("must be >= 16 (got {})", self.record_points_per_pulse),
            ));
        }
        self.faults.validate()
    }
}

impl FaultOptions {
    /// Checks every fault option: shares in `[0, 1]` (also summed over the faults that share
    /// an impact or a quiet stretch), the overdrive above 1, the run lengths.
    pub fn validate(&self) -> Result<(), StreamError> {
        share("saturate_share", self.saturate_share)?;
        share("drop_share", self.drop_share)?;
        share(
            "saturate_share + drop_share",
            self.saturate_share + self.drop_share,
        )?;
        share("spike_share", self.spike_share)?;
        share("stuck_share", self.stuck_share)?;
        share("drop_quiet_share", self.drop_quiet_share)?;
        share(
            "spike_share + stuck_share + drop_quiet_share",
            self.spike_share + self.stuck_share + self.drop_quiet_share,
        )?;
        if !(self.saturate_overdrive.is_finite() && self.saturate_overdrive > 1.0) {
            return Err(opt_err(
                "saturate_overdrive",
                format!("must be finite and > 1 (got {})", self.saturate_overdrive),
            ));
        }
        range("spike_counts", self.spike_counts)?;
        if self.stuck_samples < 2 {
            return Err(opt_err("stuck_samples", "must be >= 2"));
        }
        if self.drop_samples < 1 {
            return Err(opt_err("drop_samples", "must be >= 1"));
        }
        if !self.drift_counts_per_s.is_finite() {
            return Err(opt_err("drift_counts_per_s", "must be finite"));
        }
        Ok(())
    }
}

/// `v` finite and `>= 0`.
fn nonneg(field: &'static str, v: f64) -> Result<(), StreamError> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(opt_err(field, format!("must be finite and >= 0 (got {v})")))
    }
}

/// `v` a share in `[0, 1]`.
fn share(field: &'static str, v: f64) -> Result<(), StreamError> {
    if (0.0..=1.0).contains(&v) {
        Ok(())
    } else {
        Err(opt_err(field, format!("must be in [0, 1] (got {v})")))
    }
}

/// `r` finite with `r[0] <= r[1]`.
fn range(field: &'static str, r: [f64; 2]) -> Result<(), StreamError> {
    if r[0].is_finite() && r[1].is_finite() && r[0] <= r[1] {
        Ok(())
    } else {
        Err(opt_err(
            field,
            format!("must be finite with min <= max (got [{}, {}])", r[0], r[1]),
        ))
    }
}

/// What happened to an impact besides the physics.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ImpactFault {
    /// A clean impact.
    None,
    /// It overlaps another impact (less than one contact time apart).
    PileUp,
    /// Scaled beyond the ADC's full scale.
    Saturated,
    /// Samples were dropped during its pulse.
    Gap,
    /// The stream ends during its pulse.
    Truncated,
}

impl ImpactFault {
    /// Lower-case name used in the truth file.
    pub fn name(self) -> &'static str {
        match self {
            ImpactFault::None => "none",
            ImpactFault::PileUp => "pileup",
            ImpactFault::Saturated => "saturated",
            ImpactFault::Gap => "gap",
            ImpactFault::Truncated => "truncated",
        }
    }

    pub(crate) fn from_name(s: &str) -> Option<Self> {
        [
            ImpactFault::None,
            ImpactFault::PileUp,
            ImpactFault::Saturated,
            ImpactFault::Gap,
            ImpactFault::Truncated,
        ]
        .into_iter()
        .find(|f| f.name() == s)
    }
}

/// The truth of one impact.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Truth {
    /// Index of the class in the scene.
    pub class: usize,
    /// Sphere radius in m.
    pub radius_m: f64,
    /// Impact speed in m/s.
    pub speed_m_s: f64,
    /// Time of first contact in s (same clock as the samples).
    pub time_s: f64,
    /// Time of the peak force in s.
    pub peak_time_s: f64,
    /// Time-line index of the sample nearest to the peak force,
    /// `round((peak_time_s - phase_s) f_s)`.
    pub peak_sample: u64,
    /// Peak contact force in N the sensor saw (including `scale`).
    pub peak_force_n: f64,
    /// Duration of the force pulse in s (first contact to the first zero of the force after
    /// its peak; the contact time for undamped Hertz).
    pub duration_s: f64,
    /// Factor applied to the physical force (1 except for saturated impacts).
    pub scale: f64,
    /// Injected fault, if any.
    pub fault: ImpactFault,
}

/// Dropped samples.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Gap {
    /// Index into [`Stream::samples`] before which the samples are missing (call
    /// `Monitor::gap` after feeding `samples[..position]`).
    pub position: usize,
    /// Time-line index of the first lost sample.
    pub at_sample: u64,
    /// Samples lost.
    pub lost: u32,
}

/// Kind of a fault placed between pulses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FaultKind {
    /// A single-sample spike; `value` is the counts added.
    Spike,
    /// A stuck run; `value` is the code held, `length` its samples.
    Stuck,
}

/// A fault placed between pulses (gaps are in [`Stream::gaps`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FaultEvent {
    /// What it is.
    pub kind: FaultKind,
    /// Time-line index of its first sample.
    pub at_sample: u64,
    /// Its length in samples.
    pub length: u32,
    /// Counts added (spike) or code held (stuck).
    pub value: f64,
}

/// A labelled sample stream.
#[derive(Debug, Clone, PartialEq)]
pub struct Stream {
    /// Sample rate `f_s` in Hz.
    pub sample_rate_hz: f64,
    /// Time of time-line sample 0 in s (in `[0, 1 / f_s)`).
    pub phase_s: f64,
    /// Class names, in the scene's order.
    pub class_names: Vec<String>,
    /// ADC samples with the dropped ones removed.
    pub samples: Vec<i16>,
    /// Samples of the time line (stored + lost).
    pub timeline_samples: u64,
    /// Every impact, in order of first contact.
    pub truth: Vec<Truth>,
    /// Dropped samples, by position.
    pub gaps: Vec<Gap>,
    /// Spikes and stuck runs, by time.
    pub events: Vec<FaultEvent>,
}

/// The sample clock of a stream: `t_n = phase_s + n / fs`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Clock {
    /// Sample rate in Hz.
    pub(crate) fs: f64,
    /// Time of sample 0 in s.
    pub(crate) phase_s: f64,
}

impl Clock {
    /// Samples of the time line from sample 0 up to time `t_s` (s), unrounded:
    /// `(t_s - phase_s) fs`.
    pub(crate) fn samples_to(&self, t_s: f64) -> f64 {
        (t_s - self.phase_s) * self.fs
    }
}
