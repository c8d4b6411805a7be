//! Labelled sample streams: impacts drawn from a scene's priors, their contact force from the
//! integrator, through the sensor chain, with optional injected faults, and the truth of every
//! impact and fault; replay through the kernel's `Monitor` and matching of its reports to the
//! truth; the `.bin` + `.truth.csv` file pair (`FORMATS.md`).
//!
//! Time line: sample `n` is taken at `t_n = phase_s + n / f_s`, `phase_s` uniform in
//! `[0, 1 / f_s)`. Sample indices (`at_sample`, `peak_sample`) count every sample of the time
//! line, dropped ones included, as the kernel counts them after `Monitor::gap`; `position`
//! indexes the stored samples (dropped ones removed).
//!
//! Determinism: one seed gives one stream on every machine. Three independent ChaCha8 streams
//! are derived from it (impacts and timing; sensor noise; faults), so switching a fault on
//! or off does not change the impacts. The impacts are drawn one after another; their pulses are
//! simulated on every core ([`crate::sim::par`]) and taken in order, so nothing depends on the
//! number of threads.

use std::io::{Read, Write};
use std::path::{Path, PathBuf};

use coalshock::math::Backend;
use coalshock::{Event, FlowSlot, Monitor, Report};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::physics::hertz64::HertzImpact64;
use crate::physics::impact::{ImpactSpec, simulate};
use crate::physics::integrate::SimError;
use crate::scene::{SceneError, SceneFile, SpeedSpec};
use crate::sim::par::map_ordered;
use crate::sim::sensor::{ForcePulse, ForceTrack, PulseShape, Sensor};

/// Samples kept clear of any pulse on both sides when a quiet-stretch fault is placed (more
/// than the kernel's 32-sample pre-trigger ring).
pub const QUIET_MARGIN_SAMPLES: u64 = 64;

/// Longest time line a stream may have, in samples (2^30, 3 hours at 100 kS/s, 2 GiB).
pub const MAX_STREAM_SAMPLES: u64 = 1 << 30;

/// ChaCha8 stream of the impacts and their timing.
const RNG_IMPACTS: u64 = 1;
/// ChaCha8 stream of the sensor noise seed.
const RNG_NOISE: u64 = 2;
/// ChaCha8 stream of the faults.
const RNG_FAULTS: u64 = 3;

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

fn opt_err(field: &'static str, problem: impl Into<String>) -> StreamError {
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
    /// The closed-form undamped shape `F_max sin^(3/2)(pi t / t_c)` ([`hertz_sine_pulse`]),
    /// ignoring the scene's contact law: fast, within 2.4 % of `F_max` of the exact pulse.
    HertzSine,
}

