//! The equaliser's state re-estimated from the quiet samples after a clipped impact or a gap:
//! a least-squares observer of the sections' free response.
//!
//! **Why.** The equaliser ([`crate::equaliser`]) inverts the samples it is given. While the
//! ADC clips, those are not the chain's output; after a gap it restarts from rest while the
//! beam still rings. Either way its sections are left off the chain's state, and that error
//! rings on at the sections' poles (the chain's zeros, as lightly damped as the beam's modes)
//! under every later pulse: after an impact that clips, thousands of counts for tens of
//! milliseconds, which the detector waits out, deaf to the impacts beneath.
//!
//! **How.** The sections are linear. With their states off by `d` (two numbers per section)
//! at the start of a quiet window, the equalised value is
//! `v_n = b + sum_i d_i phi_i(n) + noise`, where `b` is the baseline the detector held before
//! the event and `phi_i` the sections' output for zero input from the unit state `e_i`, which
//! a shadow copy of the sections runs beside them (`EqualiserDesign::free_step`). Each
//! sample adds one row to a least-squares problem, reduced at once by Givens rotations to
//! `R d = z` (no sample is stored); after a window of [`WINDOW_S`] (at least
//! [`MIN_WINDOW_SAMPLES`] rows), `d` carried to the
//! window's end by the shadows' own states, `sum_i d_i A^W e_i`, is taken off the sections'
//! (`Equaliser::correct_states`). The first [`WARM_UP`] samples after the event are
//! passed over: the accelerometer FIR's history still holds clipped samples (a FIR forgets in
//! four). A direction whose column `R` cannot tell from the others (`|R_ii|` below
//! [`RANK_TOLERANCE`] of its column's norm) is left uncorrected.
//!
//! **What it cannot do.** Behind a chain given off by a few per cent, the equaliser's own
//! ringing near a mode (180 Hz) looks over one window like a free response at the nearest
//! chain zero (171 Hz): the fit takes part of it for a state error, and its correction beats
//! against it afterwards (`docs/chain.md`: no gain there, 0.4-0.5 pp of forced choice lost on
//! a scene where a fifth of the impacts clip).
//!
//! **When it is believed.** The fit is taken only when the window's residual mean square is
//! within [`ACCEPT_SIGMAS`]^2 of the equalised noise's variance: a pulse inside the window (or
//! a chain given off, whose own ringing the sections do not annihilate) leaves more, and the
//! window is discarded for a fresh one, at most [`MAX_WINDOWS`] per event; a sample at full
//! scale ends the re-estimation at once and goes to the detector (the next impact that clips
//! starts it again). Every sample spent here is counted (`Counters::settle_samples`), and the
//! detector is told of them: it searches none of them for pulses.
//!
//! **A clipped pulse behind beam modes** (with the feature `pulse_shape`) waits for the window
//! after it: `Settler::start_anchored` starts the shadows at the pulse's anchor, so that the
//! fit's `d` is the state error there and also states the error in that pulse's own samples
//! after the run (`crate::settle_clip`). It waits through discarded windows, each anchored
//! afresh, until one is believed or [`MAX_WINDOWS`] are spent: the first window often
//! holds the pulse's own tail, which the state error (thousands of counts after a deep clip)
//! pushed below the detector's release level.
//!
//! **Cost.** Behind a rigid chain nothing arms it. It is the cargo feature `settle` (on by
//! default): on a Cortex-M4F 2.5 KB of flash on a size-optimised node with one math backend
//! (6.0 KB on the measuring node, which carries both) and 592 B of RAM in every
//! [`crate::Monitor`]; without it a monitor carries [`NoSettle`], which takes no sample, and
//! an equaliser left off the chain's state rings until its own damping ends it.

use crate::equaliser::{Equaliser, MAX_MODES};
#[cfg(feature = "settle")]
use crate::equaliser::{EqualiserDesign, SECTION_STATES, SectionStates};
#[cfg(all(feature = "settle", feature = "pulse_shape"))]
use crate::settle_clip::{ClipAnchor, ClipColumns, ClipError};

/// Length of one window of the fit (s, after [`WARM_UP`]): long enough for a section at
/// 170 Hz to turn by a fifth of a period, short enough that an impact seldom falls into it.
pub const WINDOW_S: f32 = 1e-3;

/// Rows of a window at least, whatever the rate: three per unknown.
pub const MIN_WINDOW_SAMPLES: u16 = 6 * MAX_MODES as u16;

/// Samples passed over before a window: the accelerometer FIR's four of history.
pub const WARM_UP: u16 = 4;

/// Windows tried per event before the state is left as it is.
pub const MAX_WINDOWS: u8 = 3;

