//! Streaming pulse detector: cuts impact pulses out of integer ADC samples and measures each
//! one's peak force and contact duration with the Hertz pulse shape.
//!
//! Memory is fixed and independent of the sample rate: a pulse is never stored, only summed.
//!
//! - Baseline: exponential moving average of quiet samples, time constant `baseline_tau_s`.
//!   A pulse's pre-trigger samples (its rising edge below the trigger) are taken out of it
//!   again when the pulse starts (`Detector::baseline_before`): kept, they would lift the
//!   baseline under the pulse and every later one, whose sums lose the lift times their
//!   length; a faint pulse's edge below the trigger is much of its area. Faint impacts that
//!   never trigger still lift it (`docs/random.md`, "Faint pulses").
//! - The measurement's second-order corrections (feature `second_order`: the baseline's
//!   above, the sum's and the vertex's below) are made on a rigid chain only. Behind a chain
//!   the pre-trigger samples hold the equaliser's own response to the pulse, which the chain
//!   residual's calibration counts in its sum, and the noise is coloured, where the vertex's
//!   variance is white noise's: with them, `mems_chain` known exactly stated its noise too
//!   narrow (root mean square of `z` 1.22-1.24 against 1.06-1.10) and Flores at e 0.3 behind
//!   it fell from -0.62 to -0.92 pp of the reference (`docs/damped-chain-table.sh`).
//! - Trigger: a sample above `baseline + max(trigger_sigmas * noise, 2)` counts starts a
//!   pulse, which takes along the [`PRE_TRIGGER`] samples before it; the pulse ends after
//!   `hold` samples below `baseline + max(release_sigmas * noise, 1)`.
//! - Duration from the area: the area of the Hertz pulse is the impulse `2 m u`, and with
//!   `t_c = 2.9432752 delta_max / u` and `F_max delta_max = (5/4) m u^2` that is
//!   `C_AREA F_max t_c` with `C_AREA = 1.6 / 2.9432752 = 0.543612`, so
//!   `t_c = area / (C_AREA F_max)`: unbiased by amplitude, unlike a threshold width. The
//!   sum's noise biases its logarithm by `-var / (2 S^2)`, which the sum adds back
//!   (`Detector::unbiased_sum`). For a
//!   contact whose pulse has another shape (a damped or a yielding one) this is the duration
//!   of the Hertz pulse with the same peak and area, which the contact's envelope or
//!   calibration states (for Thornton's yield, [`crate::thornton::YieldRatios::area_duration`]).
//! - Shape check: the pulse's energy `sum v^2 dt` is `C_ENERGY F_max^2 t_c` with
//!   `C_ENERGY = 2 B(8/5, 1/2) / (2.5 * 2.9432752) = 0.411342`, so `t_energy = energy /
//!   (C_ENERGY F_max^2)` must equal `t_area`; `q = t_energy / t_area` drops for two impacts
//!   within one contact and rises for a flat (clipped) top. `|ln q|` beyond
//!   `Settings::shape_tolerance` plus four noise sigmas rejects the pulse as `Misshapen`
//!   (`q` is divided by the scene's `ContactCalibration::shape_ratio` first).
//! - Skewness: the moments of the pulse's part above the trigger, weighted by `v^2`, give its
//!   skewness, 0 for the symmetric Hertz pulse (the contact's own for a damped law); two
//!   impacts within one contact with unequal peaks are skewed, and a skewness too far from
//!   the contact's is `Misshapen` too (see `Detector::symmetric_enough`). The weight `v^2`,
//!   not `v`, keeps a low tail out of it: the few per cent of the peak that an equaliser
//!   given its accelerometer's damping 30 % low leaves just after a pulse skewed it by 0.13
//!   under `v` and 0.02 under `v^2`, while two impacts 0.45-0.6 contact times apart with
//!   peaks 2 : 1 skew by 0.27-0.69 under `v^2` (0.23-0.37 under `v`).
//! - Spike on a pulse: the most negative second difference `v[i-1] - 2 v[i] + v[i+1]` of a
//!   Hertz pulse is about `-1.65 pi^2 F_max / n^2` at its peak (`n` samples per pulse); one
//!   below `-(2 * that + spike_fraction F_max + 8 noise)` (`Settings::spike_fraction`, 0.3)
//!   is a sample that jumped alone: `Spike`. A run of
//!   `max(3, n / 20)` (times `Settings::flat_top_ratio` for a contact with a broader top) or
//!   more consecutive samples equal to the pulse's largest one, on a sensor with at least one
//!   count of noise, is a clipped top: `Saturated`.
//! - Clipped at the ADC's full scale (on a rigid chain, or with the feature `pulse_shape`
//!   behind an accelerometer, and with `settle` too behind beam modes): the two samples
//!   before the first clipped one and the two after the last give `F_max` and `t_c` by the
//!   least-squares fit of the Hertz shape to them ([`flank_fit`],
//!   `Detector::measure_clipped`), or of a damped contact's own
//!   tabulated shape (`Settings::pulse_shape`, `crate::pulse_shape::shape_flank_fit`), with
//!   their sigmas from the fit. Behind an accelerometer the flank samples lie beyond the
//!   equaliser's delay either side of the clipped ones (its FIR read a clipped sample into
//!   those), and each carries the equaliser's own error at the pulse's length
//!   ([`crate::chain_residual::sample_error`]). Behind beam modes the run leaves the
//!   sections' state off the chain's, and that error rings under the samples after it: the
//!   pulse waits, its report deferred, for the re-estimation that follows it
//!   (`crate::settle_clip`), whose fit states the error and its variance at the two samples
//!   after the run and in the pulse's sum; the level at which the force clipped is the
//!   sample before the run plus the raw headroom it left over the modes' gain above their
//!   band (`1 + sum g_j`), less a slow part bounded by `sum g_j w_j^2` over the run; ringing
//!   seen before the pulse counts at every flank sample and, with one sign, in the sum. A
//!   pulse whose flanks are too short, whose contact's shape the scene does not carry, that
//!   the fit does not describe, or whose re-estimation is believed in none of its windows
//!   (another pulse inside each, or a sample at full scale first) stays `Saturated`. After
//!   the run behind beam modes no second impact is looked for (`PileUp`): the state error
//!   under the values and the modes' ringing in the raw samples both fall and rise like one.
//! - Drift: the oldest half of the pre-trigger samples must sit within half the trigger level
//!   of the baseline; otherwise the baseline lagged a DC drift and the pulse is `Drift`.
//! - A sample below the baseline moves it by at most the level a sample above it must pass to
//!   start a pulse (the trigger level and, behind a chain, [`RING_SIGMAS`] times the quiet
//!   RMS; times the weight), so a negative EMI spike cannot drag it down and ringing moves
//!   it both ways alike.
//! - Ringing seen before a pulse (behind a chain that is off) goes on through it: its
//!   variance, from the oldest half of the pre-trigger samples or, behind a chain, the quiet
//!   signal's mean square ([`RING_TRACK_SIGMAS`]), averaged over the chain's modes, and its
//!   covariance join the measurement's (`Detector::ring_noise`).
//! - Peak between samples ([`peak_fit`]): for a scene whose pulses have one shape (the Hertz
//!   law, or a restitution-parametrised damped law, whose difference from the Hertz shape
//!   its sampling correction measures with the same fit; not a yielding contact or one whose
//!   ratios a table bends) from 8 samples per pulse, the least-squares fit of
//!   the Hertz pulse's shape about its top to the five samples about the largest, in the
//!   peak, its time and its width (the largest of single noisy samples is biased high by
//!   the noise, +0.009 in `ln F_max` at 40 counts RMS; the fit's bias is second order, the
//!   vertex's, which is taken out ([`PeakFit::vertex_bias`]), and its noise about 30 %
//!   smaller); below, `z = F^(2/3) = F_max^(2/3) sin(pi t / t_c)` as a
//!   sinusoid of known frequency through the largest sample and its larger neighbour,
//!   `F_max` and `t_c` iterated three times. The fit reports its noise gain and what noise it
//!   shares with the area, and the noise model carries both. Behind a chain the equalised
//!   noise is coloured: the gains are then the fit's weights' quadratic form in the noise's
//!   correlations ([`crate::noise_colour`]), and the area's variance that of the sum of its
//!   correlated samples.
//! - A short damped pulse (feature `pulse_shape`; on a rigid chain, below
//!   [`crate::short_pulse::SHORT_SAMPLES`] samples as the fit through the top measures it):
//!   the contact's own tabulated shape fitted to the five samples about the largest
//!   ([`crate::short_pulse::short_shape_fit`]), its peak and duration the continuous pulse's
//!   (no sampling correction), its sigmas the fit's; where fewer than three samples see the
//!   pulse, or the fit does not hold, the fit through the top stands.
//! - Long pulses (a scene whose shortest pulse has 24 samples or more): the peak is the
//!   largest mean of `w` consecutive samples (`w` odd, up to an eighth of the shortest pulse,
//!   at most 15), corrected for the pulse's own curvature over the window ([`smooth_fit`]):
//!   the maximum of single noisy samples on a flat top is biased high by about the noise
//!   (+9 % in `F_max` at 1 MS/s with 150 counts of noise), the mean of `w` is not, and its
//!   noise is `sqrt(w)` smaller.

use crate::classifier::{Measurement, RejectReason};
use crate::equaliser::Pairs;
use crate::math::{Backend, DefaultBackend};
#[cfg(feature = "noise_colour")]
use crate::noise_colour::NoiseColour;
#[cfg(feature = "pulse_shape")]
use crate::pulse_shape::{PulseShape, shape_flank_fit};
use crate::pulse_window::hold_samples;
use crate::scene::{ContactCalibration, Scene};
#[cfg(feature = "pulse_shape")]
use crate::short_pulse::{SHORT_SAMPLES, short_shape_fit};

pub use crate::pulse_window::PRE_TRIGGER;

pub use crate::shape_fit::{
    C_AREA, C_ENERGY, FlankChain, FlankFit, Flanks, PEAK_OMEGA, PeakFit, flank_fit, peak_fit,
    shape_fit,
};

pub use crate::scene::MIN_DURATION_SAMPLES;

/// Behind a non-rigid chain, the quiet signal's mean square is tracked with this time
/// constant (s), and a sample starts a pulse only above [`RING_SIGMAS`] times its root as well:
/// what ringing the equaliser leaves (a chain known only to a few per cent) then neither
/// triggers nor ends pulses.
pub const RING_TAU_S: f32 = 1e-3;

/// See [`RING_TAU_S`]; the release level is held at `RING_SIGMAS / 2` times the same root.
pub const RING_SIGMAS: f32 = 4.0;

/// Behind a chain, the quiet mean square tracked over [`RING_TAU_S`] states the ringing before a
/// pulse (`Pulse::excess`) once it exceeds the noise's by this many standard deviations of the
/// tracker's own spread under white noise, `noise^2 sqrt(2 w / (2 - w))` for its weight `w`
/// per sample. The oldest half of the pre-trigger samples alone states only ringing above
/// `sqrt 2` noise RMS, where a slow offset far below it, summed over the pulse's samples, moves
/// its duration by several of its sigmas (behind `tail_beam`'s modes with drawn chains, errors
/// beyond three stated sigmas came several times as often as a normal law's).
pub const RING_TRACK_SIGMAS: f32 = 5.0;

/// The shape fit's own error of `ln F_max` at `n` samples per pulse, `FIT_FORCE n^-2.5`: the
/// worst over the sample's phase of noiseless Hertz pulses from 3 to 400 samples per pulse.
/// The detector's checks allow for it.
pub const FIT_FORCE: f32 = 0.15;

/// The shape fit's own error of `ln t_c`, `FIT_DURATION n^-2.5` (see [`FIT_FORCE`]).
pub const FIT_DURATION: f32 = 0.65;

/// The root mean square over the sample's phase of the shape fit's own error of `ln F_max`,
/// `FIT_FORCE_RMS n^-2.5`, over the same pulses as [`FIT_FORCE`]: what a measurement states as
/// the fit's standard deviation. The error goes with the phase (a uniform phase, no bias), so
/// its worst is about twice its RMS.
pub const FIT_FORCE_RMS: f32 = 0.075;

/// The same of `ln t_c`, `FIT_DURATION_RMS n^-2.5` (see [`FIT_FORCE_RMS`]).
pub const FIT_DURATION_RMS: f32 = 0.32;

/// The flank fit's own error of `ln F_max` and `ln t_c` (standard deviation) beside the
/// noise: its template, [`crate::shape_fit::peak_shape`], is within 1e-4 of the pulse's shape
/// out to [`crate::shape_fit::FLANK_REACH`].
pub const FLANK_FLOOR: f32 = 1e-4;