/// Injected faults. Shares are probabilities in `[0, 1]`; "per impact" faults hit only impacts
/// that are not part of a pile-up, "per quiet stretch" faults are placed in the stretch
/// between two pulses (at least [`QUIET_MARGIN_SAMPLES`] plus the fault's length from either
/// pulse; a stretch too short gets none), at most one per stretch.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FaultOptions {
    /// Per impact: scale the pulse so that its rigid peak reaches `saturate_overdrive` times
    /// the ADC's full scale (the kernel should reject it as `Saturated`).
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
        let nonneg = |field, v: f64| {
            if v.is_finite() && v >= 0.0 {
                Ok(())
            } else {
                Err(opt_err(field, format!("must be finite and >= 0 (got {v})")))
            }
        };
        let share = |field, v: f64| {
            if (0.0..=1.0).contains(&v) {
                Ok(())
            } else {
                Err(opt_err(field, format!("must be in [0, 1] (got {v})")))
            }
        };
        let range = |field, r: [f64; 2]| {
            if r[0].is_finite() && r[1].is_finite() && r[0] <= r[1] {
                Ok(())
            } else {
                Err(opt_err(
                    field,
                    format!("must be finite with min <= max (got [{}, {}])", r[0], r[1]),
                ))
            }
        };
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
        let f = &self.faults;
        share("saturate_share", f.saturate_share)?;
        share("drop_share", f.drop_share)?;
        share(
            "saturate_share + drop_share",
            f.saturate_share + f.drop_share,
        )?;
        share("spike_share", f.spike_share)?;
        share("stuck_share", f.stuck_share)?;
        share("drop_quiet_share", f.drop_quiet_share)?;
        share(
            "spike_share + stuck_share + drop_quiet_share",
            f.spike_share + f.stuck_share + f.drop_quiet_share,
        )?;
        if !(f.saturate_overdrive.is_finite() && f.saturate_overdrive > 1.0) {
            return Err(opt_err(
                "saturate_overdrive",
                format!("must be finite and > 1 (got {})", f.saturate_overdrive),
            ));
        }
        range("spike_counts", f.spike_counts)?;
        if f.stuck_samples < 2 {
            return Err(opt_err("stuck_samples", "must be >= 2"));
        }
        if f.drop_samples < 1 {
            return Err(opt_err("drop_samples", "must be >= 1"));
        }
        if !f.drift_counts_per_s.is_finite() {
            return Err(opt_err("drift_counts_per_s", "must be finite"));
        }
        Ok(())
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

    fn from_name(s: &str) -> Option<Self> {
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

/// One impact before simulation.
#[derive(Debug, Clone)]
struct Draw {
    class: usize,
    radius_m: f64,
    speed_m_s: f64,
    start_s: f64,
    hertz: HertzImpact64,
    pileup: bool,
}

/// The closed-form undamped pulse `F_max sin^(3/2)(pi t / t_c)` of an impact (the shape the
/// integrator is replaced by under [`PulseModel::HertzSine`]).
pub fn hertz_sine_pulse(hertz: &HertzImpact64, start_s: f64) -> ForcePulse {
    ForcePulse {
        start_s,
        duration_s: hertz.duration_s,
        scale: 1.0,
        shape: PulseShape::HertzSine {
            peak_force_n: hertz.peak_force_n,
        },
    }
}

/// Makes a stream of `n_impacts` impacts of `scene` from `seed`.
pub fn generate(
    scene: &SceneFile,
    n_impacts: usize,
    seed: u64,
    options: &StreamOptions,
) -> Result<Stream, StreamError> {
    generate_with_progress(scene, n_impacts, seed, options, &mut |_| {})
}

fn rng_for(seed: u64, stream: u64) -> ChaCha8Rng {
    let mut r = ChaCha8Rng::seed_from_u64(seed);
    r.set_stream(stream);
    r
}

/// [`generate`], calling `progress(done)` after each impact is simulated.
pub fn generate_with_progress(
    scene: &SceneFile,
    n_impacts: usize,
    seed: u64,
    options: &StreamOptions,
    progress: &mut dyn FnMut(usize),
) -> Result<Stream, StreamError> {
    generate_inner(
        scene,
        Source::Drawn(None),
        n_impacts,
        seed,
        options,
        progress,
    )
}

/// [`generate`] with every impact of class `class` (index in the scene's order) instead of a
/// class drawn from the priors; radius, speed, timing, noise and faults are drawn exactly as
/// [`generate`] draws them. A class index out of range is an option error.
pub fn generate_class(
    scene: &SceneFile,
    class: usize,
    n_impacts: usize,
    seed: u64,
    options: &StreamOptions,
) -> Result<Stream, StreamError> {
    if class >= scene.classes.len() {
        return Err(opt_err(
            "class",
            format!(
                "must be a class index below {} (got {class})",
                scene.classes.len()
            ),
        ));
    }
    generate_inner(
        scene,
        Source::Drawn(Some(class)),
        n_impacts,
        seed,
        options,
        &mut |_| {},
    )
}

/// One impact of a given class, size, speed and time (see [`generate_planned`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlannedImpact {
    /// Index of the class in the scene.
    pub class: usize,
    /// Sphere radius in m.
    pub radius_m: f64,
    /// Impact speed in m/s.
    pub speed_m_s: f64,
    /// First contact in s after the lead-in (`options.lead_in_s`); impacts that start while
    /// the previous one is on are marked as pile-ups.
    pub start_s: f64,
}

/// A stream of the impacts of `plan` (class, radius, speed and start time given), through the
/// scene's contact law and sensor chain, with `seed` for the sample phase, the noise and the
/// faults; `options.gap_s` and `pileup_share` are not used.
pub fn generate_planned(
    scene: &SceneFile,
    plan: &[PlannedImpact],
    seed: u64,
    options: &StreamOptions,
) -> Result<Stream, StreamError> {
    for (i, p) in plan.iter().enumerate() {
        if p.class >= scene.classes.len() {
            return Err(opt_err(
                "plan.class",
                format!("impact {i}: no class {}", p.class),
            ));
        }
        let ok = |v: f64| v.is_finite() && v > 0.0;
        if !(ok(p.radius_m) && ok(p.speed_m_s) && p.start_s.is_finite() && p.start_s >= 0.0) {
            return Err(opt_err(
                "plan",
                format!("impact {i}: radius and speed must be > 0, start >= 0"),
            ));
        }
    }
    generate_inner(
        scene,
        Source::Plan(plan),
        plan.len(),
        seed,
        options,
        &mut |_| {},
    )
}

/// Where a stream's impacts come from.
#[derive(Clone, Copy)]
enum Source<'a> {
    /// Drawn from the scene's priors, of one class when given.
    Drawn(Option<usize>),
    /// Given impact by impact.
    Plan(&'a [PlannedImpact]),
}