/// A window is believed when its residual RMS is within this many noise sigmas.
pub const ACCEPT_SIGMAS: f32 = 2.0;

/// `|R_ii|` below this share of column `i`'s norm: the direction is left uncorrected.
pub const RANK_TOLERANCE: f32 = 1e-4;

/// Unknowns at most: two states per section.
#[cfg(feature = "settle")]
const UNKNOWNS: usize = SECTION_STATES;

/// Where the re-estimation stands.
#[cfg(feature = "settle")]
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
enum Phase {
    /// Nothing to do.
    Off,
    /// An event happened: a window starts once the detector is idle.
    Armed,
    /// Inside a window: samples taken so far (the warm-up included).
    Window(u16),
}

/// What one sample of a window ended in.
#[cfg(feature = "settle")]
#[derive(Debug, Clone, Copy, PartialEq)]
enum Settled {
    /// The window goes on.
    Pending,
    /// The fit is believed: take `error` off the sections' states; the quiet signal's mean
    /// square about the baseline is then `quiet_ms` (counts^2).
    Correct {
        /// The sections' state error at the window's end.
        error: SectionStates,
        /// The residual mean square of the window (counts^2).
        quiet_ms: f32,
        /// The error in the samples of the clipped pulse the window was anchored at.
        #[cfg(feature = "pulse_shape")]
        clip: Option<ClipError>,
    },
    /// The window was discarded; another starts (or, after [`MAX_WINDOWS`], none).
    Discarded,
}

/// What [`Settler::run`] took from a stream, for the detector ([`crate::Detector`] is told
/// of every sample) and the counters.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Taken {
    /// Samples taken (equalised, not searched for pulses).
    pub samples: u32,
    /// The last of them (raw counts).
    pub last_raw: Option<i32>,
    /// With a believed fit: the residual mean square about the baseline (counts^2).
    pub quiet_ms: Option<f32>,
    /// With a believed fit of a window anchored at a clipped pulse
    /// (`Settler::start_anchored`): the error in that pulse's samples.
    #[cfg(all(feature = "settle", feature = "pulse_shape"))]
    pub clip: Option<ClipError>,
}

/// The observer: its phase, the shadow sections and the triangular least-squares system.
#[cfg(feature = "settle")]
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Settler {
    phase: Phase,
    windows: u8,
    /// Rows of a window: [`WINDOW_S`] at the sample rate, at least [`MIN_WINDOW_SAMPLES`].
    window_samples: u16,
    /// The detector's baseline when the window started (counts).
    baseline: f32,
    /// The sections from each unit state, running with zero input.
    shadows: [SectionStates; UNKNOWNS],
    /// Rows of `R`, the right-hand side `z` in the last column.
    r: [[f32; UNKNOWNS + 1]; UNKNOWNS],
    /// Squared norm of each column so far.
    norm2: [f32; UNKNOWNS],
    /// Residual sum of squares so far (counts^2).
    rss: f32,
    /// The columns at a clipped pulse's samples when the shadows started at its anchor.
    #[cfg(feature = "pulse_shape")]
    columns: Option<ClipColumns>,
}

#[cfg(feature = "settle")]
impl Settler {
    /// An observer at rest for a stream sampled at `sample_rate_hz` (a window of
    /// `max(WINDOW_S fs, MIN_WINDOW_SAMPLES)` rows, at most `u16::MAX`).
    pub fn new(sample_rate_hz: f32) -> Self {
        let rows = (WINDOW_S * sample_rate_hz).max(MIN_WINDOW_SAMPLES as f32);
        Self {
            window_samples: rows.min(u16::MAX as f32) as u16,
            ..Self::resting()
        }
    }

    fn resting() -> Self {
        Self {
            phase: Phase::Off,
            windows: 0,
            window_samples: MIN_WINDOW_SAMPLES,
            baseline: 0.0,
            shadows: [[[0.0; 2]; MAX_MODES]; UNKNOWNS],
            r: [[0.0; UNKNOWNS + 1]; UNKNOWNS],
            norm2: [0.0; UNKNOWNS],
            rss: 0.0,
            #[cfg(feature = "pulse_shape")]
            columns: None,
        }
    }

    /// An event left the sections' states unknown (a sample at full scale, a gap): a window
    /// starts once the detector is idle, and [`MAX_WINDOWS`] are allowed again.
    pub fn arm(&mut self) {
        self.phase = Phase::Armed;
        self.windows = 0;
    }

    /// A sample at full scale inside a window: the window ends and the event stays armed (the
    /// monitor then hands that sample to the detector, which re-arms it with fresh windows;
    /// every window consumes samples, so a stream at full scale cannot loop here).
    pub fn interrupt(&mut self) {
        if let Phase::Window(_) = self.phase {
            self.phase = Phase::Armed;
        }
    }