/// Longest box filter over the top of a pulse (samples).
pub const SMOOTH_MAX: usize = 16;

/// Consecutive samples equal to a pulse's largest sample that make a clipped (flat) top, at
/// least (and `n / 20` for a pulse of `n` samples).
pub const FLAT_TOP_SAMPLES: u16 = 3;

/// What the detector reports.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Detection {
    /// A pulse ended: its measurement, or why it cannot be measured.
    Pulse {
        /// Index (from 0, counting every sample fed) of the pulse's largest sample: of a
        /// pulse clipped at full scale, the first clipped one, or the one nearest the peak
        /// its flanks were measured to.
        at_sample: u64,
        /// The measured pulse or the reason it was rejected.
        outcome: Result<Measurement, RejectReason>,
    },
    /// The sensor output has not changed for `stuck_samples` samples although the scene says
    /// it is noisy: reported once per stuck run.
    Stuck {
        /// Index of the sample that completed the run.
        at_sample: u64,
    },
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
enum State {
    /// Waiting for a trigger.
    Idle,
    /// Inside a pulse.
    Active,
    /// After a pulse that ran too long (`true`: the baseline is tracked fast, a DC step or a
    /// stuck sensor may be the cause) or was cut by a gap (`false`: the baseline is frozen,
    /// the rest of the pulse must not move it): waiting for the signal to come back down.
    Recovering(bool),
    /// The first sample after a gap.
    Resumed,
    /// The first `PRE_TRIGGER` samples, whose mean sets the baseline.
    Unprimed,
}

/// What [`Pulse::track_clipping`] reads a raw sample against: the ADC's low and high ends
/// (counts) and the samples after the last clipped one that the equaliser's FIR took from it.
#[cfg(feature = "pulse_shape")]
type Clip = (i32, i32, u8);

/// A clipped pulse behind beam modes, waiting for the equaliser's state re-estimation to
/// state what the sections' state, left off by the run, put into its samples after it
/// ([`crate::settle_clip`]; features `pulse_shape` and `settle`). Indices are the
/// detector's sample indices.
#[cfg(all(feature = "pulse_shape", feature = "settle"))]
#[derive(Debug, Clone, Copy, PartialEq)]
struct PendingClip {
    /// The pulse as the flank fit reads it, before the correction.
    flanks: Flanks,
    /// The run's first sample.
    first: u64,
    /// The first sample past the run and the samples the FIR took from it.
    anchor: u64,
    /// The sample after the pulse's last.
    end: u64,
    /// What the pre-trigger samples carried beyond the noise (counts RMS, `Pulse::excess`):
    /// ringing that an earlier clipped impact left, slow against the pulse.
    excess: f32,
}

/// Running sums of the pulse being cut.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
struct Pulse {
    samples: u32,
    sum: f32,
    sum_sq: f32,
    prev: f32,
    min_curvature: f32,
    top: i32,
    run: u16,
    flat: u16,
    drift: bool,
    max: f32,
    max_at: u64,
    /// The two samples before the largest, oldest first.
    before_max: [f32; 2],
    /// The two samples after the largest, as far as they came (`after_count`).
    after_max: [f32; 2],
    after_count: u8,
    /// Samples at the ADC's full scale, and whether one sat at its low end.
    clipped: u16,
    low_clip: bool,
    /// The two samples after the last one at full scale and the `2 guard` after it (those
    /// the equaliser's FIR took from a clipped one), as far as they came
    /// (`after_clip_count - 2 guard`).
    after_clip: [f32; 2],
    after_clip_count: u8,
    /// The two samples before the first one at full scale, its index, and the sum of the
    /// samples from it to the `2 guard` after the last.
    #[cfg(feature = "pulse_shape")]
    before_clip: [f32; 2],
    #[cfg(feature = "pulse_shape")]
    clip_at: u64,
    #[cfg(feature = "pulse_shape")]
    run_sum: f32,
    /// The index of the last sample at full scale.
    #[cfg(feature = "pulse_shape")]
    last_clip_at: u64,
    /// The last raw sample, and the one before the first at full scale.
    #[cfg(feature = "pulse_shape")]
    raw_last: i32,
    #[cfg(feature = "pulse_shape")]
    raw_before_clip: i32,
    last: f32,
    valley: f32,
    above_trigger: u32,
    moments: [f32; 4],
    below_release: u16,
    pileup: bool,
    saturated: bool,
    after_gap: bool,
    ring: [f32; SMOOTH_MAX],
    ring_at: usize,
    ring_len: usize,
    ring_sum: f32,
    top_smooth: f32,
    /// RMS in counts of what the oldest half of the pre-trigger samples carry beyond the noise
    /// (ringing the equaliser left, with a chain that is off from the truth), 0 when they
    /// are within `sqrt(3)` noise RMS.
    excess: f32,
    /// The trigger and release levels in force for this pulse (counts).
    trigger: f32,
    release: f32,
}

impl Pulse {
    const EMPTY: Pulse = Pulse {
        samples: 0,
        sum: 0.0,
        sum_sq: 0.0,
        prev: 0.0,
        min_curvature: 0.0,
        top: i32::MIN,
        run: 0,
        flat: 0,
        drift: false,
        max: f32::NEG_INFINITY,
        max_at: 0,
        before_max: [0.0; 2],
        after_max: [0.0; 2],
        after_count: 0,
        clipped: 0,
        low_clip: false,
        after_clip: [0.0; 2],
        after_clip_count: 0,
        #[cfg(feature = "pulse_shape")]
        before_clip: [0.0; 2],
        #[cfg(feature = "pulse_shape")]
        clip_at: 0,
        #[cfg(feature = "pulse_shape")]
        run_sum: 0.0,
        #[cfg(feature = "pulse_shape")]
        last_clip_at: 0,
        #[cfg(feature = "pulse_shape")]
        raw_last: 0,
        #[cfg(feature = "pulse_shape")]
        raw_before_clip: 0,
        last: 0.0,
        valley: 0.0,
        above_trigger: 0,
        moments: [0.0; 4],
        below_release: 0,
        pileup: false,
        saturated: false,
        after_gap: false,
        ring: [0.0; SMOOTH_MAX],
        ring_at: 0,
        ring_len: 0,
        ring_sum: 0.0,
        top_smooth: f32::NEG_INFINITY,
        excess: 0.0,
        trigger: 0.0,
        release: 0.0,
    };

    /// Adds `v` to the running mean of the last `w` samples and keeps the largest mean
    /// (`w <= 1`: nothing to do).
    #[inline]
    fn smooth(&mut self, v: f32, w: usize) {
        if w <= 1 {
            return;
        }
        if self.ring_len >= w {
            let old = self.ring_at.wrapping_sub(w) & (SMOOTH_MAX - 1);
            self.ring_sum -= self.ring.get(old).copied().unwrap_or(0.0);
        } else {
            self.ring_len += 1;
        }
        if let Some(slot) = self.ring.get_mut(self.ring_at & (SMOOTH_MAX - 1)) {
            *slot = v;
        }
        self.ring_at = self.ring_at.wrapping_add(1);
        self.ring_sum += v;
        if self.ring_len >= w {
            self.top_smooth = self.top_smooth.max(self.ring_sum / w as f32);
        }
    }

    /// Counts raw samples at the ADC's full scale (`adc_max`) and at its low end (`adc_min`),
    /// and keeps the first two values `v` after the last one at full scale.
    #[cfg(not(feature = "pulse_shape"))]
    #[inline(always)]
    fn track_clipping(&mut self, sample: i32, v: f32, adc_min: i32, adc_max: i32) {
        if sample >= adc_max {
            self.saturated = true;
            self.clipped = self.clipped.saturating_add(1);
            self.after_clip_count = 0;
        } else if sample <= adc_min {
            self.saturated = true;
            self.low_clip = true;
        } else if let Some(slot) = self.after_clip.get_mut(self.after_clip_count as usize) {
            *slot = v;
            self.after_clip_count += 1;
        }
    }

    /// Counts raw samples at the ADC's full scale (`adc_max`) and at its low end (`adc_min`);
    /// keeps the two values `v` before the first at full scale (`v` of sample `index`, `older`
    /// and `prev` before it), and the first two values after the last at full scale and the
    /// `guard2` after it that an equaliser's FIR took from it; sums the values in between.
    #[cfg(feature = "pulse_shape")]
    #[inline(always)]
    fn track_clipping(&mut self, sample: i32, v: f32, older: f32, index: u64, clip: Clip) {
        let (adc_min, adc_max, guard2) = clip;
        if sample >= adc_max {
            if self.clipped == 0 {
                (self.before_clip, self.clip_at) = ([older, self.prev], index);
                self.raw_before_clip = self.raw_last;
            }
            self.saturated = true;
            self.clipped = self.clipped.saturating_add(1);
            self.after_clip_count = 0;
            self.run_sum += v;
            self.last_clip_at = index;
        } else if sample <= adc_min {
            self.saturated = true;
            self.low_clip = true;
        } else if self.clipped > 0 {
            let count = self.after_clip_count;
            match count.checked_sub(guard2) {
                None => self.run_sum += v,
                Some(k) => {
                    if let Some(slot) = self.after_clip.get_mut(k as usize) {
                        *slot = v;
                    }
                }
            }
            self.after_clip_count = count.saturating_add(1);
        }
        self.raw_last = sample;
    }

    /// Runs at the largest raw sample (a clipped top is flat in what the ADC gave): the
    /// current run and the longest.
    #[inline(always)]
    fn track_top(&mut self, sample: i32) {
        if sample > self.top {
            self.top = sample;
            self.run = 1;
            self.flat = 1;
        } else if sample == self.top {
            self.run = self.run.saturating_add(1);
            self.flat = self.flat.max(self.run);
        } else {
            self.run = 0;
        }
    }

    /// Moments `sum v^2 t^k` (`k = 0..3`) of the part above the trigger, in samples `t` since
    /// the pulse's start.
    #[inline(always)]
    fn track_moments(&mut self, v: f32) {
        if v > self.trigger {
            self.above_trigger = self.above_trigger.saturating_add(1);
            let t = self.samples as f32;
            let [m0, m1, m2, m3] = &mut self.moments;
            let w = v * v;
            *m0 += w;
            *m1 += w * t;
            *m2 += w * t * t;
            *m3 += w * t * t * t;
        }
    }

    /// The largest value `v` with its index and neighbours (`older`, `last` before it, two
    /// after it), the valley since, and (when `second` is set) a second impact: a rise from
    /// a deep valley after an earlier peak ([`second_peak`]).
    #[inline(always)]
    fn track_max(&mut self, v: f32, older: f32, index: u64, noise: f32, second: bool) {
        if v > self.max {
            if second
                && self.max > 0.0
                && second_peak(self.max, self.valley, v, self.trigger, noise)
            {
                self.pileup = true;
            }
            self.max = v;
            self.max_at = index;
            self.before_max = [older, self.last];
            self.after_count = 0;
            self.valley = v;
        } else {
            if let Some(slot) = self.after_max.get_mut(self.after_count as usize) {
                *slot = v;
                self.after_count += 1;
            }
            if v < self.valley {
                self.valley = v;
            } else if second && second_peak(self.max, self.valley, v, self.trigger, noise) {
                self.pileup = true;
            }
        }
    }
}

/// What ringing before a pulse leaves in its measurement ([`Detector::ring_noise`]): the
/// variances of `ln F_max` and `ln sum` and their covariance.
#[derive(Debug, Clone, Copy, Default)]
struct RingNoise {
    force2: f32,
    sum2: f32,
    shared: f32,
}

impl RingNoise {
    /// The variance of `ln t_c = ln sum - ln F_max`.
    fn duration2(&self) -> f32 {
        self.sum2 + self.force2 - 2.0 * self.shared
    }
}

/// What a pulse's pre-trigger samples hold against the baseline
/// (`Detector::pre_trigger_window`).
struct PreTrigger {
    /// Sum of the oldest half's values less the baseline (counts).
    old_sum: f32,
    /// Sum of their steps into the baseline (counts).
    #[cfg(feature = "second_order")]
    steps: f32,
    /// How many of the steps were not clamped.
    #[cfg(feature = "second_order")]
    free: f32,
}