fn generate_inner(
    scene: &SceneFile,
    source: Source<'_>,
    n_impacts: usize,
    seed: u64,
    options: &StreamOptions,
    progress: &mut dyn FnMut(usize),
) -> Result<Stream, StreamError> {
    let fixed_class = match source {
        Source::Drawn(c) => c,
        Source::Plan(_) => None,
    };
    scene.validate()?;
    options.validate()?;
    let faults = &options.faults;
    let mut sensor_spec = scene.sensor.clone();
    sensor_spec.dc_drift_counts_per_s += faults.drift_counts_per_s;
    let sensor = Sensor::new(&sensor_spec)?;
    let fs = sensor.sample_rate_hz();
    let mut rng = rng_for(seed, RNG_IMPACTS);
    let phase_s = rng.random::<f64>() / fs;

    // 1. Impacts and timing.
    let probs = scene.class_probabilities();
    let plate = scene.plate.material();
    let mut draws: Vec<Draw> = Vec::with_capacity(n_impacts.min(1 << 16));
    let mut busy_until = phase_s + options.lead_in_s;
    for i in 0..n_impacts {
        let (r_class, r_radius, r_speed): (f64, f64, f64) =
            (rng.random(), rng.random(), rng.random());
        let (r_pile, r_gap, r_offset): (f64, f64, f64) = (rng.random(), rng.random(), rng.random());
        let mut acc = 0.0;
        let class = fixed_class.unwrap_or_else(|| {
            probs
                .iter()
                .position(|p| {
                    acc += p;
                    r_class < acc
                })
                .unwrap_or(probs.len() - 1)
        });
        let planned = match source {
            Source::Plan(plan) => plan.get(i),
            Source::Drawn(_) => None,
        };
        let class = planned.map_or(class, |p| p.class);
        let c = &scene.classes[class];
        let (r0, r1) = (c.radius_m.min.ln(), c.radius_m.max.ln());
        let radius_m = (r0 + r_radius * (r1 - r0)).exp();
        let speed_m_s = match c.speed {
            SpeedSpec::Uniform(s) => s.min + r_speed * (s.max - s.min),
            SpeedSpec::DropHeight(h) => {
                crate::scene::drop_speed_m_s(h.min + r_speed * (h.max - h.min))
            }
        };
        let (radius_m, speed_m_s) =
            planned.map_or((radius_m, speed_m_s), |p| (p.radius_m, p.speed_m_s));
        let hertz = HertzImpact64::new(&c.material.material(), &plate, radius_m, speed_m_s)
            .map_err(|error| StreamError::Simulation {
                impact: i,
                radius_m,
                speed_m_s,
                error,
            })?;
        if let Some(p) = planned {
            let start_s = phase_s + options.lead_in_s + p.start_s;
            let pileup = start_s < busy_until && i > 0;
            if let (true, Some(prev)) = (pileup, draws.last_mut()) {
                prev.pileup = true;
            }
            busy_until = busy_until.max(start_s + hertz.duration_s);
            draws.push(Draw {
                class,
                radius_m,
                speed_m_s,
                start_s,
                hertz,
                pileup,
            });
            continue;
        }
        let pileup = i > 0 && r_pile < options.pileup_share;
        let start_s = match draws.last_mut() {
            Some(prev) if pileup => {
                prev.pileup = true;
                let [a, b] = options.pileup_offset_tc;
                prev.start_s + (a + r_offset * (b - a)) * prev.hertz.duration_s
            }
            _ => {
                let [a, b] = options.gap_s;
                busy_until + if i == 0 { 0.0 } else { a + r_gap * (b - a) }
            }
        };
        busy_until = busy_until.max(start_s + hertz.duration_s);
        let so_far = ((busy_until - phase_s) * fs).ceil();
        if so_far.is_nan() || so_far > MAX_STREAM_SAMPLES as f64 {
            return Err(StreamError::TooLong(so_far.min(u64::MAX as f64) as u64));
        }
        draws.push(Draw {
            class,
            radius_m,
            speed_m_s,
            start_s,
            hertz,
            pileup,
        });
    }

    // 2. Force pulses.
    let fine_step_s = if sensor.is_rigid() {
        f64::INFINITY
    } else {
        1.0 / (fs * sensor_spec.oversample as f64)
    };
    let mut pulses = Vec::with_capacity(draws.len());
    let mut truth = Vec::with_capacity(draws.len());
    // Each impact's pulse depends on its draw only: simulated on every core, taken in order.
    let make_pulse = |i: usize, d: &Draw| match options.pulse_model {
        PulseModel::HertzSine => Ok((
            hertz_sine_pulse(&d.hertz, d.start_s),
            0.5 * d.hertz.duration_s,
            d.hertz.peak_force_n,
            d.hertz.duration_s,
        )),
        PulseModel::Integrator => simulate_pulse(scene, d, options, fine_step_s).map_err(|error| {
            StreamError::Simulation {
                impact: i,
                radius_m: d.radius_m,
                speed_m_s: d.speed_m_s,
                error,
            }
        }),
    };
    map_ordered(&draws, make_pulse, |i, made| {
        let d = &draws[i];
        let (pulse, peak_tau_s, peak_force_n, duration_s) = made?;
        let peak_time_s = d.start_s + peak_tau_s;
        truth.push(Truth {
            class: d.class,
            radius_m: d.radius_m,
            speed_m_s: d.speed_m_s,
            time_s: d.start_s,
            peak_time_s,
            peak_sample: ((peak_time_s - phase_s) * fs).round().max(0.0) as u64,
            peak_force_n,
            duration_s,
            scale: 1.0,
            fault: if d.pileup {
                ImpactFault::PileUp
            } else {
                ImpactFault::None
            },
        });
        pulses.push(pulse);
        progress(i + 1);
        Ok::<(), StreamError>(())
    })?;

    // 3. Faults on impacts (drawn for every impact, so the draws do not depend on the shares).
    let mut frng = rng_for(seed, RNG_FAULTS);
    let full_scale = sensor.adc_range().1 as f64;
    let last = n_impacts.checked_sub(1);
    for (i, (t, p)) in truth.iter_mut().zip(pulses.iter_mut()).enumerate() {
        let r: f64 = frng.random();
        if faults.end_mid_pulse && Some(i) == last {
            t.fault = ImpactFault::Truncated;
        } else if t.fault == ImpactFault::None {
            if r < faults.saturate_share {
                let peak_counts = t.peak_force_n * sensor.counts_per_newton();
                let scale = (faults.saturate_overdrive * full_scale / peak_counts).max(1.0);
                p.scale = scale;
                t.scale = scale;
                t.peak_force_n *= scale;
                t.fault = ImpactFault::Saturated;
            } else if r < faults.saturate_share + faults.drop_share {
                t.fault = ImpactFault::Gap;
            }
        }
    }

    // 4. Time line length.
    let end_s = pulses
        .iter()
        .map(|p| p.start_s + p.duration_s)
        .fold(phase_s + options.lead_in_s, f64::max)
        + options.tail_s;
    let mut timeline = ((end_s - phase_s) * fs).ceil().max(1.0) as u64;
    if let (true, Some(t)) = (faults.end_mid_pulse, truth.last()) {
        timeline = timeline.min(t.peak_sample + 1);
    }
    if timeline > MAX_STREAM_SAMPLES {
        return Err(StreamError::TooLong(timeline));
    }

    // 5. Sensor.
    let noise_seed = rng_for(seed, RNG_NOISE).random::<u64>();
    let track = ForceTrack::new(pulses);
    let mut samples = sensor.sample(&track, timeline as usize, phase_s, noise_seed);

    // 6. Faults between pulses and drops inside pulses.
    let span = |t: &Truth| {
        let a = ((t.time_s - phase_s) * fs).floor().max(0.0) as u64;
        let b = ((t.time_s + t.duration_s.max(0.0) - phase_s) * fs)
            .ceil()
            .max(0.0) as u64;
        (a, b)
    };
    let mut busy: Vec<(u64, u64)> = Vec::new();
    for (a, b) in truth.iter().map(span) {
        match busy.last_mut() {
            Some(last) if a <= last.1 => last.1 = last.1.max(b),
            _ => busy.push((a, b)),
        }
    }
    let mut drops: Vec<(u64, u32)> = Vec::new();
    let mut events = Vec::new();
    for t in truth.iter() {
        if t.fault == ImpactFault::Gap {
            let (a, b) = span(t);
            let quarter = (b - a) / 4;
            let lo = t.peak_sample.saturating_sub(quarter).max(1);
            let hi = (t.peak_sample + quarter).max(lo);
            let at = lo + ((hi - lo + 1) as f64 * frng.random::<f64>()) as u64;
            drops.push((at.min(hi), faults.drop_samples));
        }
    }
    for w in busy.windows(2) {
        let r: f64 = frng.random();
        let r_pos: f64 = frng.random();
        let r_val: f64 = frng.random();
        let (lo, hi) = (
            w[0].1 + QUIET_MARGIN_SAMPLES,
            w[1].0.saturating_sub(QUIET_MARGIN_SAMPLES),
        );
        let fits = |len: u64| hi >= lo + len && lo + len <= timeline;
        let pick = |len: u64| lo + ((hi - lo - len + 1) as f64 * r_pos) as u64;
        if r < faults.spike_share {
            let len = 1;
            if fits(len) {
                let at = pick(len);
                let [a, b] = faults.spike_counts;
                let value = a + r_val * (b - a);
                if let Some(s) = samples.get_mut(at as usize) {
                    let (lo_c, hi_c) = sensor.adc_range();
                    *s = (*s as f64 + value)
                        .round()
                        .max(lo_c as f64)
                        .min(hi_c as f64) as i16;
                }
                events.push(FaultEvent {
                    kind: FaultKind::Spike,
                    at_sample: at,
                    length: 1,
                    value,
                });
            }
        } else if r < faults.spike_share + faults.stuck_share {
            let len = faults.stuck_samples as u64;
            if fits(len) {
                let at = pick(len);
                let held = samples.get(at as usize).copied().unwrap_or(0);
                for s in samples.iter_mut().skip(at as usize).take(len as usize) {
                    *s = held;
                }
                events.push(FaultEvent {
                    kind: FaultKind::Stuck,
                    at_sample: at,
                    length: faults.stuck_samples,
                    value: held as f64,
                });
            }
        } else if r < faults.spike_share + faults.stuck_share + faults.drop_quiet_share {
            let len = faults.drop_samples as u64;
            if fits(len) {
                drops.push((pick(len), faults.drop_samples));
            }
        }
    }

    // 7. Remove the dropped samples.
    drops.sort_unstable();
    let mut kept = Vec::with_capacity(samples.len());
    let mut gaps = Vec::new();
    let mut next = 0u64;
    for (at, len) in drops {
        let at = at.max(next);
        if at >= timeline {
            break;
        }
        let end = (at + len as u64).min(timeline);
        kept.extend_from_slice(&samples[next as usize..at as usize]);
        gaps.push(Gap {
            position: kept.len(),
            at_sample: at,
            lost: (end - at) as u32,
        });
        next = end;
    }
    kept.extend_from_slice(&samples[next as usize..]);

    Ok(Stream {
        sample_rate_hz: fs,
        phase_s,
        class_names: scene.classes.iter().map(|c| c.name.clone()).collect(),
        samples: kept,
        timeline_samples: timeline,
        truth,
        gaps,
        events,
    })
}