    /// `true` when a window waits for the detector to be idle.
    pub fn is_armed(&self) -> bool {
        self.phase == Phase::Armed
    }

    /// `true` inside a window: the next samples are the observer's.
    pub fn in_window(&self) -> bool {
        matches!(self.phase, Phase::Window(_))
    }

    /// Starts a window on the detector's `baseline` (counts), or gives up after
    /// [`MAX_WINDOWS`].
    pub fn start(&mut self, baseline: f32) {
        if self.windows >= MAX_WINDOWS {
            self.phase = Phase::Off;
            return;
        }
        *self = Self {
            phase: Phase::Window(0),
            windows: self.windows + 1,
            window_samples: self.window_samples,
            baseline,
            ..Self::resting()
        };
    }

    /// Starts a window as [`Settler::start`] does, with its shadows started at the anchor of
    /// a clipped pulse behind beam modes and run to the window's first sample
    /// ([`ClipColumns::run_to_window`]): a believed fit then also states that pulse's error
    /// (`Taken::clip`). Without columns (too far, too short) a plain window.
    #[cfg(feature = "pulse_shape")]
    pub fn start_anchored(&mut self, baseline: f32, design: &EqualiserDesign, anchor: ClipAnchor) {
        self.start(baseline);
        if self.in_window() {
            self.columns = ClipColumns::run_to_window(design, anchor, &mut self.shadows);
        }
    }

    /// Runs the open window over `raw` samples (counts): each through `equaliser` and into
    /// the window's fit (`noise`: the equalised noise's RMS, counts), until the window
    /// closes or a sample reaches `adc` `(min, max)` (that one is not taken: it ends the
    /// window and is left for the detector). A believed fit is taken off `equaliser`'s
    /// sections. Returns what the detector must be told.
    #[inline(never)]
    pub fn run(
        &mut self,
        equaliser: &mut Equaliser,
        noise: f32,
        (adc_min, adc_max): (i32, i32),
        raw: &mut dyn Iterator<Item = i32>,
    ) -> Taken {
        let mut taken = Taken::default();
        while self.in_window() {
            let Some(sample) = raw.next() else { break };
            if sample >= adc_max || sample <= adc_min {
                self.interrupt();
                break;
            }
            let value = equaliser.step(sample);
            taken.samples += 1;
            taken.last_raw = Some(sample);
            match self.take(equaliser.design(), value, noise) {
                Settled::Pending => {}
                Settled::Correct {
                    error,
                    quiet_ms,
                    #[cfg(feature = "pulse_shape")]
                    clip,
                } => {
                    equaliser.correct_states(&error);
                    taken.quiet_ms = Some(quiet_ms);
                    #[cfg(feature = "pulse_shape")]
                    {
                        taken.clip = clip;
                    }
                }
                Settled::Discarded => break,
            }
        }
        taken
    }

    /// Takes one equalised `value` (counts) of the window for the equaliser `design`, the
    /// equalised noise's RMS being `noise` (counts): the last of the window solves the fit.
    #[inline(never)]
    fn take(&mut self, design: &EqualiserDesign, value: f32, noise: f32) -> Settled {
        let Phase::Window(n) = self.phase else {
            return Settled::Pending;
        };
        let unknowns = 2 * design.section_count();
        if self.anchored() {
            // The shadows run from the anchor: through the warm-up too.
            if n < WARM_UP {
                for shadow in self.shadows.iter_mut().take(unknowns) {
                    design.free_step(shadow);
                }
            }
        } else if n == WARM_UP {
            for (i, shadow) in self.shadows.iter_mut().enumerate().take(unknowns) {
                if let Some(s) = shadow.get_mut(i / 2).and_then(|st| st.get_mut(i % 2)) {
                    *s = 1.0;
                }
            }
        }
        if n >= WARM_UP {
            let mut row = [0.0; UNKNOWNS + 1];
            for (x, shadow) in row.iter_mut().zip(&mut self.shadows).take(unknowns) {
                *x = design.free_step(shadow);
            }
            if let Some(z) = row.last_mut() {
                *z = value - self.baseline;
            }
            self.add_row(row, unknowns);
        }
        let n = n.saturating_add(1);
        self.phase = Phase::Window(n);
        if n < WARM_UP.saturating_add(self.window_samples) {
            return Settled::Pending;
        }
        self.phase = Phase::Armed;
        let quiet_ms = self.rss / self.window_samples as f32;
        let limit = ACCEPT_SIGMAS * noise;
        // NaN is not believed either.
        let believed = quiet_ms <= limit * limit;
        if !believed {
            return Settled::Discarded;
        }
        self.phase = Phase::Off;
        let d = self.solve(unknowns);
        Settled::Correct {
            error: self.carried(&d, unknowns),
            quiet_ms,
            #[cfg(feature = "pulse_shape")]
            clip: self
                .columns
                .as_ref()
                .and_then(|c| c.error(&d, &self.r, (&self.norm2, RANK_TOLERANCE, unknowns), noise)),
        }
    }