/// The noise model of one measured pulse (natural-log units, per [`Detector::sigmas`]).
struct Sigmas {
    /// Standard deviation of `ln F_max`.
    ln_force: f32,
    /// Standard deviation of `ln t_c`.
    ln_duration: f32,
    /// Covariance of `ln sum` and `ln F_max`: the noise's, `noise^2 weight_sum / (sum F_max)`,
    /// and the ringing's ([`RingNoise`]).
    shared: f32,
    /// Standard deviation of `ln sum` from the noise.
    area: f32,
    /// The fit's own error of `ln F_max`, `FIT_FORCE n^-2.5`.
    fit_force: f32,
    /// The fit's own error of `ln t_c`, `FIT_DURATION n^-2.5`.
    fit_duration: f32,
    /// The shape check's allowance for the ringing before the pulse (a variance of `ln q`).
    ring2: f32,
}

/// The streaming detector, with math backend `M` for the per-pulse fit. Build it from a
/// scene with [`Detector::new`].
#[derive(Debug, Clone)]
pub struct Detector<M: Backend = DefaultBackend> {
    trigger: f32,
    release: f32,
    noise: f32,
    shape_tolerance: f32,
    skew_tolerance: f32,
    skewness: f32,
    smooth: usize,
    shape_ratio: f32,
    /// `Settings::flat_top_ratio` (feature `plasticity`).
    #[cfg(feature = "plasticity")]
    flat_top_ratio: f32,
    spike_fraction: f32,
    /// The contact is the undamped Hertz law (no calibration): a clipped pulse is read from
    /// its flanks by the Hertz series, and a short pulse is read through its top, not by the
    /// contact's tabulated shape ([`Detector::short_measurement`], which the Hertz shape of
    /// the top already is).
    hertz: bool,
    /// Every pulse of the scene has one shape ([`one_shape`]): its top is read with the Hertz
    /// shape through five samples ([`peak_fit`]'s `five`).
    five: bool,
    /// The scene carries a sampling correction ([`crate::Settings::corrects_sampling`]) whose
    /// spread states the fit's error at few samples per pulse: a measurement then
    /// states its sigmas without the fit's generic bound ([`Detector::stated_sigmas`]).
    sampling_calibrated: bool,
    /// The contact's own pulse shape, from which a clipped pulse is measured: the Hertz
    /// pulse's ([`PulseShape::hertz`]) for an undamped contact, else `Settings::pulse_shape`;
    /// none behind a chain that is not rigid ([`clip_shape`]; feature `pulse_shape`).
    #[cfg(feature = "pulse_shape")]
    pulse_shape: PulseShape,
    hold: u16,
    max_samples: u32,
    alpha: f32,
    stuck_limit: u16,
    /// At least one count of noise at the ADC: identical raw samples are then a sign of a
    /// stuck or clipped sensor.
    adc_noisy: bool,
    /// Weight per sample of the quiet signal's mean square (0: not tracked, a rigid chain).
    ring_weight: f32,
    /// `1 - ring_weight`, the decay per sample of `ring_sum`.
    ring_decay: f32,
    /// The chain's beam modes in radians per sample, `2 pi f / fs` (the first `ring_modes`):
    /// where ringing before a pulse is ([`Detector::ring_noise`]).
    ring_omegas: [f32; crate::equaliser::MAX_MODES],
    ring_modes: u8,
    /// The quiet signal's mean square about the baseline over `ring_weight / ring_decay`
    /// (counts^2): `S <- (S + v^2) (1 - w)` (see [`ring_sum_step`]).
    ring_sum: f32,
    adc_min: i32,
    adc_max: i32,
    /// Twice the equaliser's delay behind a chain of an accelerometer alone (the samples
    /// either side of a clipped run that its FIR takes from a clipped one), else 0.
    #[cfg(feature = "pulse_shape")]
    guard2: u8,
    /// How far the raw samples lag the force behind the accelerometer (samples,
    /// `FlankChain::lag`).
    #[cfg(feature = "pulse_shape")]
    clip_lag: f32,
    /// The equaliser's error per sample over the peak at [`clip_error_n`]`(k)` samples per
    /// pulse, in the body and at the ends ([`crate::chain_residual::sample_error`]), and the
    /// raw samples' ([`crate::chain_residual::raw_error`]); zeros on a rigid chain.
    #[cfg(feature = "pulse_shape")]
    clip_errors: [[f32; CLIP_ERROR_POINTS]; 3],
    /// Behind beam modes, their gain above their band, `1 + sum_j g_j`, and how fast the
    /// raw top may part from that times the force, `sum_j g_j w_j^2 / (1 + sum_j g_j)`
    /// (`w_j` in radians per sample).
    #[cfg(all(feature = "pulse_shape", feature = "settle"))]
    mode_gain: f32,
    #[cfg(all(feature = "pulse_shape", feature = "settle"))]
    mode_slow: f32,
    /// A clipped pulse waiting for the re-estimation after it.
    #[cfg(all(feature = "pulse_shape", feature = "settle"))]
    pending: Option<PendingClip>,
    /// The equalised noise's correlation between samples (`None`: white, behind a rigid
    /// chain).
    #[cfg(feature = "noise_colour")]
    colour: Option<NoiseColour>,
    dt_s: f32,
    force_per_count_n: f32,
    baseline: f32,
    previous: i32,
    same_run: u16,
    pre: [f32; PRE_TRIGGER],
    pre_next: usize,
    pre_start: usize,
    state: State,
    stuck_runs: u32,
    pulse: Pulse,
    next_index: u64,
    backend: M,
}

impl<M: Backend> Detector<M> {
    /// A detector for the scene's sensor chain and settings.
    ///
    /// `hold = max(hold_samples, 0.05 t_c,min fs)`; a pulse longer than
    /// `3 t_c,max fs + PRE_TRIGGER + hold` samples is rejected as `TooLong`; the baseline
    /// weight per sample is `alpha = 1 - exp(-1 / (tau fs))`.
    pub fn new<const N: usize>(scene: &Scene<N, M>) -> Self {
        let sensor = scene.sensor();
        let s = scene.settings();
        let fs = sensor.sample_rate_hz;
        let (short, long) = scene.duration_bounds_s();
        let hold = hold_samples(s.hold_samples, short, fs);
        let max_samples =
            (3.0 * long * fs + PRE_TRIGGER as f32 + hold as f32).min(u32::MAX as f32 / 2.0) as u32;
        // The equaliser colours and scales the ADC's white noise by its noise gain.
        let noise = sensor.noise_rms_counts * scene.equaliser().noise_gain();
        let adc_noisy = sensor.noise_rms_counts >= 1.0;
        let rigid = scene.equaliser().is_identity();
        let (ring_weight, ring_decay) = Self::ring_weights(rigid, fs);
        let hertz = s.contact == ContactCalibration::HERTZ && plain_top(s);
        let five = one_shape(scene);
        #[cfg(feature = "pulse_shape")]
        let clip_lag = sensor.dynamics.accelerometer().map_or(0.0, |a| {
            a.damping_ratio * fs / (core::f32::consts::PI * a.frequency_hz)
        });
        let modes = sensor.dynamics.modes();
        #[cfg(feature = "pulse_shape")]
        let pulse_shape = clip_shape(s, modes.is_empty() || cfg!(feature = "settle"));
        let mut ring_omegas = [0.0; crate::equaliser::MAX_MODES];
        for (w, mode) in ring_omegas.iter_mut().zip(modes) {
            *w = core::f32::consts::TAU * mode.frequency_hz / fs;
        }
        #[cfg(all(feature = "pulse_shape", feature = "settle"))]
        let mode_gain = 1.0 + modes.iter().map(|m| m.gain).sum::<f32>();
        Self {
            trigger: (s.trigger_sigmas * noise).max(2.0),
            release: (s.release_sigmas * noise).max(1.0),
            noise,
            shape_tolerance: s.shape_tolerance,
            skew_tolerance: s.skew_tolerance,
            skewness: s.contact.skewness,
            smooth: smooth_width(short * fs),
            shape_ratio: s.contact.shape_ratio,
            #[cfg(feature = "plasticity")]
            flat_top_ratio: s.flat_top_ratio,
            spike_fraction: s.spike_fraction,
            hertz,
            five,
            sampling_calibrated: s.corrects_sampling(),
            #[cfg(feature = "pulse_shape")]
            clip_errors: clip_errors(scene, clip_lag, pulse_shape.is_some()),
            #[cfg(feature = "pulse_shape")]
            pulse_shape,
            hold,
            max_samples,
            alpha: 1.0 - M::exp(-1.0 / (s.baseline_tau_s * fs)),
            stuck_limit: if adc_noisy { s.stuck_samples } else { 0 },
            adc_noisy,
            ring_weight,
            ring_decay,
            ring_omegas,
            ring_modes: modes.len() as u8,
            ring_sum: 0.0,
            adc_min: sensor.adc_min,
            adc_max: sensor.adc_max,
            #[cfg(feature = "pulse_shape")]
            guard2: (2 * scene.equaliser().delay_samples()).min(8) as u8,
            #[cfg(feature = "pulse_shape")]
            clip_lag,
            #[cfg(all(feature = "pulse_shape", feature = "settle"))]
            mode_gain,
            #[cfg(all(feature = "pulse_shape", feature = "settle"))]
            mode_slow: modes
                .iter()
                .zip(&ring_omegas)
                .map(|(m, w)| m.gain * w * w)
                .sum::<f32>()
                / mode_gain,
            #[cfg(all(feature = "pulse_shape", feature = "settle"))]
            pending: None,
            #[cfg(feature = "noise_colour")]
            colour: (!scene.equaliser().is_identity()).then(|| *scene.equaliser().noise_colour()),
            dt_s: 1.0 / fs,
            force_per_count_n: sensor.force_per_count_n,
            baseline: 0.0,
            previous: 0,
            same_run: 0,
            pre: [0.0; PRE_TRIGGER],
            pre_next: 0,
            pre_start: 0,
            state: State::Unprimed,
            stuck_runs: 0,
            pulse: Pulse::EMPTY,
            next_index: 0,
            backend: M::default(),
        }
    }

    /// The quiet mean square's weight per sample and decay, `(1 - d, d)` with
    /// `d = exp(-1 / (RING_TAU_S fs))` for `fs` in Hz; `(0, 0)` (not tracked) behind a rigid
    /// chain (`identity`).
    fn ring_weights(identity: bool, fs: f32) -> (f32, f32) {
        if identity {
            (0.0, 0.0)
        } else {
            let decay = M::exp(-1.0 / (RING_TAU_S * fs));
            (1.0 - decay, decay)
        }
    }

    /// The math backend.
    pub fn backend(&self) -> M {
        self.backend
    }

    /// Number of samples fed so far.
    pub fn samples_fed(&self) -> u64 {
        self.next_index
    }

    /// The current baseline estimate in counts.
    pub fn baseline(&self) -> f32 {
        self.baseline
    }

    /// `true` while a pulse is being cut.
    pub fn in_pulse(&self) -> bool {
        self.state == State::Active
    }

    /// Feeds one sample; returns a detection when a pulse ends or the sensor is found stuck.
    ///
    /// `O(1)` work and memory per sample.
    #[inline(always)]
    pub fn feed(&mut self, sample: i32) -> Option<Detection> {
        self.feed_value(sample, sample as f32)
    }

    /// Feeds one sample as the ADC gave it (`raw`: saturation and stuck runs are seen there)
    /// and as the equaliser reconstructed it (`value`, counts of the rigid plate: everything
    /// else is measured on it). [`Detector::feed`] is `feed_value(s, s as f32)`.
    #[inline(always)]
    pub fn feed_value(&mut self, sample: i32, value: f32) -> Option<Detection> {
        // A clipped pulse still waiting when the detector is fed again: the re-estimation
        // never ran (a sample at full scale came first, which cannot also end a pulse).
        #[cfg(all(feature = "pulse_shape", feature = "settle"))]
        if self.pending.is_some() {
            let waited = self.resolve_clip(None);
            return waited.or(self.feed_now(sample, value));
        }
        self.feed_now(sample, value)
    }

    /// [`Detector::feed_value`] with no clipped pulse waiting.
    #[inline(always)]
    fn feed_now(&mut self, sample: i32, value: f32) -> Option<Detection> {
        let index = self.next_index;
        self.next_index = index.wrapping_add(1);
        let stuck = if sample == self.previous {
            self.same_again(index)
        } else {
            self.previous = sample;
            self.same_run = 0;
            None
        };
        match self.state {
            State::Idle => {
                let v = value - self.baseline;
                if (v > self.trigger && self.above_ringing(v)) || sample >= self.adc_max {
                    return self.trigger(sample, value, index, false).or(stuck);
                }
                // A sample far below the baseline moves it by at most the level a sample above
                // it must pass to start a pulse (measured before this sample joins the ringing).
                let step = self.baseline_step(v);
                self.track_ringing(v);
                self.baseline += step * self.alpha;
                // Ring of the last PRE_TRIGGER samples (a power of two: the mask keeps the
                // index in bounds, so the check compiles away).
                if let Some(slot) = self.pre.get_mut(self.pre_next & (PRE_TRIGGER - 1)) {
                    *slot = value;
                }
                self.pre_next = self.pre_next.wrapping_add(1);
                stuck
            }
            State::Active => self.active(sample, value, index).or(stuck),
            State::Recovering(track) => {
                self.recover(value, track);
                stuck
            }
            State::Resumed => self.resume(sample, value, index).or(stuck),
            State::Unprimed => {
                self.prime(value);
                None
            }
        }
    }