/// Simulates one impact: `(pulse, time of peak after first contact in s, peak force in N,
/// force pulse duration in s)`.
fn simulate_pulse(
    scene: &SceneFile,
    d: &Draw,
    options: &StreamOptions,
    fine_step_s: f64,
) -> Result<(ForcePulse, f64, f64, f64), SimError> {
    let c = &scene.classes[d.class];
    let mut spec = ImpactSpec::new(
        c.material.material(),
        scene.plate.material(),
        d.radius_m,
        d.speed_m_s,
    );
    spec.law = scene.class_law(d.class)?;
    let step_s = (d.hertz.duration_s / options.record_points_per_pulse as f64).min(fine_step_s);
    spec.record = Some(step_s);
    let report = simulate(&spec)?;
    let force_n: Vec<f64> = report
        .force_series
        .unwrap_or_default()
        .into_iter()
        .map(|(_, f)| f)
        .collect();
    // Peak time: the largest recorded point, refined by a parabola through its neighbours.
    let (k, _) = force_n
        .iter()
        .enumerate()
        .fold((0, f64::NEG_INFINITY), |best, (i, &f)| {
            if f > best.1 { (i, f) } else { best }
        });
    let mut peak_tau = k as f64 * step_s;
    if let (Some(&a), Some(&b), Some(&c)) = (
        k.checked_sub(1).and_then(|j| force_n.get(j)),
        force_n.get(k),
        force_n.get(k + 1),
    ) {
        let curv = a - 2.0 * b + c;
        if curv < 0.0 {
            peak_tau += 0.5 * (a - c) / curv * step_s;
        }
    }
    let pulse = ForcePulse {
        start_s: d.start_s,
        duration_s: report.duration_s,
        scale: 1.0,
        shape: PulseShape::Series { step_s, force_n },
    };
    Ok((
        pulse,
        peak_tau,
        report.peak_force_n,
        report.pulse_duration_s,
    ))
}