    /// Whether the shadows started at a clipped pulse's anchor.
    fn anchored(&self) -> bool {
        #[cfg(feature = "pulse_shape")]
        return self.columns.is_some();
        #[cfg(not(feature = "pulse_shape"))]
        false
    }

    /// One row `(phi_1 .. phi_p, y)` into `R` and `z` by Givens rotations; what is left of `y`
    /// joins the residual sum of squares.
    #[inline(never)]
    fn add_row(&mut self, mut row: [f32; UNKNOWNS + 1], unknowns: usize) {
        for (x, n2) in row.iter().zip(self.norm2.iter_mut()).take(unknowns) {
            *n2 += x * x;
        }
        for (i, ri) in self.r.iter_mut().enumerate().take(unknowns) {
            rotate(ri, &mut row, i);
        }
        // The columns past `unknowns` stay zero: the rotations left `z`'s residual there.
        let e = row.last().copied().unwrap_or(0.0);
        self.rss += e * e;
    }

    /// Back-substitution of `R d = z`: the state error where the shadows started (a
    /// direction `R` cannot tell from the others left at 0).
    #[inline(never)]
    fn solve(&self, unknowns: usize) -> [f32; UNKNOWNS] {
        let mut d = [0.0_f32; UNKNOWNS];
        for i in (0..unknowns).rev() {
            let Some(ri) = self.r.get(i) else { continue };
            let mut acc = ri.last().copied().unwrap_or(0.0);
            for (rij, dj) in ri.iter().zip(&d).take(unknowns).skip(i + 1) {
                acc -= rij * dj;
            }
            let diag = ri.get(i).copied().unwrap_or(0.0);
            let norm = libm::sqrtf(self.norm2.get(i).copied().unwrap_or(0.0));
            if let Some(di) = d.get_mut(i) {
                *di = if diag.abs() > RANK_TOLERANCE * norm {
                    acc / diag
                } else {
                    0.0
                };
            }
        }
        d
    }

    /// `sum_i d_i` times shadow `i`'s state now: the state error `d` carried to the window's
    /// end.
    fn carried(&self, d: &[f32; UNKNOWNS], unknowns: usize) -> SectionStates {
        let mut error = [[0.0; 2]; MAX_MODES];
        for (di, shadow) in d.iter().zip(&self.shadows).take(unknowns) {
            for (e, s) in error.iter_mut().zip(shadow) {
                e[0] += di * s[0];
                e[1] += di * s[1];
            }
        }
        error
    }
}

/// The Givens rotation that zeroes `row[i]` against `ri[i]` (`c = a / h`, `s = b / h`,
/// `h = sqrt(a^2 + b^2)`), applied to both from column `i` on; nothing when `h` is 0 or not
/// finite. Out of line, one loop: a window's rows are few, the firmware's flash is not.
#[cfg(feature = "settle")]
#[inline(never)]
fn rotate(ri: &mut [f32; UNKNOWNS + 1], row: &mut [f32; UNKNOWNS + 1], i: usize) {
    let (Some(&a), Some(&b)) = (ri.get(i), row.get(i)) else {
        return;
    };
    let h = libm::sqrtf(a * a + b * b);
    if !(h > 0.0 && h.is_finite()) {
        return;
    }
    let (c, s) = (a / h, b / h);
    for (rj, xj) in ri.iter_mut().zip(row.iter_mut()).skip(i) {
        let (p, q) = (*rj, *xj);
        *rj = c * p + s * q;
        *xj = c * q - s * p;
    }
}

/// The monitor's slot without the feature `settle`: never armed, takes no sample, no RAM.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct NoSettle;

impl NoSettle {
    /// Nothing to keep, whatever the rate.
    pub fn new(_sample_rate_hz: f32) -> Self {
        Self
    }

    /// Nothing is re-estimated.
    pub fn arm(&mut self) {}

    /// Never armed.
    pub fn is_armed(&self) -> bool {
        false
    }

    /// Never in a window.
    pub fn in_window(&self) -> bool {
        false
    }

    /// Opens no window.
    pub fn start(&mut self, _baseline: f32) {}

    /// Takes nothing.
    pub fn run(
        &mut self,
        _equaliser: &mut Equaliser,
        _noise: f32,
        _adc: (i32, i32),
        _raw: &mut dyn Iterator<Item = i32>,
    ) -> Taken {
        Taken::default()
    }
}