    /// Feeds quiet samples from the front of `samples` for as long as nothing happens: stops
    /// before the first sample that would trigger a pulse, complete a stuck run, or when the
    /// detector is not idle. Returns how many samples it consumed; the state afterwards is
    /// exactly what [`Detector::feed`] on each of them would leave. The tight loop behind
    /// [`crate::Monitor::feed_slice`].
    #[inline]
    pub fn feed_quiet<S: Copy + Into<i32>>(&mut self, samples: &[S]) -> usize {
        self.feed_quiet_values(samples.iter().map(|&s| {
            let x: i32 = s.into();
            (x, x as f32)
        }))
    }

    /// [`Detector::feed_quiet`] for samples given as `(raw, value)` pairs (see
    /// [`Detector::feed_value`]): the loop behind an equalised [`crate::Monitor::feed_slice`].
    /// The pair that stops the loop is taken from the iterator but not fed: the caller goes on
    /// from the returned count in its own slices.
    #[inline(always)]
    pub fn feed_quiet_values(&mut self, samples: impl Iterator<Item = (i32, f32)>) -> usize {
        if self.ring_weight > 0.0 {
            self.quiet_loop::<true>(samples)
        } else {
            self.quiet_loop::<false>(samples)
        }
    }

    /// The quiet loop, tracking the quiet mean square (`RING`) or not.
    #[inline(always)]
    fn quiet_loop<const RING: bool>(&mut self, samples: impl Iterator<Item = (i32, f32)>) -> usize {
        if self.state != State::Idle {
            return 0;
        }
        let (decay, k2) = (self.ring_decay, RING_SIGMAS * RING_SIGMAS);
        let weighted_k2 = k2 * self.ring_scale();
        let mut ms = self.ring_sum;
        let (trigger, alpha, adc_max) = (self.trigger, self.alpha, self.adc_max);
        let floor = -trigger;
        // Stop before the repeat that completes a stuck run: `feed` reports it.
        let limit = self.stuck_limit.wrapping_sub(1);
        let (mut baseline, mut previous, mut run, mut next) =
            (self.baseline, self.previous, self.same_run, self.pre_next);
        let mut n = 0usize;
        for (x, value) in samples {
            let v = value - baseline;
            if (v > trigger && (!RING || v * v > weighted_k2 * ms)) || x >= adc_max {
                break;
            }
            if x == previous {
                if run >= limit {
                    break;
                }
                run += 1;
            } else {
                previous = x;
                run = 0;
            }
            // Behind a rigid chain the level is the trigger's alone: one select.
            let step = if RING {
                clamp_low::<M>(v, trigger, || weighted_k2 * ms)
            } else if v < floor {
                floor
            } else {
                v
            };
            if RING {
                ms = ring_sum_step(ms, decay, v);
            }
            baseline += step * alpha;
            if let Some(slot) = self.pre.get_mut(next & (PRE_TRIGGER - 1)) {
                *slot = value;
            }
            next = next.wrapping_add(1);
            n += 1;
        }
        self.keep_quiet(baseline, ms, (previous, run), next, n);
        n
    }

    /// `true` while waiting for a trigger: [`Detector::feed_quiet_pairs`] has work to do.
    pub fn is_idle(&self) -> bool {
        self.state == State::Idle
    }

    /// The quiet loop behind an equaliser ([`crate::Monitor::feed_slice`] behind a chain):
    /// feeds the equalised samples of `pairs` while nothing happens, straight into the
    /// pre-trigger ring (in runs up to its end, so that each is stored without a wrap test).
    /// Returns how many it fed and the `(raw, value)` that stopped it, taken from `pairs` but
    /// not fed (`None` when `pairs` ran out or the detector is not idle): the caller feeds
    /// that one with [`Detector::feed_value`]. The state afterwards is exactly what
    /// `feed_value` on each fed pair would leave.
    ///
    /// The loop takes only what needs no decision: `|value - baseline|` within the trigger
    /// level (so that the baseline moves by the whole step), below full scale, and not the
    /// repeat that completes a stuck run; any other sample goes to `feed_value`.
    #[inline(always)]
    pub fn feed_quiet_pairs(&mut self, pairs: &mut impl Pairs) -> (usize, Option<(i32, f32)>) {
        if self.state != State::Idle {
            return (0, None);
        }
        let (trigger, alpha, adc_max, decay) =
            (self.trigger, self.alpha, self.adc_max, self.ring_decay);
        // A repeat of the previous raw sample may take `same_run` up to `limit`, never to
        // the `stuck_limit` that completes a stuck run (that one goes to `feed_value`).
        let limit = self.stuck_limit.wrapping_sub(1);
        let (mut baseline, mut ms, mut previous, mut run) =
            (self.baseline, self.ring_sum, self.previous, self.same_run);
        let start = self.pre_next;
        let mut next = start;
        let stop = loop {
            let ring = self
                .pre
                .get_mut(next & (PRE_TRIGGER - 1)..)
                .unwrap_or(&mut []);
            // Few enough samples that no run of repeats among them reaches `limit`: the loop
            // needs no stuck test, the repeats are counted once the samples are fed.
            let room = ring.len().min(limit.saturating_sub(run) as usize);
            let ring = ring.get_mut(..room).unwrap_or(&mut []);
            let fed = pairs.each(ring, adc_max, |slot, _, value| {
                let v = value - baseline;
                // Within the trigger level either way (false for NaN).
                let within = v.abs() <= trigger;
                if !within {
                    return false;
                }
                ms = ring_sum_step(ms, decay, v);
                baseline += v * alpha;
                *slot = value;
                true
            });
            next = next.wrapping_add(fed.count);
            if let Some((first, last)) = fed.ends {
                // `room` bounds the sum: no overflow past `limit`.
                run = if fed.repeats + 1 < fed.count || first != previous {
                    fed.repeats as u16
                } else {
                    run + fed.count as u16
                };
                previous = last;
            }
            if fed.stop.is_some() || fed.count < room || room == 0 {
                break fed.stop;
            }
        };
        let n = next.wrapping_sub(start);
        self.keep_quiet(baseline, ms, (previous, run), next, n);
        (n, stop)
    }

    /// What a quiet loop leaves after feeding `n` samples: the baseline, the ring's scaled mean
    /// square, the last raw sample and its repeats, the pre-trigger ring's next slot.
    #[inline(always)]
    fn keep_quiet(
        &mut self,
        baseline: f32,
        ring_sum: f32,
        (previous, run): (i32, u16),
        pre_next: usize,
        n: usize,
    ) {
        self.baseline = baseline;
        self.ring_sum = ring_sum;
        self.previous = previous;
        self.same_run = run;
        self.pre_next = pre_next;
        self.next_index = self.next_index.wrapping_add(n as u64);
    }

    /// Tells the detector that `lost` samples were dropped (e.g. a FIFO overrun). A pulse in
    /// progress is rejected as `Gap` and the rest of it is skipped; a pulse already under way
    /// when the stream resumes (the first sample is above the trigger) is rejected as `Gap`
    /// when it ends. The sample index advances by `lost`.
    pub fn gap(&mut self, lost: u32) -> Option<Detection> {
        self.next_index = self.next_index.wrapping_add(lost as u64);
        self.pre_start = self.pre_next;
        match self.state {
            State::Active => {
                self.state = State::Recovering(false);
                self.pulse.below_release = 0;
                Some(self.reject(RejectReason::Gap))
            }
            State::Idle => {
                self.state = State::Resumed;
                self.unsettled_clip()
            }
            State::Recovering(_) | State::Resumed | State::Unprimed => None,
        }
    }

    /// Tells the idle detector that the `n` samples after the last one it was fed went to the
    /// equaliser's re-estimation ([`crate::settle`]), not to it: the sample index advances by
    /// `n`, the last of them (`last_raw`) is the one the next is compared with for a stuck run,
    /// and the pre-trigger samples start afresh. The quiet mean square behind a chain is kept:
    /// it decays from what it tracked before within a few of its time constants
    /// ([`RING_TAU_S`]), and a chain given off leaves ringing that the re-estimation does not
    /// remove (set to the window's residual, it let more of that ringing start spurious
    /// pulses: `docs/chain.md`).
    pub(crate) fn skip_settled(&mut self, n: u32, last_raw: Option<i32>) {
        self.next_index = self.next_index.wrapping_add(n as u64);
        self.pre_start = self.pre_next;
        if let Some(raw) = last_raw {
            self.previous = raw;
            self.same_run = 0;
        }
    }

    /// RMS of the equalised noise (counts): the sensor's noise times the equaliser's noise
    /// gain.
    pub fn noise(&self) -> f32 {
        self.noise
    }

    /// Ends the stream: a pulse in progress is rejected as `Truncated`.
    pub fn finish(&mut self) -> Option<Detection> {
        match self.state {
            State::Active => {
                self.state = State::Idle;
                self.pre_start = self.pre_next;
                Some(self.reject(RejectReason::Truncated))
            }
            _ => self.unsettled_clip(),
        }
    }

    /// Runs of identical samples counted as stuck so far.
    pub fn stuck_runs(&self) -> u32 {
        self.stuck_runs
    }

    /// The sample repeats the previous one: a stuck run completes at `stuck_limit` repeats.
    #[cold]
    #[inline(never)]
    fn same_again(&mut self, index: u64) -> Option<Detection> {
        self.same_run = self.same_run.saturating_add(1);
        if self.stuck_limit != 0 && self.same_run == self.stuck_limit {
            self.stuck_runs = self.stuck_runs.saturating_add(1);
            return Some(Detection::Stuck { at_sample: index });
        }
        None
    }

    /// The first [`PRE_TRIGGER`] samples set the baseline to their mean (an impact inside them
    /// is not seen: at 100 kS/s that is the first 0.32 ms after start).
    #[cold]
    #[inline(never)]
    fn prime(&mut self, value: f32) {
        if let Some(slot) = self.pre.get_mut(self.pre_next & (PRE_TRIGGER - 1)) {
            *slot = value;
        }
        self.pre_next = self.pre_next.wrapping_add(1);
        if self.pre_next >= PRE_TRIGGER {
            let sum: f32 = self.pre.iter().sum();
            self.baseline = sum / PRE_TRIGGER as f32;
            self.pre_start = self.pre_next;
            self.state = State::Idle;
        }
    }

    /// After a pulse that ran too long or was cut by a gap: wait for `hold` samples below the
    /// release level. After a pulse that ran too long the baseline is tracked 16 times faster
    /// than when idle (a DC step is followed within about `tau / 16`); after a gap it is frozen.
    #[cold]
    #[inline(never)]
    fn recover(&mut self, value: f32, track: bool) {
        if track {
            let fast = (16.0 * self.alpha).min(1.0);
            self.baseline += (value - self.baseline) * fast;
        }
        if (value - self.baseline) <= self.release {
            self.pulse.below_release = self.pulse.below_release.saturating_add(1);
            if self.pulse.below_release >= self.hold {
                self.state = State::Idle;
                self.pre_start = self.pre_next;
            }
        } else {
            self.pulse.below_release = 0;
        }
    }

    /// First sample after a gap: a pulse already above the trigger lost its start.
    #[cold]
    #[inline(never)]
    fn resume(&mut self, sample: i32, value: f32, index: u64) -> Option<Detection> {
        self.state = State::Idle;
        let v = value - self.baseline;
        if (v > self.trigger && self.above_ringing(v)) || sample >= self.adc_max {
            return self.trigger(sample, value, index, true);
        }
        self.track_ringing(v);
        self.track_baseline(value);
        None
    }

    /// `true` when `v` (above the trigger) also stands above the ringing: always for a rigid
    /// chain; otherwise above [`RING_SIGMAS`] times the quiet RMS (the same test as
    /// [`Detector::feed_quiet_values`]).
    #[inline(always)]
    fn above_ringing(&self, v: f32) -> bool {
        self.ring_weight <= 0.0 || v * v > RING_SIGMAS * RING_SIGMAS * self.ring_ms()
    }