// ---------------------------------------------------------------------------------------------
// Replay and matching
// ---------------------------------------------------------------------------------------------

/// Feeds a stream to a monitor: the stored samples in blocks (`Monitor::feed_slice`),
/// `Monitor::gap` at every recorded gap, `Monitor::finish` at the end. Returns every event.
pub fn replay_events<const N: usize, M: Backend, F: FlowSlot<M>>(
    stream: &Stream,
    monitor: &mut Monitor<N, M, F>,
) -> Vec<Event> {
    let mut out = Vec::new();
    let mut pos = 0usize;
    for g in &stream.gaps {
        let end = g.position.clamp(pos, stream.samples.len());
        monitor.feed_slice(&stream.samples[pos..end], |e| out.push(e));
        out.extend(monitor.gap(g.lost));
        pos = end;
    }
    monitor.feed_slice(&stream.samples[pos..], |e| out.push(e));
    out.extend(monitor.finish());
    out
}

/// [`replay_events`], keeping the pulse reports only.
pub fn replay<const N: usize, M: Backend>(
    stream: &Stream,
    monitor: &mut Monitor<N, M>,
) -> Vec<Report> {
    replay_events(stream, monitor)
        .into_iter()
        .filter_map(|e| match e {
            Event::Pulse(r) => Some(r),
            Event::Stuck { .. } | Event::Flow(_) => None,
        })
        .collect()
}