    /// A quiet sample `v` joins the quiet mean square (behind a non-rigid chain), exactly as
    /// in [`Detector::feed_quiet_values`] and [`Detector::feed_quiet_pairs`].
    #[inline(always)]
    fn track_ringing(&mut self, v: f32) {
        if self.ring_weight > 0.0 {
            self.ring_sum = ring_sum_step(self.ring_sum, self.ring_decay, v);
        }
    }

    /// The quiet signal's mean square about the baseline (counts^2), `S w / (1 - w)`: an
    /// exponential average with weight `w` per sample.
    #[inline(always)]
    fn ring_ms(&self) -> f32 {
        self.ring_scale() * self.ring_sum
    }

    /// `w / (1 - w)`: the quiet mean square per unit of `ring_sum`.
    #[inline(always)]
    fn ring_scale(&self) -> f32 {
        self.ring_weight / self.ring_decay
    }

    fn track_baseline(&mut self, value: f32) {
        let step = self.baseline_step(value - self.baseline);
        self.baseline += step * self.alpha;
    }

    /// How far a quiet sample `v` (counts above the baseline) moves the baseline, before the
    /// weight: `v`, but at most the level a sample must pass to start a pulse below it
    /// ([`clamp_low`]), so that a negative spike cannot drag the baseline down, and ringing
    /// the trigger waits out moves it both ways alike.
    #[inline(always)]
    fn baseline_step(&self, v: f32) -> f32 {
        clamp_low::<M>(v, self.trigger, || {
            if self.ring_weight > 0.0 {
                RING_SIGMAS * RING_SIGMAS * self.ring_ms()
            } else {
                0.0
            }
        })
    }

    /// The `len` pre-trigger samples from ring slot `first` against the baseline: the sum of
    /// the oldest half's values, and of their steps into the baseline (each value less the
    /// baseline, at least `floor`, as [`Detector::baseline_step`] takes it) with the count of
    /// the steps not clamped (feature `second_order`). Plain loops, kept out of line: the
    /// pulse's start is cold.
    #[inline(never)]
    fn pre_trigger_window(&self, first: usize, len: usize, floor: f32) -> PreTrigger {
        #[cfg(not(feature = "second_order"))]
        let _ = floor;
        let b = self.baseline;
        let value = |k: usize| self.pre_at(first, k) - b;
        let mut w = PreTrigger {
            old_sum: 0.0,
            #[cfg(feature = "second_order")]
            steps: 0.0,
            #[cfg(feature = "second_order")]
            free: 0.0,
        };
        for k in 0..len / 2 {
            w.old_sum += value(k);
        }
        #[cfg(feature = "second_order")]
        for k in 0..len {
            let v = value(k);
            // A compare and a select (`f32::max` is a call on the M4F); NaN takes the floor.
            if v >= floor {
                w.steps += v;
                w.free += 1.0;
            } else {
                w.steps += floor;
            }
        }
        w
    }

    /// The baseline before the pre-trigger samples of `window` moved it: they hold a pulse's
    /// rising edge below the trigger, which the baseline took in as quiet and would subtract
    /// from every sample of the pulse (and of the pulses after it). Each moved it by `alpha`
    /// times its step; to first order in `alpha` (the baseline moves by `O(alpha)` over the
    /// samples) the steps taken at the baseline `b` now sum to `S`, and `n` of them unclamped
    /// moved with it, so `b = b_before + alpha (S + n (b - b_before))`: `b_before = b - alpha S /
    /// (1 - n alpha)`. Where `n alpha` exceeds 1/2 (a baseline time constant under 64 samples)
    /// the baseline stays.
    #[cfg(feature = "second_order")]
    fn baseline_before(&self, window: &PreTrigger) -> f32 {
        let kept = 1.0 - window.free * self.alpha;
        if kept < 0.5 {
            return self.baseline;
        }
        self.baseline - self.alpha * window.steps / kept
    }

    /// The `k`-th pre-trigger sample from ring slot `first` (the ring wraps; its length is a
    /// power of two).
    #[inline(always)]
    fn pre_at(&self, first: usize, k: usize) -> f32 {
        let i = first.wrapping_add(k) & (PRE_TRIGGER - 1);
        self.pre.get(i).copied().unwrap_or(0.0)
    }

    /// Starts a pulse with the pre-trigger samples, oldest first.
    #[cold]
    #[inline(never)]
    fn trigger(
        &mut self,
        sample: i32,
        value: f32,
        index: u64,
        after_gap: bool,
    ) -> Option<Detection> {
        let mut p = Pulse::EMPTY;
        let ring = if self.ring_weight > 0.0 {
            M::sqrt(self.ring_ms())
        } else {
            0.0
        };
        p.trigger = self.trigger.max(RING_SIGMAS * ring);
        p.release = self.release.max(0.5 * RING_SIGMAS * ring);
        let len = self.pre_next.wrapping_sub(self.pre_start).min(PRE_TRIGGER);
        let first = self.pre_next.wrapping_sub(len);
        let old = len / 2;
        // The oldest half of the pre-trigger samples: clear of the pulse's leading edge. Where
        // they sit at the baseline, the pre-trigger samples are the pulse's, and the baseline
        // lets go of them; where they do not, it lags a drift, which they are part of. The
        // floor of a baseline step is the trigger level in force ([`clamp_low`]).
        let window = self.pre_trigger_window(first, len, -p.trigger);
        p.drift = old >= 4 && (window.old_sum / old as f32).abs() > 0.5 * p.trigger;
        #[cfg(feature = "second_order")]
        if !p.drift && self.rigid() {
            self.baseline = self.baseline_before(&window);
        }
        let mut old_sq = 0.0;
        for k in 0..len {
            let w = self.pre_at(first, k) - self.baseline;
            p.samples += 1;
            p.sum += w;
            p.sum_sq += w * w;
            p.prev = p.last;
            p.last = w;
            p.smooth(w, self.smooth);
            if k < old {
                old_sq += w * w;
            }
        }
        // Ringing before the pulse: its oldest half above the noise (by two standard
        // deviations of 16 white samples' mean square, `sqrt(2 / 16)`), and either, behind a
        // chain, the quiet signal's longer memory above it ([`RING_TRACK_SIGMAS`]: it sees
        // ringing below the next test and averages more of its phase, but alone it rose on the
        // coloured noise and pulse tails behind a MEMS band known exactly), or the oldest half
        // well above it (16 samples of noise alone exceed 3 noise^2 in mean square with
        // probability 1e-5).
        let (ms, noise2) = (old_sq / old.max(1) as f32, self.noise * self.noise);
        if old >= 4 && ms > 1.7 * noise2 {
            let w = self.ring_weight;
            let level = if w > 0.0
                && self.ring_ms()
                    > noise2 * (1.0 + RING_TRACK_SIGMAS * M::sqrt(2.0 * w / (2.0 - w)))
            {
                self.ring_ms()
            } else if ms > 3.0 * noise2 {
                ms
            } else {
                noise2
            };
            p.excess = M::sqrt(level - noise2);
        }
        p.after_gap = after_gap;
        self.pulse = p;
        self.state = State::Active;
        self.active(sample, value, index)
    }

    #[inline(never)]
    fn active(&mut self, sample: i32, value: f32, index: u64) -> Option<Detection> {
        let v = value - self.baseline;
        let modes = self.behind_modes();
        let p = &mut self.pulse;
        p.samples = p.samples.saturating_add(1);
        p.sum += v;
        p.sum_sq += v * v;
        p.smooth(v, self.smooth);
        let older = p.prev;
        // Second difference at the previous sample.
        p.min_curvature = p.min_curvature.min(p.prev + v - 2.0 * p.last);
        p.prev = p.last;
        #[cfg(not(feature = "pulse_shape"))]
        p.track_clipping(sample, v, self.adc_min, self.adc_max);
        #[cfg(feature = "pulse_shape")]
        p.track_clipping(
            sample,
            v,
            older,
            index,
            (self.adc_min, self.adc_max, self.guard2),
        );
        p.track_top(sample);
        p.track_moments(v);
        // Behind beam modes the values after a clipped run carry the sections' state error
        // (thousands of counts after a deep clip) and the raw samples the modes' ringing (the
        // modes' gain times a peak that passed full scale): either falls and rises like a
        // second impact, so the second-peak test is not made there. The flank fit's residual
        // (its sum takes a second impact within the pulse) remains.
        let after_run = modes && p.clipped > 0;
        p.track_max(v, older, index, self.noise, !after_run);
        p.last = v;
        if v <= p.release {
            p.below_release = p.below_release.saturating_add(1);
        } else {
            p.below_release = 0;
        }
        if p.below_release >= self.hold {
            self.state = State::Idle;
            self.pre_start = self.pre_next;
            #[cfg(all(feature = "pulse_shape", feature = "settle"))]
            if let Some(pending) = self.clip_to_settle(index) {
                self.pending = Some(pending);
                return None;
            }
            return Some(self.measure());
        }
        if p.samples > self.max_samples {
            self.state = State::Recovering(true);
            self.pulse.below_release = 0;
            return Some(self.reject(RejectReason::TooLong));
        }
        None
    }

    fn reject(&self, reason: RejectReason) -> Detection {
        Detection::Pulse {
            at_sample: self.pulse.max_at,
            outcome: Err(reason),
        }
    }

    /// Whether the `v^2`-weighted skewness of the pulse's part above the trigger is the
    /// contact's own (0 for Hertz, [`crate::ContactCalibration::skewness`] for a damped law)
    /// within `skew_tolerance + 0.6 / n + 40 (noise / F_max) / sqrt(n)` for `n` samples above
    /// the trigger (the sampling spread, at most `0.8 / n` at any phase, and about eight noise
    /// sigmas: one sigma is `5.1 (noise / F_max) / sqrt(n)`), widened by four times the
    /// calibrated skewness times `min(trigger / F_max, 1/4)`: a damped pulse cut at a fraction
    /// `c` of its peak is less skewed, by about `2.5 c` of its skewness for Flores at e 0.3
    /// (0.93 above 0.5 %, 0.81 above 5 %, 0.50 above 20 %), less for the other laws. Two
    /// impacts 0.45-0.6 contact times apart with peaks 2 : 1 are skewed by 0.27-0.69. Pulses
    /// of fewer than 8 samples above the trigger pass.
    fn symmetric_enough(&self, peak: f32) -> bool {
        let [m0, m1, m2, m3] = self.pulse.moments;
        let n = self.pulse.above_trigger as f32;
        if n < 8.0 || m0 <= 0.0 || peak <= 0.0 {
            return true;
        }
        let mu = m1 / m0;
        let var = m2 / m0 - mu * mu;
        if var <= 0.0 {
            return true;
        }
        let third = m3 / m0 - 3.0 * mu * (m2 / m0) + 2.0 * mu * mu * mu;
        let skew = third / (var * M::sqrt(var));
        let allowed = self.skew_tolerance
            + 0.6 / n
            + 40.0 * self.noise / (peak * M::sqrt(n))
            + 4.0 * self.skewness.abs() * (self.pulse.trigger / peak).min(0.25);
        (skew - self.skewness).abs() <= allowed
    }

    /// Peak and duration of the finished pulse (see the module docs for the method).
    #[cold]
    #[inline(never)]
    fn measure(&self) -> Detection {
        let p = &self.pulse;
        let at_sample = p.max_at;
        let reject = |r| Detection::Pulse {
            at_sample,
            outcome: Err(r),
        };
        if p.saturated {
            return self.measure_clipped();
        }
        if let Some(r) = self.flaw_before_fit() {
            return reject(r);
        }
        let Some(PeakFit {
            peak,
            duration,
            gain2,
            weight_sum,
            ..
        }) = self.fit_top()
        else {
            return reject(RejectReason::Implausible);
        };
        if let Some(r) = self.flaw_of_top(peak, duration) {
            return reject(r);
        }
        let sigmas = self.sigmas(peak, duration, gain2, weight_sum);
        // Shorter than the fit can measure, even allowing three sigma for noise.
        if duration * (1.0 + 3.0 * sigmas.ln_duration) < MIN_DURATION_SAMPLES {
            return reject(RejectReason::TooShort);
        }
        if !self.shape_ok(peak, &sigmas) || !self.symmetric_enough(peak) {
            return reject(RejectReason::Misshapen);
        }
        let ([_, before], [after, _]) = (p.before_max, p.after_max);
        let trigger_margin = (peak - p.trigger) / (self.noise * M::sqrt(gain2));
        #[cfg(feature = "pulse_shape")]
        if let Some(m) = self.short_measurement(duration, trigger_margin) {
            return Detection::Pulse {
                at_sample,
                outcome: Ok(m),
            };
        }
        let (sigma_ln_force, sigma_ln_duration) = self.stated_sigmas(&sigmas);
        Detection::Pulse {
            at_sample,
            outcome: Ok(Measurement {
                peak_force_n: peak * self.force_per_count_n,
                duration_s: duration * self.dt_s,
                sigma_ln_force,
                sigma_ln_duration,
                cov_ln: sigmas.shared - sigma_ln_force * sigma_ln_force,
                asymmetry: crate::sampled_phase::neighbour_asymmetry(before, p.max, after),
                trigger_margin,
                #[cfg(feature = "pulse_shape")]
                shape_fitted: false,
            }),
        }
    }

    /// A damped pulse on a rigid chain shorter than [`SHORT_SAMPLES`] (`duration`, samples,
    /// as the fit through its top measured it) measured by its contact's shape from the five
    /// samples about its largest ([`short_shape_fit`]), its sigmas the fit's; `None` for any
    /// other pulse, or when the fit does not hold (the fit through the top then stands).
    #[cfg(feature = "pulse_shape")]
    #[inline(never)]
    fn short_measurement(&self, duration: f32, trigger_margin: f32) -> Option<Measurement> {
        let p = &self.pulse;
        if self.hertz || !self.rigid() || duration >= SHORT_SAMPLES || p.after_count < 2 {
            return None;
        }
        let ([b0, b1], [a0, a1]) = (p.before_max, p.after_max);
        let fit = short_shape_fit(
            &[b0, b1, p.max, a0, a1],
            self.noise,
            &self.pulse_shape,
            duration,
        )?;
        // The rows were weighted: the gains are the variances.
        Some(self.shape_measurement(&fit, 1.0, 0.0, trigger_margin))
    }

    /// The measurement of a pulse by a fit of its shape (a clipped pulse's flank fit, or a
    /// short pulse's, [`FlankFit`]): its peak and duration the continuous pulse's, their
    /// variances the fit's gains times `variance` (counts^2) with the template's own error
    /// `floor2` (log units squared), and `trigger_margin`.
    fn shape_measurement(
        &self,
        fit: &FlankFit,
        variance: f32,
        floor2: f32,
        trigger_margin: f32,
    ) -> Measurement {
        let [f2, t2, cov] = fit.gains.map(|g| g * variance);
        Measurement {
            peak_force_n: fit.peak * self.force_per_count_n,
            duration_s: fit.duration * self.dt_s,
            sigma_ln_force: M::sqrt(f2 + floor2),
            sigma_ln_duration: M::sqrt(t2 + floor2),
            cov_ln: cov,
            asymmetry: 0.0,
            trigger_margin,
            #[cfg(feature = "pulse_shape")]
            shape_fitted: true,
        }
    }

    /// Why the finished, unclipped pulse cannot be measured before any fit: a lone sample
    /// above the trigger with low neighbours (`Spike`), a gap, a second impact, or a drifting
    /// baseline; `None` when none of these.
    #[inline(always)]
    fn flaw_before_fit(&self) -> Option<RejectReason> {
        let p = &self.pulse;
        let [_, before] = p.before_max;
        let [after, _] = p.after_max;
        let neighbour = if p.after_count > 0 {
            before.max(after)
        } else {
            before
        };
        if p.above_trigger <= 1 && neighbour < 0.2 * p.max {
            return Some(RejectReason::Spike);
        }
        if p.after_gap {
            return Some(RejectReason::Gap);
        }
        if p.pileup {
            return Some(RejectReason::PileUp);
        }
        if p.drift {
            return Some(RejectReason::Drift);
        }
        None
    }

    /// Peak (counts) and duration (samples) of the pulse's top: [`smooth_fit`] of the largest
    /// mean of `smooth` samples for a long pulse, else [`peak_fit`] of the five samples about
    /// the largest; `None` when they are not a positive pulse.
    #[inline(always)]
    fn fit_top(&self) -> Option<PeakFit> {
        let p = &self.pulse;
        let [before2, before] = p.before_max;
        let [after, after2] = p.after_max;
        let samples = p.samples as f32;
        // The second-order corrections on a rigid chain only (see the module's docs).
        #[cfg(feature = "second_order")]
        let rigid = self.rigid();
        #[cfg(feature = "second_order")]
        let sum = if rigid {
            self.unbiased_sum(samples)
        } else {
            p.sum
        };
        #[cfg(not(feature = "second_order"))]
        let sum = p.sum;
        let fit = if self.smooth > 1 {
            smooth_fit(p.top_smooth, self.smooth, sum).map(|(peak, duration)| PeakFit {
                peak,
                duration,
                gain2: 1.0 / self.smooth as f32,
                weight_sum: 1.0,
                vertex_bias: [0.0; 2],
                #[cfg(feature = "noise_colour")]
                basis: crate::shape_fit::WeightBasis::Largest,
            })?
        } else {
            peak_fit::<M>(
                [before2, before, p.max, after, after2],
                sum,
                samples,
                self.five,
            )?
        };
        #[cfg(feature = "noise_colour")]
        let fit = {
            let mut fit = fit;
            if let Some(colour) = &self.colour {
                self.colour_gains(colour, &mut fit, samples);
            }
            fit
        };
        #[cfg(feature = "second_order")]
        let fit = if rigid {
            unbiased_vertex(fit, self.noise)
        } else {
            fit
        };
        Some(fit)
    }

    /// The pulse's sum of `samples` samples, `S`, with `ln S` made unbiased to second order in
    /// its noise: `E[ln S] = ln S_0 - var S / (2 S_0^2)`, so `S (1 + var S / (2 S^2))` with `var S
    /// = noise^2 samples`: it runs on a rigid chain only, whose noise is white. The duration is
    /// the area over the peak: at 9 noise RMS and 44 samples the bias of `ln t_c` it removes is
    /// -0.005.
    #[cfg(feature = "second_order")]
    fn unbiased_sum(&self, samples: f32) -> f32 {
        let sum = self.pulse.sum;
        let var = self.noise * self.noise * samples;
        if sum > 0.0 {
            sum + 0.5 * var / sum
        } else {
            sum
        }
    }

    /// `V(n)`: the variance of the sum of `n` consecutive equalised samples over one sample's
    /// (`n` for white noise, [`crate::noise_colour::NoiseColour::sum_variance`] behind a chain).
    fn sum_variance(&self, n: f32) -> f32 {
        #[cfg(feature = "noise_colour")]
        if let Some(colour) = &self.colour {
            return colour.sum_variance(n);
        }
        n
    }

    /// Behind a chain the samples are correlated: `fit`'s noise gains become its weights'
    /// quadratic form in the noise's correlations `colour`, and their covariance with the sum
    /// of its `samples` (for the mean of `smooth` samples, `V(smooth) / smooth^2` and the middle
    /// sample's row; see [`NoiseColour`]).
    #[cfg(feature = "noise_colour")]
    #[inline(never)]
    fn colour_gains(&self, colour: &NoiseColour, fit: &mut PeakFit, samples: f32) {
        (fit.gain2, fit.weight_sum) = if self.smooth > 1 {
            let w = self.smooth as f32;
            (colour.sum_variance(w) / (w * w), colour.middle_row(samples))
        } else {
            let (top, per_sample) = fit.weights();
            colour.weighted(&top, per_sample, samples)
        };
    }

    /// Why a fitted top of `peak` counts and `duration` samples is not a pulse's: a flat
    /// (clipped) top, `Saturated`, or a bend sharper than the Hertz pulse's, `Spike`.
    #[inline(always)]
    fn flaw_of_top(&self, peak: f32, duration: f32) -> Option<RejectReason> {
        let p = &self.pulse;
        // A clipped top: a run of identical samples at the maximum, longer than noise makes by
        // chance and than a long pulse's own flat top (`duration / 20` samples).
        // A contact with a broader top than Hertz's (a yielding one) allows that much more.
        let flat_limit = (0.05 * duration).max(FLAT_TOP_SAMPLES as f32);
        #[cfg(feature = "plasticity")]
        let flat_limit = flat_limit * self.flat_top_ratio;
        if self.adc_noisy && p.flat as f32 >= flat_limit {
            return Some(RejectReason::Saturated);
        }
        // The sharpest bend a Hertz pulse of this peak and duration has (see the module docs).
        let bend =
            1.65 * core::f32::consts::PI * core::f32::consts::PI * peak / (duration * duration);
        if p.min_curvature < -(2.0 * bend + self.spike_fraction * peak + 8.0 * self.noise) {
            return Some(RejectReason::Spike);
        }
        None
    }

    /// The noise model of a fitted pulse of `peak` counts and `duration` samples, whose fit
    /// has noise gain `gain2` and shares `weight_sum` samples with the sum: the fit's own
    /// error, the noise, and the ringing seen before the pulse (see [`Sigmas`]).
    #[inline(always)]
    fn sigmas(&self, peak: f32, duration: f32, gain2: f32, weight_sum: f32) -> Sigmas {
        let p = &self.pulse;
        let n = p.samples as f32;
        // Sampling: the fit's own error falls as `duration^-2.5`; its worst over the sample's
        // phase, measured at 3 to 400 samples per pulse (tests/detector.rs,
        // `shape_fit_errors_by_rate`), is 0.15 and 0.65 of it for the peak and the duration,
        // taken here as the standard deviations (beside `model_sigma` this matters below ~10
        // samples per pulse).
        let sampling = 1.0 / (duration * duration * M::sqrt(duration));
        let (fit_force, fit_duration) = (FIT_FORCE * sampling, FIT_DURATION * sampling);
        // The fit's peak carries `gain2` times one sample's noise variance (the mean of
        // `smooth` samples, or the five samples' least squares), and shares `weight_sum`
        // samples' worth of it with the pulse's sum: `cov(ln sum, ln F_max) = noise^2
        // weight_sum / (sum F_max)`.
        let noise_force = self.noise * M::sqrt(gain2) / peak;
        let sigma_area = self.noise * M::sqrt(self.sum_variance(n)) / p.sum;
        let shared = self.noise * self.noise * weight_sum / (p.sum * peak);
        // The shape check's allowance for the ringing seen before the pulse: its amplitude
        // (`sqrt 2` RMS, and a half more) on the peak and on all `n` samples of the sum.
        let (ring_force, ring_area) = (
            1.5 * p.excess / peak,
            1.5 * p.excess * n / p.sum.max(f32::MIN_POSITIVE),
        );
        let ring2 = ring_force * ring_force + ring_area * ring_area;
        // What the same ringing leaves in the measurement, at its own frequency.
        let ring = self.ring_noise(peak);
        let ln_force = M::sqrt(noise_force * noise_force + fit_force * fit_force + ring.force2);
        // `ln t_c = ln sum - ln F_max`: the variance of the difference of the two.
        let ln_duration = M::sqrt(
            (sigma_area * sigma_area + noise_force * noise_force - 2.0 * shared).max(0.0)
                + fit_duration * fit_duration
                + ring.duration2().max(0.0),
        );
        let shared = shared + ring.shared;
        Sigmas {
            ln_force,
            ln_duration,
            shared,
            area: sigma_area,
            fit_force,
            fit_duration,
            ring2,
        }
    }

    /// What ringing seen before the pulse (RMS `excess` above the noise) leaves in the
    /// measured `ln F_max` and `ln sum` of a pulse of `peak` counts: a sinusoid of random
    /// phase at `theta` radians per sample, going on through the pulse's `n` summed samples
    /// whose middle lies `m` samples after the peak, moves the peak by `x = e sin phi / peak`
    /// (`e` the RMS times `sqrt 2`) and the sum by
    /// `y = e (D cos(theta m) sin phi + D sin(theta m) cos phi) / sum`, with
    /// `D = sin(theta n / 2) / sin(theta / 2)`. Over the phase:
    /// `var x = excess^2 / peak^2`, `var y = excess^2 D^2 / sum^2`,
    /// `cov(x, y) = excess^2 D cos(theta m) / (peak sum)`. Behind a chain the ringing is at its
    /// beam modes' frequencies (an off equaliser's own poles lie just below them), in a mix
    /// that depends on the chain's errors and on the stream's impacts (a fast mode has
    /// decayed by the next pulse, a slow one rings through several), which the node does not
    /// know: the moments are averaged over a uniform prior on the mix, each mode's share
    /// `1 / M` of the `M` modes' on average. (The mode that moves `ln t_c` most, taken before,
    /// stated `ln t_c`'s ringing about twice as wide as it was; each mode's share from its
    /// energy per impact, by Campbell's theorem, stated it too narrow behind the MEMS band,
    /// whose longer window averages all but the slowest mode out.) Without modes it is a slow
    /// offset (`theta -> 0`, `D = n`). Zero without ringing.
    #[inline(always)]
    fn ring_noise(&self, peak: f32) -> RingNoise {
        let p = &self.pulse;
        if p.excess <= 0.0 {
            return RingNoise::default();
        }
        let (n, sum) = (p.samples as f32, p.sum.max(f32::MIN_POSITIVE));
        // Samples after the peak: fewer than `max_samples`, a `u32`.
        let after = self.next_index.wrapping_sub(1).wrapping_sub(p.max_at) as u32 as f32;
        let m = after - 0.5 * (n - 1.0);
        let e2 = p.excess * p.excess;
        let force2 = e2 / (peak * peak);
        let of = |d: f32, c: f32| RingNoise {
            force2,
            sum2: e2 * d * d / (sum * sum),
            shared: e2 * d * c / (peak * sum),
        };
        let omegas = self
            .ring_omegas
            .get(..self.ring_modes as usize)
            .unwrap_or(&[]);
        if omegas.is_empty() {
            return of(n, 1.0);
        }
        let (mut d2, mut dc) = (0.0, 0.0);
        for &w in omegas {
            let (half, _) = crate::math::sin_cos_any(0.5 * w);
            let (wide, _) = crate::math::sin_cos_any(0.5 * w * n);
            let (_, c) = crate::math::sin_cos_any(w * m);
            let d = wide / half.max(f32::MIN_POSITIVE);
            d2 += d * d;
            dc += d * c;
        }
        let share = 1.0 / omegas.len() as f32;
        RingNoise {
            force2,
            sum2: share * e2 * d2 / (sum * sum),
            shared: share * e2 * dc / (peak * sum),
        }
    }