/// A report paired with a truth impact.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Pair {
    /// Index into the reports.
    pub report: usize,
    /// Index into the truth.
    pub truth: usize,
    /// `report.at_sample - truth.peak_sample` in samples.
    pub offset_samples: i64,
}

/// Reports paired with truth impacts.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Matching {
    /// Pairs, in report order.
    pub pairs: Vec<Pair>,
    /// Reports with no truth impact within the tolerance.
    pub unmatched_reports: Vec<usize>,
    /// Truth impacts no report was paired with.
    pub unmatched_truth: Vec<usize>,
}

/// Pairs each report with the truth impact nearest in peak time (`at_sample` against
/// `peak_sample`), one to one, nearest pairs first, at most `tolerance_samples` apart.
pub fn match_truth(reports: &[Report], truth: &[Truth], tolerance_samples: u64) -> Matching {
    let mut order: Vec<usize> = (0..truth.len()).collect();
    order.sort_by_key(|&i| truth[i].peak_sample);
    let mut candidates: Vec<(u64, usize, usize)> = Vec::new();
    for (r, rep) in reports.iter().enumerate() {
        let lo = rep.at_sample.saturating_sub(tolerance_samples);
        let start = order.partition_point(|&i| truth[i].peak_sample < lo);
        for &t in &order[start..] {
            let d = truth[t].peak_sample.abs_diff(rep.at_sample);
            if truth[t].peak_sample > rep.at_sample.saturating_add(tolerance_samples) {
                break;
            }
            candidates.push((d, r, t));
        }
    }
    candidates.sort_unstable();
    let mut report_used = vec![false; reports.len()];
    let mut truth_used = vec![false; truth.len()];
    let mut pairs = Vec::new();
    for (_, r, t) in candidates {
        if !report_used[r] && !truth_used[t] {
            report_used[r] = true;
            truth_used[t] = true;
            pairs.push(Pair {
                report: r,
                truth: t,
                offset_samples: reports[r].at_sample as i64 - truth[t].peak_sample as i64,
            });
        }
    }
    pairs.sort_by_key(|p| p.report);
    let unmatched = |used: &[bool]| {
        used.iter()
            .enumerate()
            .filter(|(_, u)| !**u)
            .map(|(i, _)| i)
            .collect()
    };
    Matching {
        pairs,
        unmatched_reports: unmatched(&report_used),
        unmatched_truth: unmatched(&truth_used),
    }
}

// ---------------------------------------------------------------------------------------------
// Files
// ---------------------------------------------------------------------------------------------

/// The two files of a stream: `<stem>.bin` (samples) and `<stem>.truth.csv` (truth). A path
/// ending in `.bin` names the same pair as the path without it.
pub fn stream_paths(out: &Path) -> (PathBuf, PathBuf) {
    let stem = if out.extension().is_some_and(|e| e == "bin") {
        out.with_extension("")
    } else {
        out.to_path_buf()
    };
    let with = |suffix: &str| {
        let mut s = stem.clone().into_os_string();
        s.push(suffix);
        PathBuf::from(s)
    };
    (with(".bin"), with(".truth.csv"))
}

/// One row of the truth file (see `FORMATS.md`).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
struct Row {
    kind: String,
    id: Option<u64>,
    sample: Option<u64>,
    position: Option<u64>,
    length: Option<u64>,
    value: Option<f64>,
    class: Option<usize>,
    class_name: Option<String>,
    radius_m: Option<f64>,
    speed_m_s: Option<f64>,
    time_s: Option<f64>,
    peak_time_s: Option<f64>,
    peak_force_n: Option<f64>,
    duration_s: Option<f64>,
    fault: Option<String>,
}