    /// The sigmas of `ln F_max` and `ln t_c` a measurement states: the noise model's `s` with
    /// the fit's own error as its root mean square over the phase (`FIT_FORCE_RMS`,
    /// `FIT_DURATION_RMS` times `n^-2.5`) in place of its worst (`FIT_FORCE`, `FIT_DURATION`),
    /// which the detector's own checks keep: `s^2 - worst^2 (1 - (rms / worst)^2)`. Where the
    /// scene's sampling correction states that error in its place, the whole of it is taken
    /// out, so that it is not counted twice.
    #[inline(always)]
    fn stated_sigmas(&self, s: &Sigmas) -> (f32, f32) {
        let (keep_force, keep_duration) = if self.sampling_calibrated {
            (0.0, 0.0)
        } else {
            (FIT_FORCE_RMS / FIT_FORCE, FIT_DURATION_RMS / FIT_DURATION)
        };
        let less = |a: f32, worst: f32, keep: f32| {
            M::sqrt((a * a - worst * worst * (1.0 - keep * keep)).max(0.0))
        };
        (
            less(s.ln_force, s.fit_force, keep_force),
            less(s.ln_duration, s.fit_duration, keep_duration),
        )
    }

    /// Whether the pulse's energy and area agree with the contact's shape for a fitted `peak`
    /// (counts): `|ln q| <= shape_tolerance + 4 sigma_q` (see the module docs).
    #[inline(always)]
    fn shape_ok(&self, peak: f32, s: &Sigmas) -> bool {
        let p = &self.pulse;
        let n = p.samples as f32;
        let energy = p.sum_sq - n * self.noise * self.noise;
        let q = (energy * C_AREA) / (p.sum * peak * C_ENERGY * self.shape_ratio);
        let sigma_energy = 2.0 * self.noise / M::sqrt(energy.max(f32::MIN_POSITIVE));
        let sigma_q = M::sqrt(
            sigma_energy * sigma_energy
                + s.area * s.area
                + s.ln_force * s.ln_force
                + s.fit_duration * s.fit_duration
                + s.ring2,
        );
        q > 0.0 && M::ln(q).abs() <= self.shape_tolerance + 4.0 * sigma_q
    }

    /// A pulse with samples at the ADC's full scale, measured from its unclipped flanks when
    /// the clipped samples are one run at its top, on a rigid chain or behind a chain (feature
    /// `pulse_shape`; behind beam modes also `settle`), with two samples either side of the run (beyond those
    /// the equaliser's FIR took from a clipped one): an undamped pulse by the Hertz shape
    /// ([`flank_fit`], rigid only), a damped one by the contact's own (`Settings::pulse_shape`,
    /// [`shape_flank_fit`]); otherwise, or when the fit does not describe the flanks,
    /// `Saturated`. Its sigmas are the fit's, from the noise and the four samples (with the
    /// table's, the pulse's sum); the shape and skewness checks, which a clipped top fails,
    /// are not made.
    #[cold]
    #[inline(never)]
    fn measure_clipped(&self) -> Detection {
        let reject = self.reject(RejectReason::Saturated);
        if !self.clip_measurable() {
            return reject;
        }
        let (flanks, first) = self.flanks();
        self.flank_detection(&flanks, first).unwrap_or(reject)
    }

    /// Whether the finished pulse's clipped samples are one run at its top, with its whole
    /// flanks (no gap, second impact, drift or low clip) and two samples after the run past
    /// the FIR's guard, behind a chain whose flanks can be read.
    fn clip_measurable(&self) -> bool {
        let p = &self.pulse;
        let whole = !(p.low_clip || p.after_gap || p.pileup || p.drift);
        let after = p.after_clip_count >= 2 + self.guard2();
        whole && self.flanks_readable() && after && p.clipped == p.flat
    }

    /// The measurement of a clipped pulse by the fit of its `flanks` (`first`: the index of
    /// its run's first sample); `None` when the fit fails.
    fn flank_detection(&self, flanks: &Flanks, first: u64) -> Option<Detection> {
        let (fit, noise2, floor2) = self.fit_flanks(flanks)?;
        Some(Detection::Pulse {
            // The sample nearest the fitted peak (within the run; through u32, which the FPU
            // converts, where a u64 would call a library routine).
            at_sample: first + u64::from((fit.peak_at + 0.5).max(0.0) as u32),
            outcome: Ok(self.shape_measurement(&fit, noise2, floor2, f32::INFINITY)),
        })
    }

    /// Behind beam modes, the finished pulse (its last sample `index`) as a clipped pulse to
    /// wait for the sections' state error, when its flanks can be read.
    #[cfg(all(feature = "pulse_shape", feature = "settle"))]
    fn clip_to_settle(&self, index: u64) -> Option<PendingClip> {
        let p = &self.pulse;
        if !(self.behind_modes() && p.saturated && self.clip_measurable()) {
            return None;
        }
        let (flanks, first) = self.flanks();
        Some(PendingClip {
            flanks,
            first,
            anchor: p.last_clip_at + 1 + u64::from(self.guard2),
            end: index + 1,
            excess: p.excess,
        })
    }

    /// Where a clipped pulse waiting for the sections' state error lies from its anchor,
    /// counted to the next sample ([`crate::settle::Settler::start_anchored`]).
    #[cfg(all(feature = "pulse_shape", feature = "settle"))]
    pub(crate) fn clip_anchor(&self) -> Option<crate::settle_clip::ClipAnchor> {
        let c = self.pending.as_ref()?;
        let count = |from: u64, to: u64| u32::try_from(to.saturating_sub(from)).unwrap_or(u32::MAX);
        Some(crate::settle_clip::ClipAnchor {
            to_window: count(c.anchor, self.next_index),
            in_pulse: count(c.anchor, c.end),
        })
    }

    /// The clipped pulse waiting for the sections' state error, measured with `error` taken
    /// off its samples after the run (their sigmas joining the flank fit's,
    /// [`FlankChain::state_error`]), or `Saturated` without it (the re-estimation was not
    /// believed) or when the fit fails; `None` when no pulse waits.
    #[cfg(all(feature = "pulse_shape", feature = "settle"))]
    pub(crate) fn resolve_clip(
        &mut self,
        error: Option<crate::settle_clip::ClipError>,
    ) -> Option<Detection> {
        let c = self.pending.take()?;
        // The waiting pulse is still the detector's (a sample fed resolves it first).
        let reject = self.reject(RejectReason::Saturated);
        let Some(e) = error else {
            return Some(reject);
        };
        let [a0, a1] = c.flanks.after;
        let [v0, v1, v_sum] = e.variance;
        // Ringing seen before the pulse goes on through it, slow against it: at each flank
        // sample, and with one sign over the sum's samples.
        let ring = c.excess;
        let flanks = Flanks {
            after: [a0 - e.after[0], a1 - e.after[1]],
            sum: c.flanks.sum - e.sum,
            chain: FlankChain {
                state_error: [
                    M::sqrt(v0.max(v1) + ring * ring),
                    M::sqrt(v_sum) + ring * c.flanks.samples,
                ],
                ..c.flanks.chain
            },
            ..c.flanks
        };
        Some(self.flank_detection(&flanks, c.first).unwrap_or(reject))
    }

    /// A clipped pulse still waiting when the stream ends or breaks: `Saturated`.
    fn unsettled_clip(&mut self) -> Option<Detection> {
        #[cfg(all(feature = "pulse_shape", feature = "settle"))]
        return self.resolve_clip(None);
        #[cfg(not(all(feature = "pulse_shape", feature = "settle")))]
        None
    }

    /// The clipped pulse as the flank fits read it, and the index of its run's first sample:
    /// on a rigid chain, the clipped samples at the largest value.
    #[cfg(not(feature = "pulse_shape"))]
    fn flanks(&self) -> (Flanks, u64) {
        let p = &self.pulse;
        let run = p.clipped as f32;
        let flanks = Flanks {
            before: p.before_max,
            run,
            after: p.after_clip,
            level: p.max,
            sum: p.sum,
            samples: p.samples as f32,
            run_sum: run * p.max,
            chain: FlankChain::RIGID,
        };
        (flanks, p.max_at)
    }

    /// The clipped pulse as the flank fits read it, and the index of its run's first sample:
    /// the clipped samples and the equaliser's delay either side of them (those its FIR took
    /// from a clipped one), at the level of the ADC's full scale.
    #[cfg(feature = "pulse_shape")]
    fn flanks(&self) -> (Flanks, u64) {
        let p = &self.pulse;
        let guard2 = f32::from(self.guard2);
        let flanks = Flanks {
            before: p.before_clip,
            run: p.clipped as f32 + guard2,
            after: p.after_clip,
            level: self.clip_level(),
            sum: p.sum,
            samples: p.samples as f32,
            run_sum: p.run_sum,
            chain: FlankChain {
                guard: 0.5 * guard2,
                lag: self.clip_lag,
                ..FlankChain::RIGID
            },
        };
        (flanks, p.clip_at)
    }

    /// `flanks.chain` with the chain's errors at a pulse of `t_c` samples
    /// (`FlankChain::sample_error` and `level_error`, from `Detector::clip_errors`); zeros on
    /// a rigid chain.
    #[cfg(feature = "pulse_shape")]
    fn clip_chain(&self, flanks: &Flanks, t_c: f32) -> FlankChain {
        let at = 2.0 * libm::log2f(t_c / CLIP_ERROR_FIRST_N);
        let position = crate::math::table_position(at, CLIP_ERROR_POINTS);
        let [body, ends, raw] = self
            .clip_errors
            .map(|e| crate::math::interpolate(&e, position));
        FlankChain {
            sample_error: [body, ends],
            level_error: raw + self.mode_slow() * flanks.run * (flanks.run + t_c),
            ..flanks.chain
        }
    }

    /// The force (counts over the baseline) at which the ADC clips: its full scale, or behind
    /// beam modes (feature `settle`), whose raw top is `(1 + sum g_j)` times the force less a
    /// slow part, the sample before the run plus the raw headroom it left over that gain.
    #[cfg(feature = "pulse_shape")]
    fn clip_level(&self) -> f32 {
        #[cfg(feature = "settle")]
        if self.behind_modes() {
            let p = &self.pulse;
            let headroom = self.adc_max as f32 - p.raw_before_clip as f32;
            return p.before_clip[1] + headroom / self.mode_gain;
        }
        self.adc_max as f32 - self.baseline
    }

    /// How far, over the peak, the raw top behind beam modes parts from `(1 + sum g_j)`
    /// times the force per sample of the run and of the pulse (`sum g_j w_j^2 / (1 + sum
    /// g_j)`, `w_j` per sample); 0 elsewhere.
    #[cfg(feature = "pulse_shape")]
    fn mode_slow(&self) -> f32 {
        #[cfg(feature = "settle")]
        return self.mode_slow;
        #[cfg(not(feature = "settle"))]
        0.0
    }

    /// Samples after a clipped run that the equaliser's FIR took from a clipped one (twice
    /// its delay behind an accelerometer alone; 0 on a rigid chain, and always without the
    /// feature `pulse_shape`).
    fn guard2(&self) -> u8 {
        #[cfg(feature = "pulse_shape")]
        return self.guard2;
        #[cfg(not(feature = "pulse_shape"))]
        0
    }

    /// Whether a clipped pulse waits for the sections' state error (the chain has beam
    /// modes, with the features `pulse_shape` and `settle`).
    fn behind_modes(&self) -> bool {
        cfg!(all(feature = "pulse_shape", feature = "settle")) && self.ring_modes > 0
    }

    /// Whether the chain lets the flanks of a clipped pulse be read: a rigid one, or with
    /// the feature `pulse_shape` one of an accelerometer alone (whose FIR takes a few samples
    /// from the run; beam modes' sections would ring from it under the flanks) when the
    /// scene carries the contact's shape.
    fn flanks_readable(&self) -> bool {
        #[cfg(feature = "pulse_shape")]
        if self.pulse_shape.is_some() {
            return true;
        }
        self.rigid()
    }

    /// Whether the chain is rigid (the equaliser the identity: nothing rings, no FIR).
    fn rigid(&self) -> bool {
        self.ring_weight <= 0.0
    }

    /// The flank fit of a clipped pulse, the variance per sample its gains take (counts^2)
    /// and its template's own error (log units squared): for an undamped contact on a rigid
    /// chain, the noise's and the Hertz series' [`FLANK_FLOOR`]^2; where that series does not
    /// reach the flanks, behind an accelerometer, or for a damped contact, with the
    /// contact's [`PulseShape`] (the Hertz pulse's own, [`PulseShape::hertz`], or the
    /// scene's), the noise's with the table's error at the four samples
    /// (`PulseShape::error`; behind an accelerometer with the chain's own, [`FlankChain`],
    /// first at the shortest pulse the fit allows, then at the fitted one), and no floor.
    /// `None` for any other contact, or when the fit fails.
    fn fit_flanks(&self, flanks: &Flanks) -> Option<(FlankFit, f32, f32)> {
        let noise2 = self.noise * self.noise;
        if self.hertz && self.guard2() == 0 && !self.behind_modes() {
            if let Some(fit) = flank_fit(flanks, self.noise) {
                return Some((fit, noise2, FLANK_FLOOR * FLANK_FLOOR));
            }
        }
        #[cfg(feature = "pulse_shape")]
        if self.pulse_shape.is_some() {
            let shape = &self.pulse_shape;
            // Behind a chain, first with its errors at the shortest pulse the fit allows
            // (`run + 3` samples), then at the fitted one.
            let rigid = flanks.chain == FlankChain::RIGID;
            let first = match rigid {
                true => *flanks,
                false => Flanks {
                    chain: self.clip_chain(flanks, flanks.run + 3.0),
                    ..*flanks
                },
            };
            let (mut fit, mut table) = shape_flank_fit(&first, self.noise, shape)?;
            if !rigid {
                let flanks = Flanks {
                    chain: self.clip_chain(flanks, fit.duration * C_AREA / shape.area),
                    ..*flanks
                };
                (fit, table) = shape_flank_fit(&flanks, self.noise, shape)?;
            }
            let variance = noise2 + table * table + flanks.chain.state_variance();
            return Some((fit, variance, 0.0));
        }
        None
    }
}

/// Points of the equaliser's error per sample that a clipped pulse's flank fit reads
/// (`Detector::clip_errors`): from [`CLIP_ERROR_FIRST_N`] samples per pulse in steps of
/// `sqrt 2`, to 113; a longer pulse takes the last.
#[cfg(feature = "pulse_shape")]
const CLIP_ERROR_POINTS: usize = 12;

/// Samples per pulse at the first point of `Detector::clip_errors`.
#[cfg(feature = "pulse_shape")]
const CLIP_ERROR_FIRST_N: f32 = 2.5;

/// Samples per pulse at point `k` of `Detector::clip_errors`: `2.5 sqrt(2)^k`.
#[cfg(feature = "pulse_shape")]
fn clip_error_n(k: usize) -> f32 {
    CLIP_ERROR_FIRST_N * libm::powf(core::f32::consts::SQRT_2, k as f32)
}

/// The equaliser's error per sample of a pulse over its peak at [`clip_error_n`] samples per
/// pulse, which a clipped pulse's flank fit counts beside the noise behind a chain (the
/// sample before the run, and after it, read the force through the equaliser); zeros on a
/// rigid chain, behind beam modes without the feature `settle`, and where no flank fit is
/// made (`read` false: the scene carries no shape for the contact).
#[cfg(feature = "pulse_shape")]
#[inline(never)]
fn clip_errors<const N: usize, M: Backend>(
    scene: &Scene<N, M>,
    lag: f32,
    read: bool,
) -> [[f32; CLIP_ERROR_POINTS]; 3] {
    let design = scene.equaliser();
    let sensor = scene.sensor();
    let mut out = [[0.0; CLIP_ERROR_POINTS]; 3];
    let modes = !sensor.dynamics.modes().is_empty();
    if !read || design.is_identity() || (modes && !cfg!(feature = "settle")) {
        return out;
    }
    let (dynamics, fs) = (&sensor.dynamics, sensor.sample_rate_hz);
    // The raw top's own part from beam modes is the detector's (`Detector::clip_level`):
    // the accelerometer's alone here.
    let band = match dynamics.accelerometer() {
        Some(a) => crate::equaliser::ChainDynamics::RIGID.with_accelerometer(a),
        None => crate::equaliser::ChainDynamics::RIGID,
    };
    for k in 0..CLIP_ERROR_POINTS {
        let n = clip_error_n(k);
        let [body, ends] = crate::chain_residual::sample_error(dynamics, design, fs, n);
        let raw = crate::chain_residual::raw_error(&band, fs, n, lag);
        for (table, e) in out.iter_mut().zip([body, ends, raw]) {
            if let Some(slot) = table.get_mut(k) {
                *slot = e;
            }
        }
    }
    out
}

/// The shape a clipped pulse is measured with (`Detector::measure_clipped`): the Hertz
/// pulse's own table for the undamped Hertz law (its ratios Hertz's, whatever sampling or
/// chain correction it carries), the scene's for another; none behind a chain with beam
/// modes without the feature `settle` (`readable` false: the flank fit is not reached
/// there) or for a yielding top, so
/// that the Hertz table's 1 024 steps are taken only where they are read.
#[cfg(feature = "pulse_shape")]
fn clip_shape(s: &crate::scene::Settings, readable: bool) -> PulseShape {
    let hertz = ContactCalibration {
        sampled: s.contact.sampled,
        ..ContactCalibration::HERTZ
    };
    match (readable && plain_top(s), s.contact == hertz) {
        (false, _) => PulseShape::NONE,
        (true, true) => PulseShape::hertz(),
        (true, false) => s.pulse_shape,
    }
}

/// Whether every pulse of `scene` has one shape, scaled in force and time: no class yields
/// (its top broadens with speed) and none carries a ratio map (a damped law whose ratios,
/// and so its shape, change with size and speed). The Hertz law and a restitution-parametrised
/// law (Hunt-Crossley, Lankarani-Nikravesh, Flores, Gonthier, Tsuji) are such. The five
/// samples' fit with the Hertz shape then reads a damped contact's top with an error that
/// depends only on the samples per pulse and the phase, which the scene's sampling
/// correction measures with the same fit; a fit through three samples would leave the peak
/// to the largest sample's noise.
fn one_shape<const N: usize, M: Backend>(scene: &Scene<N, M>) -> bool {
    #[cfg(feature = "ratio_map")]
    if scene.envelopes().iter().any(|e| e.ratio_map.is_some()) {
        return false;
    }
    plain_top(scene.settings())
}

/// No yield: the pulse's top is the Hertz pulse's (always, without the feature `plasticity`).
#[cfg(feature = "plasticity")]
fn plain_top(s: &crate::scene::Settings) -> bool {
    s.flat_top_ratio == 1.0
}

/// No yield: the pulse's top is the Hertz pulse's (always, without the feature `plasticity`).
#[cfg(not(feature = "plasticity"))]
fn plain_top(_: &crate::scene::Settings) -> bool {
    true
}

/// A quiet sample `v` (counts above the baseline) as the baseline takes it: `v`, but no lower
/// than `-max(trigger, sqrt(level2))`, the mirror of the level a sample must pass to start a
/// pulse (`level2()`: `RING_SIGMAS^2` times the quiet mean square behind a chain, else 0;
/// evaluated only for a sample below `-trigger`, so a quiet sample costs one comparison).
/// Clamping below at the trigger alone let ringing louder than the trigger lift the baseline:
/// its crests moved it fully and its troughs by the trigger level, and every pulse on it
/// then read low.
#[inline(always)]
fn clamp_low<M: Backend>(v: f32, trigger: f32, level2: impl FnOnce() -> f32) -> f32 {
    if v >= -trigger {
        return v;
    }
    let level2 = level2();
    if v * v <= level2 {
        v
    } else {
        -trigger.max(M::sqrt(level2))
    }
}

/// `fit` with its peak's second-order bias taken out ([`PeakFit::vertex_bias`], at `noise`
/// counts RMS per sample, the correlations behind a chain left out): `b = (3/4) d^2 min(noise^2
/// [N^-1]_kk, 2.25)`, `F_max / (1 + b)` and the duration, the area over the peak, `t_c (1 +
/// b)`. The fitted offset cannot stray more than 1.5 samples from the top (within one of the
/// largest, which is within half of the top), however large its linear variance: uncapped,
/// an ill-conditioned fit's variance took `noisy`'s worst error in `ln F_max` from 0.18 to
/// 0.25.
#[cfg(feature = "second_order")]
fn unbiased_vertex(fit: PeakFit, noise: f32) -> PeakFit {
    let [curvature, offset_gain2] = fit.vertex_bias;
    let b = curvature * (offset_gain2 * noise * noise).min(2.25);
    PeakFit {
        peak: fit.peak / (1.0 + b),
        duration: fit.duration * (1.0 + b),
        ..fit
    }
}

/// One quiet sample `v` into the scaled mean square `sum` (`ms (1 - w) / w`, see
/// [`Detector::ring_ms`]): `(sum + v^2) (1 - w)`, a multiply-add and a multiply, both in
/// place.
#[inline(always)]
fn ring_sum_step(sum: f32, decay: f32, v: f32) -> f32 {
    (sum + v * v) * decay
}

/// The box filter over a pulse's top for a scene whose shortest pulse is `shortest_samples`
/// long: the largest odd width up to an eighth of it (so that the pulse's own curvature
/// lowers the mean by at most 1 %, and that is corrected), at most `SMOOTH_MAX - 1`; 1 (no
/// filter) below 24 samples.
fn smooth_width(shortest_samples: f32) -> usize {
    let w = (shortest_samples / 8.0) as usize;
    let odd = if w.is_multiple_of(2) {
        w.saturating_sub(1)
    } else {
        w
    };
    odd.clamp(1, SMOOTH_MAX - 1)
}

/// Peak (counts) and duration (samples) of a long pulse from the largest mean `top` of `w`
/// consecutive samples and the sum of all its samples: near its peak the Hertz pulse is
/// `F_max (1 - (3/4) PEAK_OMEGA^2 tau^2)` (`tau` in contact times), so the mean of `w` samples
/// centred on it is `F_max (1 - PEAK_OMEGA^2 (w^2 - 1) / (16 n^2))` for `n` samples per pulse;
/// `F_max` and `n = sum / (C_AREA F_max)` are iterated three times. `None` when they are not a
/// positive pulse.
pub fn smooth_fit(top: f32, w: usize, sum: f32) -> Option<(f32, f32)> {
    if !(top > 0.0 && sum > 0.0 && top.is_finite() && sum.is_finite()) {
        return None;
    }
    let spread = PEAK_OMEGA * PEAK_OMEGA * ((w * w) as f32 - 1.0) / 16.0;
    let mut peak = top;
    let mut duration = sum / (C_AREA * peak);
    for _ in 0..3 {
        let lowered = 1.0 - spread / (duration * duration);
        peak = top / lowered.max(0.5);
        duration = sum / (C_AREA * peak);
    }
    (peak.is_finite() && duration.is_finite() && duration > 0.0).then_some((peak, duration))
}

/// A rise to `v` from a valley below `0.75 max` after the peak `max`, by more than
/// `max(0.25 max, trigger + 4 noise)` (so that noise on a long, low pulse is no second
/// impact) and to above the trigger level: the start of a second impact.
#[inline]
fn second_peak(max: f32, valley: f32, v: f32, trigger: f32, noise: f32) -> bool {
    v > trigger && valley < 0.75 * max && v - valley > (0.25 * max).max(trigger + 4.0 * noise)
}