/// Writes `<stem>.bin` (little-endian `i16`) and `<stem>.truth.csv`; returns both paths.
pub fn write_stream(stream: &Stream, out: &Path) -> Result<(PathBuf, PathBuf), StreamError> {
    let (bin, csv_path) = stream_paths(out);
    let io = |path: &Path| {
        let path = path.to_path_buf();
        move |error| StreamError::Io { path, error }
    };
    if let Some(dir) = bin.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(io(dir))?;
    }
    let mut bytes = Vec::with_capacity(2 * stream.samples.len());
    for s in &stream.samples {
        bytes.extend_from_slice(&s.to_le_bytes());
    }
    std::fs::File::create(&bin)
        .and_then(|mut f| f.write_all(&bytes))
        .map_err(io(&bin))?;

    let fs = stream.sample_rate_hz;
    // Stored position of a time-line index, None when it was dropped or is past the end.
    let position = |at: u64| -> Option<u64> {
        if at >= stream.timeline_samples {
            return None;
        }
        let mut lost = 0u64;
        for g in &stream.gaps {
            if g.at_sample > at {
                break;
            }
            if at < g.at_sample.saturating_add(g.lost as u64) {
                return None;
            }
            lost += g.lost as u64;
        }
        Some(at - lost)
    };
    let mut rows: Vec<(u64, Row)> = Vec::new();
    for (i, t) in stream.truth.iter().enumerate() {
        rows.push((
            t.peak_sample,
            Row {
                kind: "impact".into(),
                id: Some(i as u64),
                sample: Some(t.peak_sample),
                position: position(t.peak_sample),
                length: Some((t.duration_s * fs).ceil() as u64),
                value: Some(t.scale),
                class: Some(t.class),
                class_name: stream.class_names.get(t.class).cloned(),
                radius_m: Some(t.radius_m),
                speed_m_s: Some(t.speed_m_s),
                time_s: Some(t.time_s),
                peak_time_s: Some(t.peak_time_s),
                peak_force_n: Some(t.peak_force_n),
                duration_s: Some(t.duration_s),
                fault: Some(t.fault.name().into()),
            },
        ));
    }
    for (i, g) in stream.gaps.iter().enumerate() {
        rows.push((
            g.at_sample,
            Row {
                kind: "gap".into(),
                id: Some(i as u64),
                sample: Some(g.at_sample),
                position: Some(g.position as u64),
                length: Some(g.lost as u64),
                ..Row::default()
            },
        ));
    }
    for (i, e) in stream.events.iter().enumerate() {
        rows.push((
            e.at_sample,
            Row {
                kind: match e.kind {
                    FaultKind::Spike => "spike".into(),
                    FaultKind::Stuck => "stuck".into(),
                },
                id: Some(i as u64),
                sample: Some(e.at_sample),
                position: position(e.at_sample),
                length: Some(e.length as u64),
                value: Some(e.value),
                ..Row::default()
            },
        ));
    }
    rows.sort_by_key(|(at, _)| *at);
    let header = Row {
        kind: "stream".into(),
        id: Some(0),
        sample: Some(stream.timeline_samples),
        position: Some(stream.samples.len() as u64),
        value: Some(stream.sample_rate_hz),
        time_s: Some(stream.phase_s),
        ..Row::default()
    };
    let classes: Vec<Row> = stream
        .class_names
        .iter()
        .enumerate()
        .map(|(i, name)| Row {
            kind: "class".into(),
            id: Some(i as u64),
            class: Some(i),
            class_name: Some(name.clone()),
            ..Row::default()
        })
        .collect();
    let mut w = csv::Writer::from_path(&csv_path).map_err(|e| csv_err(&csv_path, e))?;
    for row in std::iter::once(&header)
        .chain(classes.iter())
        .chain(rows.iter().map(|(_, r)| r))
    {
        w.serialize(row).map_err(|e| csv_err(&csv_path, e))?;
    }
    w.flush().map_err(io(&csv_path))?;
    Ok((bin, csv_path))
}

fn csv_err(path: &Path, e: csv::Error) -> StreamError {
    StreamError::Format {
        path: path.to_path_buf(),
        message: e.to_string(),
    }
}

/// Checks the samples read from `bin` against the truth file: as many as its `stream` row's
/// `position` (stored samples), which is the time line less the gaps' lost samples.
fn check_length(
    stream: &Stream,
    stored: Option<u64>,
    bin: &Path,
    csv_path: &Path,
) -> Result<(), StreamError> {
    let stored = stored.unwrap_or(0);
    let lost: u64 = stream.gaps.iter().map(|g| g.lost as u64).sum();
    if stream.timeline_samples.checked_sub(lost) != Some(stored) {
        return Err(StreamError::Format {
            path: csv_path.to_path_buf(),
            message: format!(
                "the stream row's position ({stored} stored samples) is not its sample \
                 ({} samples in the time line) less the gaps' {lost} lost samples",
                stream.timeline_samples
            ),
        });
    }
    let read = stream.samples.len() as u64;
    if read != stored {
        return Err(StreamError::Format {
            path: bin.to_path_buf(),
            message: format!(
                "holds {read} samples, but the truth file's stream row (position) says {stored}: \
                 the samples are {}",
                if read < stored {
                    "truncated"
                } else {
                    "longer than the stream (doubled or appended?)"
                }
            ),
        });
    }
    Ok(())
}

/// Reads a stream written by [`write_stream`] (`out` as given to it); the samples must be as
/// many as the truth file says (see `FORMATS.md`).
pub fn read_stream(out: &Path) -> Result<Stream, StreamError> {
    let (bin, csv_path) = stream_paths(out);
    let mut bytes = Vec::new();
    std::fs::File::open(&bin)
        .and_then(|mut f| f.read_to_end(&mut bytes))
        .map_err(|error| StreamError::Io {
            path: bin.clone(),
            error,
        })?;
    if bytes.len() % 2 != 0 {
        return Err(StreamError::Format {
            path: bin,
            message: "odd number of bytes: not a stream of i16 samples".into(),
        });
    }
    let samples: Vec<i16> = bytes
        .chunks_exact(2)
        .map(|c| i16::from_le_bytes([c[0], c[1]]))
        .collect();
    let bad = |message: String| StreamError::Format {
        path: csv_path.clone(),
        message,
    };
    let mut rd = csv::Reader::from_path(&csv_path).map_err(|e| csv_err(&csv_path, e))?;
    let mut stream = Stream {
        sample_rate_hz: f64::NAN,
        phase_s: 0.0,
        class_names: Vec::new(),
        samples,
        timeline_samples: 0,
        truth: Vec::new(),
        gaps: Vec::new(),
        events: Vec::new(),
    };
    let mut stored_samples = None;
    for (line, row) in rd.deserialize::<Row>().enumerate() {
        let row = row.map_err(|e| csv_err(&csv_path, e))?;
        let need = |name: &str, v: Option<f64>| {
            v.ok_or_else(|| bad(format!("row {}: {} row without {name}", line + 2, row.kind)))
        };
        let need_u = |name: &str, v: Option<u64>| need(name, v.map(|x| x as f64)).map(|x| x as u64);
        match row.kind.as_str() {
            "stream" => {
                stream.sample_rate_hz = need("value", row.value)?;
                stream.phase_s = need("time_s", row.time_s)?;
                stream.timeline_samples = need_u("sample", row.sample)?;
                stored_samples = Some(need_u("position", row.position)?);
            }
            "class" => {
                let class = need_u("class", row.class.map(|c| c as u64))? as usize;
                if class != stream.class_names.len() {
                    return Err(bad(format!("row {}: class rows out of order", line + 2)));
                }
                stream
                    .class_names
                    .push(row.class_name.clone().unwrap_or_default());
            }
            "impact" => {
                let class = need_u("class", row.class.map(|c| c as u64))? as usize;
                let fault = row.fault.as_deref().unwrap_or("none");
                stream.truth.push(Truth {
                    class,
                    radius_m: need("radius_m", row.radius_m)?,
                    speed_m_s: need("speed_m_s", row.speed_m_s)?,
                    time_s: need("time_s", row.time_s)?,
                    peak_time_s: need("peak_time_s", row.peak_time_s)?,
                    peak_sample: need_u("sample", row.sample)?,
                    peak_force_n: need("peak_force_n", row.peak_force_n)?,
                    duration_s: need("duration_s", row.duration_s)?,
                    scale: row.value.unwrap_or(1.0),
                    fault: ImpactFault::from_name(fault)
                        .ok_or_else(|| bad(format!("row {}: unknown fault {fault:?}", line + 2)))?,
                });
            }
            "gap" => stream.gaps.push(Gap {
                position: need_u("position", row.position)? as usize,
                at_sample: need_u("sample", row.sample)?,
                lost: need_u("length", row.length)?.min(u32::MAX as u64) as u32,
            }),
            "spike" | "stuck" => stream.events.push(FaultEvent {
                kind: if row.kind == "spike" {
                    FaultKind::Spike
                } else {
                    FaultKind::Stuck
                },
                at_sample: need_u("sample", row.sample)?,
                length: need_u("length", row.length)?.min(u32::MAX as u64) as u32,
                value: need("value", row.value)?,
            }),
            other => return Err(bad(format!("row {}: unknown kind {other:?}", line + 2))),
        }
    }
    if !stream.sample_rate_hz.is_finite() {
        return Err(bad("no stream row".into()));
    }
    check_length(&stream, stored_samples, &bin, &csv_path)?;
    // Truth rows are written by peak time; the stream keeps them by first contact.
    stream.truth.sort_by(|a, b| a.time_s.total_cmp(&b.time_s));
    stream.gaps.sort_by_key(|g| g.position);
    if stream
        .gaps
        .last()
        .is_some_and(|g| g.position > stream.samples.len())
    {
        return Err(bad("a gap lies past the end of the samples".into()));
    }
    Ok(stream)
}
