//! The sensor chain's inverse: turns ADC samples back into the contact force, in counts of the
//! rigid plate, before anything is detected.
//!
//! The chain (host-sim integrates the same one exactly): the rigid beam `u = S F / M` (counts);
//! base-excited beam modes `H_b(s) = 1 + sum_j g_j s^2 / d_j(s)` with
//! `d_j(s) = s^2 + 2 zeta_j w_j s + w_j^2` (`w_j = 2 pi f_j`); an accelerometer
//! `H_a(s) = w_a^2 / (s^2 + 2 zeta_a w_a s + w_a^2)`; sampling at `f_s = 1 / T`.
//!
//! **Beam modes.** `H_b = N(s) / prod_j d_j(s)` with `N = prod_j d_j + sum_j g_j s^2 prod_(k != j) d_k`.
//! The inverse `1 / H_b` has the modes' poles as its zeros and the chain's zeros (the roots of
//! `N`) as its poles. The roots are found once, at build, by Aberth's method on `N'/N =
//! H_b'/H_b + sum_j d_j'/d_j` (`H_b` evaluated directly, never expanded into a polynomial),
//! in units of the highest mode's `w`. A root in the right half-plane (a chain that is not
//! minimum phase) is refused. With positive gains the zeros interlace with the modes and lie
//! in the left half-plane whatever the damping.
//!
//! *Discretisation: matched pole-zero.* Every pole and zero `p` of `1 / H_b` maps to `e^(p T)`;
//! one second-order section per mode (the mode's poles over the nearest pair of chain zeros),
//! each with unit gain at DC. A section is written in `w = z - 1` (the delta operator):
//! `k (w^2 + f1 w + f0) / (w^2 + e1 w + e0)` with `e1 = 2 (1 - r) + 4 r sin^2(theta / 2)` and
//! `e0 = (1 - r)^2 + 4 r sin^2(theta / 2)` for a pair `r e^(+-i theta)`: small numbers that f32
//! carries to full relative precision, where the usual `a1 = -2 r cos(theta)` rounds a 180 Hz
//! mode at 100 kS/s by 0.2 % of its `theta^2` and left 4e-3 of error at its antiresonance.
//! Why matched: the free ring-down of a mode,
//! sampled, is exactly `sum c e^(p n T)`, which the section's numerator annihilates at any
//! sample rate, so ringing from earlier impacts never reaches the detector; a bilinear map
//! would move the zeros off `e^(p T)` (pre-warping fixes one frequency, not the damping), and
//! inverting an exact first-order-hold model was 5-50 times less accurate on the forced pulse
//! (its extra zero) in the prototype. The forced pulse is reconstructed to 1e-3 of its peak
//! down to 4 samples per pulse (`tests/equaliser.rs` checks it against host-sim's exact
//! chain). Memory: four coefficients and two states per mode; the sections' gains `k` are
//! linear factors, applied once in front of them (in the accelerometer's taps, or as a tap of
//! their own).
//!
//! **Accelerometer.** Its roll-off cannot be inverted past the sampled band (the exact inverse
//! `1 + (2 zeta_a / w_a) s + s^2 / w_a^2` is improper and its noise grows as `f^2`): it is
//! regularised to the sampled band by a five-tap FIR centred two samples back,
//! `b_(n-2) = sum_k c_k y_(n-k)`, whose taps solve five conditions: it annihilates the
//! sampled ring-down `e^(p n T)` of the resonance exactly (two), and it equals the exact
//! inverse to second order at low frequency, `sum c_k = 1`, `sum c_k (2 - k) = 2 zeta_a /
//! (w_a T)`, `sum c_k (k - 2)^2 = 2 / (w_a T)^2` (three). Against the three-tap central
//! differences it replaces, it cut the force error on a 115 us Hertz pulse at 100 kS/s behind a
//! 35 kHz piezo from 2.2 % to 0.3 % of the peak, and the ringing left after the pulse from 2 %
//! to nothing. A resonance at or above 0.45 `f_s` is too close to the Nyquist frequency (or
//! aliased) for the annihilator, whose in-band response then fails (80 % error): there the
//! three central-difference taps `(a + b, 1 - 2 a, a - b)`, `a = 1 / (w_a T)^2`,
//! `b = zeta_a / (w_a T)`, are used (one sample of delay), and the resonance's ringing is
//! not removed. What the FIR costs in noise is its white-noise gain `sqrt(sum c_k^2)`, part of
//! [`EqualiserDesign::noise_gain`]; [`crate::Monitor`] takes its delay off reported indices.
//! What its regularisation leaves in a pulse of a few samples (a 6.3 kHz band at 26.7 kS/s
//! reads the peak of a pulse of 2.5 samples 12 % low) is computed at build and corrected per pulse
//! ([`crate::chain_residual`]).
//!
//! A rigid chain (no mode, no accelerometer) runs no filter at all.

use crate::complex::{C, cis};
use crate::error::Error;
pub use crate::error::{ChainFault, ChainStage};
use crate::math::Backend;
#[cfg(feature = "noise_colour")]
use crate::noise_colour::{ColourSums, NoiseColour};
use crate::sampled::SampledCalibration;

/// Most beam modes a chain can carry.
pub const MAX_MODES: usize = 4;

/// The sections' states at most, two per section (one section per mode): the unknowns of
/// the state re-estimation (`crate::settle`).
#[cfg(feature = "settle")]
pub(crate) const SECTION_STATES: usize = 2 * MAX_MODES;

/// The states `(p, q)` of every second-order section (see [`EqualiserDesign`]), one pair per
/// beam mode.
pub type SectionStates = [[f32; 2]; MAX_MODES];

/// Samples of the step response summed at build for the noise gain and colour: 2048, and
/// 128 more so that the colour's widest sum (128 samples) spans the same response.
const NOISE_TAPS: usize = 2048 + 128;

/// Aberth iterations at most (each one `O(modes^2)`); they converge in 10-30.
const ROOT_ITERATIONS: usize = 200;

/// One base-excited beam mode: `g s^2 / (s^2 + 2 zeta w s + w^2)` added to the rigid path.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BeamMode {
    /// Natural frequency `f = w / (2 pi)` in Hz, below the Nyquist frequency.
    pub frequency_hz: f32,
    /// Damping ratio `zeta`, in `(0, 1)`.
    pub damping_ratio: f32,
    /// Gain `g` (dimensionless): the mode raises the peak of a short pulse by `g` of it.
    pub gain: f32,
}

/// The accelerometer's own resonance: `w^2 / (s^2 + 2 zeta w s + w^2)`, unit gain at DC.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Accelerometer {
    /// Resonance frequency in Hz (may lie above the Nyquist frequency).
    pub frequency_hz: f32,
    /// Damping ratio, in `(0, 1)`.
    pub damping_ratio: f32,
}

/// How well the chain's parameters are known: the largest relative error of every stage's
/// frequency, damping ratio and (beam modes) gain. The classifier widens a pulse's noise by
/// the bias this can leave ([`crate::chain_bias`]).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ChainTolerance {
    /// Relative error of every frequency, in `[0, 0.5)`.
    pub frequency: f32,
    /// Relative error of every damping ratio, in `[0, 0.5)`.
    pub damping: f32,
    /// Relative error of every beam mode's gain, in `[0, 0.5)`.
    pub gain: f32,
}

impl ChainTolerance {
    /// Known exactly: no widening.
    pub const EXACT: ChainTolerance = ChainTolerance {
        frequency: 0.0,
        damping: 0.0,
        gain: 0.0,
    };

    /// What a chain is taken to be known to unless stated: frequency 2 %, damping 30 %, gain
    /// 20 % (the chain parameters a stream's ring-downs give, with a margin: see
    /// `docs/chain.md`).
    pub const IDENTIFIED: ChainTolerance = ChainTolerance {
        frequency: 0.02,
        damping: 0.3,
        gain: 0.2,
    };

    fn check(&self) -> Result<(), Error> {
        for (v, name) in [
            (self.frequency, "chain tolerance of frequency"),
            (self.damping, "chain tolerance of damping"),
            (self.gain, "chain tolerance of gain"),
        ] {
            if !v.is_finite() {
                return Err(Error::NonFinite(name));
            }
            if !(0.0..0.5).contains(&v) {
                return Err(Error::OutOfRange(name));
            }
        }
        Ok(())
    }
}

/// The chain's linear dynamics between the rigid plate and the ADC; every stage optional.
/// Built from [`ChainDynamics::RIGID`] with [`ChainDynamics::with_mode`] and
/// [`ChainDynamics::with_accelerometer`]; `crate::SensorChain::with_dynamics` designs its
/// equaliser at the chain's sample rate (so that a firmware whose chain is rigid links no
/// design code).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ChainDynamics {
    modes: [BeamMode; MAX_MODES],
    mode_count: u8,
    accelerometer: Option<Accelerometer>,
    tolerance: ChainTolerance,
    /// The accelerometer's own tolerance, when it is known better or worse than the beam's.
    accelerometer_tolerance: Option<ChainTolerance>,
    /// The equaliser and the sample rate (Hz) it was designed at.
    design: Option<(f32, EqualiserDesign)>,
    /// What computes the bias the equaliser leaves in short pulses (set with the design by
    /// `SensorChain::with_dynamics`, so that a rigid chain's firmware links none of it).
    residual: Option<ResidualFn>,
}

/// A function computing the bias an equaliser leaves in pulses of few samples, per point
/// of a [`SampledCalibration`]: `(dynamics, design, sample_rate_hz) -> correction`. The
/// kernel has one, `chain_residual::residual`; every `ResidualFn` is taken as equal.
#[derive(Clone, Copy)]
pub struct ResidualFn(pub fn(&ChainDynamics, &EqualiserDesign, f32) -> SampledCalibration);

impl PartialEq for ResidualFn {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

impl core::fmt::Debug for ResidualFn {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("ResidualFn")
    }
}

#[cfg(feature = "defmt")]
impl defmt::Format for ResidualFn {
    fn format(&self, f: defmt::Formatter) {
        defmt::write!(f, "ResidualFn")
    }
}

impl ChainDynamics {
    /// A rigid plate under an ideal accelerometer: nothing to invert.
    pub const RIGID: ChainDynamics = ChainDynamics {
        modes: [BeamMode {
            frequency_hz: 0.0,
            damping_ratio: 0.0,
            gain: 0.0,
        }; MAX_MODES],
        mode_count: 0,
        accelerometer: None,
        tolerance: ChainTolerance::IDENTIFIED,
        accelerometer_tolerance: None,
        design: None,
        residual: None,
    };

    /// Adds a beam mode; [`Error::Chain`] with [`ChainFault::TooManyModes`] past [`MAX_MODES`].
    pub fn with_mode(mut self, mode: BeamMode) -> Result<Self, Error> {
        let slot = self
            .modes
            .get_mut(self.mode_count as usize)
            .ok_or(Error::Chain {
                stage: ChainStage::BeamMode(self.mode_count),
                fault: ChainFault::TooManyModes,
            })?;
        *slot = mode;
        self.mode_count += 1;
        self.design = None;
        Ok(self)
    }

    /// Sets the accelerometer resonance.
    pub fn with_accelerometer(mut self, accelerometer: Accelerometer) -> Self {
        self.accelerometer = Some(accelerometer);
        self.design = None;
        self
    }

    /// States how well the parameters are known ([`ChainTolerance::IDENTIFIED`] unless set);
    /// [`Error::OutOfRange`] or [`Error::NonFinite`] outside `[0, 0.5)`.
    pub fn with_tolerance(mut self, tolerance: ChainTolerance) -> Result<Self, Error> {
        tolerance.check()?;
        self.tolerance = tolerance;
        Ok(self)
    }

    /// How well the parameters are known.
    pub fn tolerance(&self) -> ChainTolerance {
        self.tolerance
    }

    /// States how well the accelerometer's frequency and damping ratio are known, apart from
    /// the beam modes' (its `gain` is not used: the accelerometer has unit gain at DC); a band
    /// fitted to the pulses can be known far better than the modes' damping. Unset, the
    /// chain's [`ChainDynamics::tolerance`] holds for it. [`Error::OutOfRange`] or
    /// [`Error::NonFinite`] outside `[0, 0.5)`.
    ///
    /// ```
    /// use coalshock::{Accelerometer, ChainDynamics, ChainTolerance};
    /// let band = Accelerometer { frequency_hz: 6300.0, damping_ratio: 0.7 };
    /// let known = ChainTolerance { frequency: 0.005, damping: 0.01, gain: 0.0 };
    /// let d = ChainDynamics::RIGID.with_accelerometer(band);
    /// assert_eq!(d.accelerometer_tolerance(), ChainTolerance::IDENTIFIED);
    /// let d = d.with_accelerometer_tolerance(known).unwrap();
    /// assert_eq!(d.accelerometer_tolerance(), known);
    /// assert_eq!(d.tolerance(), ChainTolerance::IDENTIFIED);
    /// ```
    pub fn with_accelerometer_tolerance(
        mut self,
        tolerance: ChainTolerance,
    ) -> Result<Self, Error> {
        tolerance.check()?;
        self.accelerometer_tolerance = Some(tolerance);
        Ok(self)
    }

    /// How well the accelerometer's parameters are known: its own tolerance if stated, else
    /// the chain's.
    pub fn accelerometer_tolerance(&self) -> ChainTolerance {
        self.accelerometer_tolerance.unwrap_or(self.tolerance)
    }

    /// `true` when the accelerometer's tolerance was stated apart from the chain's.
    pub fn has_accelerometer_tolerance(&self) -> bool {
        self.accelerometer_tolerance.is_some()
    }

    /// The accelerometer resonance, if modelled.
    pub fn accelerometer(&self) -> Option<Accelerometer> {
        self.accelerometer
    }

    /// The same dynamics with their equaliser designed at `sample_rate_hz`
    /// ([`EqualiserDesign::new`]); what cannot be inverted is refused by stage.
    pub fn designed<M: Backend>(mut self, sample_rate_hz: f32) -> Result<Self, Error> {
        let design = EqualiserDesign::new::<M>(&self, sample_rate_hz)?;
        self.design = Some((sample_rate_hz, design));
        Ok(self)
    }

    /// The equaliser for a chain sampled at `sample_rate_hz`: the identity for a rigid chain,
    /// else the one designed at that rate ([`ChainFault::NotDesigned`] when there is none).
    pub fn equaliser_at(&self, sample_rate_hz: f32) -> Result<EqualiserDesign, Error> {
        if self.is_rigid() {
            return Ok(EqualiserDesign::IDENTITY);
        }
        match self.design {
            Some((fs, design)) if fs == sample_rate_hz => Ok(design),
            _ => Err(chain(ChainStage::Beam, ChainFault::NotDesigned)),
        }
    }

    /// The same dynamics with `residual` to compute the bias their equaliser leaves in short
    /// pulses ([`ChainDynamics::residual_at`]).
    pub fn with_residual(mut self, residual: ResidualFn) -> Self {
        self.residual = Some(residual);
        self
    }

    /// The bias the equaliser designed at `sample_rate_hz` leaves in short pulses;
    /// [`SampledCalibration::NONE`] for a rigid chain, or without a design at that rate or a
    /// [`ResidualFn`].
    pub fn residual_at(&self, sample_rate_hz: f32) -> SampledCalibration {
        match (self.design, self.residual) {
            (Some((fs, design)), Some(f)) if fs == sample_rate_hz && !self.is_rigid() => {
                (f.0)(self, &design, sample_rate_hz)
            }
            _ => SampledCalibration::NONE,
        }
    }

    /// The beam modes in use.
    pub fn modes(&self) -> &[BeamMode] {
        self.modes.get(..self.mode_count as usize).unwrap_or(&[])
    }

    /// `true` when there is nothing to invert.
    pub fn is_rigid(&self) -> bool {
        self.mode_count == 0 && self.accelerometer.is_none()
    }
}

/// One second-order section `k (w^2 + f1 w + f0) / (w^2 + e1 w + e0)` in `w = z - 1`, run
/// without its gain `k` (the gains of all sections are applied once, see
/// [`EqualiserDesign`]) as `y = v + g1 q + g0 p`, `p <- p + q`, `q <- q + v - e1 q - e0 p`
/// with `g1 = f1 - e1`, `g0 = f0 - e0` (`p = v / (w^2 + e1 w + e0)`, `q = w p`).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
struct Section {
    g: [f32; 2],
    e: [f32; 2],
}

impl Section {
    /// A section that passes its input through exactly (`g = 0`: `y = v + 0 + 0`), with both
    /// poles at `z = 0` (`e = [2, 1]`: its states are the last two inputs', always finite):
    /// the unused slots, and the padding of a loop specialised for more sections.
    const IDENTITY: Section = Section {
        g: [0.0, 0.0],
        e: [2.0, 1.0],
    };

    /// One sample `v` through the section with states `st = [p, q]`: its output (before `k`).
    #[inline(always)]
    fn step(&self, st: &mut [f32; 2], v: f32) -> f32 {
        let [g1, g0] = self.g;
        let [e1, e0] = self.e;
        let [p, q] = *st;
        let y = v + g1 * q + g0 * p;
        let d = v - e1 * q - e0 * p;
        *st = [p + q, q + d];
        y
    }
}

/// The equaliser of a chain, discretised at the scene's sample rate (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct EqualiserDesign {
    sections: [Section; MAX_MODES],
    section_count: u8,
    /// The sections' gains `prod k_j = prod e0_j / f0_j` (unit DC gain), applied once to the
    /// sections' output (folded into the taps when there is an accelerometer stage).
    gain: f32,
    taps: Option<Taps>,
    noise_gain: f32,
    #[cfg(feature = "noise_colour")]
    colour: NoiseColour,
}

/// The accelerometer's FIR: `out_(n - delay) = sum_k c_k y_(n - k)` (the taps times the
/// sections' gain in an [`EqualiserDesign`]).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
struct Taps {
    c: [f32; 5],
    delay: u8,
}

impl EqualiserDesign {
    /// The identity (a rigid chain).
    pub const IDENTITY: EqualiserDesign = EqualiserDesign {
        sections: [Section::IDENTITY; MAX_MODES],
        section_count: 0,
        gain: 1.0,
        taps: None,
        noise_gain: 1.0,
        #[cfg(feature = "noise_colour")]
        colour: NoiseColour::WHITE,
    };

    /// Designs the equaliser of `dynamics` at `sample_rate_hz`; refuses a stage that cannot be
    /// inverted with [`Error::Chain`] naming it.
    pub fn new<M: Backend>(dynamics: &ChainDynamics, sample_rate_hz: f32) -> Result<Self, Error> {
        if !sample_rate_hz.is_finite() {
            return Err(Error::NonFinite("sample_rate_hz"));
        }
        if sample_rate_hz <= 0.0 {
            return Err(Error::NonPositive("sample_rate_hz"));
        }
        if dynamics.mode_count as usize > MAX_MODES {
            return Err(chain(ChainStage::Beam, ChainFault::TooManyModes));
        }
        let t = 1.0 / sample_rate_hz;
        let mut design = Self::IDENTITY;
        for (i, m) in dynamics.modes().iter().enumerate() {
            check_mode(m, i as u8, sample_rate_hz)?;
        }
        let taps = match &dynamics.accelerometer {
            Some(a) => Some(accelerometer_taps::<M>(a, t)?),
            None => None,
        };
        if dynamics.mode_count > 0 {
            let zeros = beam_zeros::<M>(dynamics.modes())?;
            for (i, m) in dynamics.modes().iter().enumerate() {
                let z = zeros.get(i).copied().unwrap_or_default();
                if let Some(s) = design.sections.get_mut(i) {
                    let (section, k) = matched_section::<M>(m, z, t);
                    *s = section;
                    design.gain *= k;
                }
            }
            design.section_count = dynamics.mode_count;
        }
        // The sections are linear: their gains move to the front of the chain, into the taps.
        design.taps = taps.map(|mut t| {
            t.c = t.c.map(|c| c * design.gain);
            t
        });
        design.noise_moments::<M>();
        Ok(design)
    }

    /// `true` when the equaliser does nothing (a rigid chain).
    pub fn is_identity(&self) -> bool {
        self.section_count == 0 && self.taps.is_none()
    }

    /// RMS of the equalised signal for unit white noise at the ADC:
    /// `sqrt(sum_n h_n^2)` over the first 2176 samples of the impulse response.
    pub fn noise_gain(&self) -> f32 {
        self.noise_gain
    }

    /// How the equaliser correlates white noise between samples ([`NoiseColour::WHITE`] for a
    /// rigid chain).
    #[cfg(feature = "noise_colour")]
    pub fn noise_colour(&self) -> &NoiseColour {
        &self.colour
    }

    /// Samples by which the equalised signal lags the input: 1 with an accelerometer stage.
    pub fn delay_samples(&self) -> u32 {
        self.taps.map_or(0, |t| t.delay as u32)
    }

    /// Second-order sections in use (one per beam mode).
    #[cfg(feature = "settle")]
    pub(crate) fn section_count(&self) -> usize {
        self.section_count as usize
    }

    /// One sample of the sections' free response: their output (before the base is added
    /// back) for zero input, from the states `st`, which advance by the sample.
    #[cfg(feature = "settle")]
    #[inline(never)]
    pub(crate) fn free_step(&self, st: &mut SectionStates) -> f32 {
        let mut v = 0.0;
        let count = self.section_count();
        for (sec, s) in self.sections.iter().zip(st.iter_mut()).take(count) {
            v = sec.step(s, v);
        }
        v
    }

    /// The frequency response at `theta = w T` (rad per sample), with the reported delay taken
    /// off: `prod_j (w^2 + f1_j w + f0_j) / (w^2 + e1_j w + e0_j)` (`w = e^(i theta) - 1`)
    /// times `sum_k c_k e^(-i k theta) e^(i delay theta)` with an accelerometer stage, else
    /// times the sections' gain. 1 at `theta = 0`.
    pub(crate) fn response(&self, theta: f32) -> C {
        let z = cis(theta);
        let w = z.sub(C::new(1.0, 0.0));
        let w2 = w.mul(w);
        let sections = self
            .sections
            .get(..self.section_count as usize)
            .unwrap_or(&[]);
        let mut h = sections.iter().fold(C::new(1.0, 0.0), |h, s| {
            let [g1, g0] = s.g;
            let [e1, e0] = s.e;
            let num = w2.add(w.scale(e1 + g1)).add(C::new(e0 + g0, 0.0));
            let den = w2.add(w.scale(e1)).add(C::new(e0, 0.0));
            h.mul(num.div(den))
        });
        match self.taps {
            Some(t) => {
                let fir = t.c.iter().enumerate().fold(C::default(), |sum, (k, &c)| {
                    sum.add(cis(-(k as f32) * theta).scale(c))
                });
                h = h.mul(fir).mul(cis(t.delay as f32 * theta));
            }
            None => h = h.scale(self.gain),
        }
        h
    }

    /// Sets the noise gain `sqrt(sum h^2)` of the impulse response `h` (and, with
    /// `noise_colour`, how it correlates the noise between samples), from the step response
    /// `s` of an input of `2^14` counts after a reference sample of 0, one [`Equaliser::step`]
    /// at a time (so that the image carries no other copy of the filter loop), over
    /// [`NOISE_TAPS`] samples: `h_m = s_m - s_(m-1)`.
    fn noise_moments<M: Backend>(&mut self) {
        let mut eq = Equaliser::new(self);
        let _ = eq.step(0);
        #[cfg(feature = "noise_colour")]
        let mut sums = ColourSums::new();
        let (mut energy, mut last) = (0.0f32, 0.0f32);
        for _ in 0..NOISE_TAPS {
            let s = eq.step(1 << 14) / 16384.0;
            energy += (s - last) * (s - last);
            #[cfg(feature = "noise_colour")]
            sums.push(s);
            last = s;
        }
        self.noise_gain = M::sqrt(energy.max(0.0));
        #[cfg(feature = "noise_colour")]
        {
            self.colour = sums.colour(energy, last);
        }
    }
}

fn chain(stage: ChainStage, fault: ChainFault) -> Error {
    Error::Chain { stage, fault }
}

fn check_mode(m: &BeamMode, i: u8, fs: f32) -> Result<(), Error> {
    let stage = ChainStage::BeamMode(i);
    if !(m.frequency_hz.is_finite() && m.damping_ratio.is_finite() && m.gain.is_finite()) {
        return Err(chain(stage, ChainFault::NonFinite));
    }
    if m.frequency_hz <= 0.0 {
        return Err(chain(stage, ChainFault::FrequencyNotPositive));
    }
    if m.frequency_hz >= 0.5 * fs {
        return Err(chain(stage, ChainFault::AboveNyquist));
    }
    if !(m.damping_ratio > 0.0 && m.damping_ratio < 1.0) {
        return Err(chain(stage, ChainFault::DampingOutOfRange));
    }
    if m.gain <= -1.0 {
        return Err(chain(stage, ChainFault::NonMinimumPhase));
    }
    Ok(())
}

/// The accelerometer's inverse FIR (module docs): five taps that annihilate its ring-down
/// below `0.45 f_s`, three central-difference taps above.
fn accelerometer_taps<M: Backend>(a: &Accelerometer, t: f32) -> Result<Taps, Error> {
    let stage = ChainStage::Accelerometer;
    if !(a.frequency_hz.is_finite() && a.damping_ratio.is_finite()) {
        return Err(chain(stage, ChainFault::NonFinite));
    }
    if a.frequency_hz <= 0.0 {
        return Err(chain(stage, ChainFault::FrequencyNotPositive));
    }
    if !(a.damping_ratio > 0.0 && a.damping_ratio < 1.0) {
        return Err(chain(stage, ChainFault::DampingOutOfRange));
    }
    let wt = 2.0 * core::f32::consts::PI * a.frequency_hz * t;
    let z = a.damping_ratio;
    let (a2, b) = (1.0 / (wt * wt), z / wt);
    if !(a2.is_finite() && a2 < 1e6) {
        // A resonance below 1/(2 pi 1000) of the sample rate: its inverse is pure noise.
        return Err(chain(stage, ChainFault::FrequencyNotPositive));
    }
    if a.frequency_hz * t >= 0.45 {
        return Ok(Taps {
            c: [a2 + b, 1.0 - 2.0 * a2, a2 - b, 0.0, 0.0],
            delay: 1,
        });
    }
    // Rows: Re and Im of sum c_k lambda^-k = 0 (lambda = r e^(i theta)), then the moments.
    let r_inv = M::exp(z * wt);
    let theta = wt * M::sqrt(1.0 - z * z);
    let mut m = [[0.0f32; 6]; 5];
    let mut scale = 1.0f32;
    for k in 0..5 {
        let d = k as f32 - 2.0;
        let (sin, cos) = (libm::sinf(k as f32 * theta), libm::cosf(k as f32 * theta));
        for (row, v) in m
            .iter_mut()
            .zip([scale * cos, -scale * sin, 1.0, -d, d * d])
        {
            if let Some(x) = row.get_mut(k) {
                *x = v;
            }
        }
        scale *= r_inv;
    }
    for (row, rhs) in m.iter_mut().zip([0.0, 0.0, 1.0, 2.0 * b, 2.0 * a2]) {
        if let Some(x) = row.get_mut(5) {
            *x = rhs;
        }
    }
    let c = solve5(m).ok_or(chain(stage, ChainFault::NotConverged))?;
    Ok(Taps { c, delay: 2 })
}

/// Solves the 5 x 5 system in the augmented matrix `m` by Gaussian elimination with partial
/// pivoting; `None` when it is singular.
fn solve5(mut m: [[f32; 6]; 5]) -> Option<[f32; 5]> {
    for col in 0..5 {
        let pivot = (col..5).max_by(|&i, &j| {
            let a = m.get(i).and_then(|r| r.get(col)).map_or(0.0, |v| v.abs());
            let b = m.get(j).and_then(|r| r.get(col)).map_or(0.0, |v| v.abs());
            a.total_cmp(&b)
        })?;
        // The pivot row and row `col` trade places (`get`, not `swap`: no bounds-check panic
        // path in the image).
        let p_row = *m.get(pivot)?;
        let row_col = *m.get(col)?;
        if let Some(r) = m.get_mut(pivot) {
            *r = row_col;
        }
        if let Some(r) = m.get_mut(col) {
            *r = p_row;
        }
        let p = *p_row.get(col)?;
        if p.abs() <= 1e-20 || p.is_nan() {
            return None;
        }
        for (i, row) in m.iter_mut().enumerate() {
            if i == col {
                continue;
            }
            let f = row.get(col).copied().unwrap_or(0.0) / p;
            for (x, y) in row.iter_mut().zip(p_row.iter()) {
                *x -= f * y;
            }
        }
    }
    let mut out = [0.0f32; 5];
    for (k, o) in out.iter_mut().enumerate() {
        let row = m.get(k)?;
        *o = row.get(5)? / row.get(k)?;
    }
    out.iter().all(|v| v.is_finite()).then_some(out)
}

/// The zeros of the beam stage with positive imaginary part (one per mode, in the mode's
/// order: each mode gets the zero nearest its own frequency), in rad/s.
fn beam_zeros<M: Backend>(modes: &[BeamMode]) -> Result<[C; MAX_MODES], Error> {
    let two_pi = 2.0 * core::f32::consts::PI;
    let w_ref = modes
        .iter()
        .map(|m| two_pi * m.frequency_hz)
        .fold(0.0f32, f32::max);
    // Normalised modes: (w / w_ref, zeta, g).
    let mut norm = [(0.0f32, 0.0f32, 0.0f32); MAX_MODES];
    for (n, m) in norm.iter_mut().zip(modes) {
        *n = (two_pi * m.frequency_hz / w_ref, m.damping_ratio, m.gain);
    }
    let norm = norm.get(..modes.len()).unwrap_or(&[]);
    let count = 2 * modes.len();
    let mut roots = starting_roots::<M>(norm);
    let roots_used = roots.get_mut(..count).unwrap_or(&mut []);
    polish_roots(norm, roots_used)?;
    zeros_by_mode::<M>(norm, roots_used, w_ref)
}

/// Starting points for the beam stage's zeros of the normalised modes `norm`
/// (`(w / w_ref, zeta, g)`): each mode's zero if it were alone, `w / sqrt(1 + g)`, a little off
/// the axis and turned so that no two coincide; two per mode, conjugate.
fn starting_roots<M: Backend>(norm: &[(f32, f32, f32)]) -> [C; 2 * MAX_MODES] {
    let mut roots = [C::default(); 2 * MAX_MODES];
    for (k, (w, z, g)) in norm.iter().enumerate() {
        let wz = *w / M::sqrt(1.0 + g.max(-0.9));
        let tilt = 1.0 + 0.01 * (k as f32 + 1.0);
        if let Some(r) = roots.get_mut(2 * k) {
            *r = C::new(-z * wz * tilt - 0.01, wz);
        }
        if let Some(r) = roots.get_mut(2 * k + 1) {
            *r = C::new(-z * wz / tilt - 0.02, -wz);
        }
    }
    roots
}

/// Newton's steps with the other roots deflated (Aberth-Ehrlich) on all `roots` of the beam
/// stage's numerator at once, until no relative step exceeds 1e-6 (squared: 1e-12), at most
/// `ROOT_ITERATIONS` rounds; `NotConverged` otherwise or on a non-finite step.
fn polish_roots(norm: &[(f32, f32, f32)], roots: &mut [C]) -> Result<(), Error> {
    let count = roots.len();
    for _ in 0..ROOT_ITERATIONS {
        let mut largest_step = 0.0f32;
        for k in 0..count {
            let Some(sk) = roots.get(k).copied() else {
                continue;
            };
            let ratio = newton_ratio(norm, sk);
            let mut repel = C::default();
            for (m, sm) in roots.iter().enumerate() {
                if m != k {
                    repel = repel.add(C::new(1.0, 0.0).div(sk.sub(*sm)));
                }
            }
            let step = ratio.div(C::new(1.0, 0.0).sub(ratio.mul(repel)));
            if !(step.re.is_finite() && step.im.is_finite()) {
                return Err(chain(ChainStage::Beam, ChainFault::NotConverged));
            }
            largest_step = largest_step.max(step.norm2() / sk.norm2().max(1e-12));
            if let Some(r) = roots.get_mut(k) {
                *r = sk.sub(step);
            }
        }
        if largest_step < 1e-12 {
            return Ok(());
        }
    }
    Err(chain(ChainStage::Beam, ChainFault::NotConverged))
}

/// For each normalised mode of `norm`, in order, the unused root of non-negative imaginary
/// part nearest its frequency, scaled back by `w_ref` (rad/s); `NonMinimumPhase` when a root
/// has a non-negative real part, `NotConverged` when a mode finds none.
fn zeros_by_mode<M: Backend>(
    norm: &[(f32, f32, f32)],
    roots: &[C],
    w_ref: f32,
) -> Result<[C; MAX_MODES], Error> {
    let mut out = [C::default(); MAX_MODES];
    let mut used = [false; 2 * MAX_MODES];
    for (slot, (w, _, _)) in out.iter_mut().zip(norm) {
        let mut best: Option<(usize, f32)> = None;
        for (k, r) in roots.iter().enumerate() {
            if r.re >= 0.0 {
                return Err(chain(ChainStage::Beam, ChainFault::NonMinimumPhase));
            }
            let free = !used.get(k).copied().unwrap_or(true);
            let distance = (M::sqrt(r.norm2()) - w).abs();
            if free && r.im >= 0.0 && best.is_none_or(|(_, d)| distance < d) {
                best = Some((k, distance));
            }
        }
        let (k, _) = best.ok_or(chain(ChainStage::Beam, ChainFault::NotConverged))?;
        if let Some(u) = used.get_mut(k) {
            *u = true;
        }
        *slot = roots.get(k).copied().unwrap_or_default().scale(w_ref);
    }
    Ok(out)
}

/// `N(s) / N'(s)` of the beam stage at `s` (normalised units), through
/// `N'/N = H'/H + sum_j d_j'/d_j`, `H = 1 + sum_j g_j s^2 / d_j`,
/// `H' = sum_j g_j (2 s d_j - s^2 d_j') / d_j^2`, `d_j' = 2 s + 2 zeta_j w_j`.
fn newton_ratio(modes: &[(f32, f32, f32)], s: C) -> C {
    let s2 = s.mul(s);
    let mut h = C::new(1.0, 0.0);
    let mut dh = C::default();
    let mut dd = C::default();
    for &(w, z, g) in modes {
        let d = s2.add(s.scale(2.0 * z * w)).add(C::new(w * w, 0.0));
        let d1 = s.scale(2.0).add(C::new(2.0 * z * w, 0.0));
        let term = s2.div(d);
        h = h.add(term.scale(g));
        dh = dh.add(s.scale(2.0).mul(d).sub(s2.mul(d1)).div(d.mul(d)).scale(g));
        dd = dd.add(d1.div(d));
    }
    C::new(1.0, 0.0).div(dh.div(h).add(dd))
}

/// `1 - e^(-x)` for `x >= 0`, accurate for small `x`.
fn one_minus_exp<M: Backend>(x: f32) -> f32 {
    if x < 1e-2 {
        x * (1.0 - x * (0.5 - x / 6.0))
    } else {
        1.0 - M::exp(-x)
    }
}

/// `(w^2 + c1 w + c0)`, `w = z - 1`, of the pair `s = -sigma +- i omega` mapped by
/// `z = e^(s T)` (`r = e^(-sigma T)`, `theta = omega T`): `[c1, c0]` with
/// `c1 = 2 (1 - r) + 4 r sin^2(theta / 2)`, `c0 = (1 - r)^2 + 4 r sin^2(theta / 2)`.
fn pair<M: Backend>(sigma: f32, omega: f32, t: f32) -> [f32; 2] {
    let r = M::exp(-sigma * t);
    let sin_half = libm::sinf(0.5 * omega * t);
    let one_minus_r = one_minus_exp::<M>(sigma * t);
    let bend = 4.0 * r * sin_half * sin_half;
    [2.0 * one_minus_r + bend, one_minus_r * one_minus_r + bend]
}

/// Mode `m`'s section: its poles (the inverse's zeros) over the chain zero `zero` (rad/s),
/// both matched, and its gain `k = e0 / f0` (unit gain at DC).
fn matched_section<M: Backend>(m: &BeamMode, zero: C, t: f32) -> (Section, f32) {
    let w = 2.0 * core::f32::consts::PI * m.frequency_hz;
    let z = m.damping_ratio;
    let [f1, f0] = pair::<M>(z * w, w * M::sqrt(1.0 - z * z), t);
    let [e1, e0] = pair::<M>(-zero.re, zero.im, t);
    let section = Section {
        g: [f1 - e1, f0 - e0],
        e: [e1, e0],
    };
    (section, e0 / f0)
}

/// The equaliser's state: fed raw samples, it gives the reconstructed force in counts of the
/// rigid plate (see the module docs). Fixed size; `O(modes)` work per sample: the FIR, then
/// the sections. [`Equaliser::step`] takes one sample; [`Equaliser::feed_to`] runs loops
/// specialised for the section count over a block (how the detector's quiet loop is fed,
/// see [`crate::Monitor::feed_slice`]), with the same arithmetic.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Equaliser {
    design: EqualiserDesign,
    /// States `(p, q)` of each section.
    state: SectionStates,
    /// The accelerometer FIR's last four inputs, newest first (relative to `offset`).
    history: [f32; 4],
    /// The first sample seen: every input is taken relative to it (and it is added back to
    /// the output, the chain's DC gain being 1), so that the states stay small and keep
    /// their f32 precision.
    offset: Option<i32>,
}

impl Equaliser {
    /// An equaliser at rest.
    pub fn new(design: &EqualiserDesign) -> Self {
        Self {
            design: *design,
            state: [[0.0; 2]; MAX_MODES],
            history: [0.0; 4],
            offset: None,
        }
    }

    /// The design it runs.
    pub fn design(&self) -> &EqualiserDesign {
        &self.design
    }

    /// Forgets the past (after a gap in the stream): the next sample is the new reference.
    pub fn reset(&mut self) {
        *self = Self::new(&self.design);
    }

    /// Takes `error` off the sections' states: the correction of an observer that estimated
    /// how far they are from the chain's ([`crate::settle`]).
    #[cfg(feature = "settle")]
    pub(crate) fn correct_states(&mut self, error: &SectionStates) {
        for (st, e) in self.state.iter_mut().zip(error) {
            st[0] -= e[0];
            st[1] -= e[1];
        }
    }

    /// Equalises `raw` into `out` (the shorter length of the two), sample by sample in order.
    #[inline]
    pub fn process<S: Copy + Into<i32>>(&mut self, raw: &[S], out: &mut [f32]) {
        self.feed_to(raw, Store(out));
    }

    /// The input's reference (the first sample seen, `sample` if none was).
    #[inline(always)]
    fn base(&mut self, sample: Option<i32>) -> f32 {
        match (self.offset, sample) {
            (Some(o), _) => o as f32,
            (None, Some(first)) => *self.offset.insert(first) as f32,
            (None, None) => 0.0,
        }
    }

    /// The FIR's taps: the accelerometer's, or the sections' gain alone (one tap) without it.
    #[inline(always)]
    fn taps(&self) -> [f32; 5] {
        self.design
            .taps
            .map_or([self.design.gain, 0.0, 0.0, 0.0, 0.0], |t| t.c)
    }

    /// Equalises one sample: the FIR and the design's sections, coefficients read from the
    /// design (small and not inlined: the path of single samples; the same arithmetic as
    /// [`Equaliser::feed_to`]'s loops, whose padding sections pass values through exactly).
    #[inline(never)]
    pub fn step(&mut self, sample: i32) -> f32 {
        let base = self.base(Some(sample));
        let taps = self.taps();
        let mut v = fir(&taps, &mut self.history, sample as f32 - base);
        let count = self.design.section_count as usize;
        for (sec, st) in self.design.sections.iter().zip(&mut self.state).take(count) {
            v = sec.step(st, v);
        }
        v + base
    }

    /// Runs `sink` over the equalised `(raw, value)` pairs of `raw`, with the filter
    /// specialised for 3 or 4 sections (fewer are padded with pass-through sections), its
    /// coefficients and states in locals (registers) and written back once: the equaliser
    /// advances by exactly the samples `sink` takes, so a sink that stops early (the
    /// detector's quiet loop) leaves it where [`Equaliser::step`] on those samples would.
    #[inline]
    pub fn feed_to<S: Copy + Into<i32>, T: Sink>(&mut self, raw: &[S], sink: T) -> T::Output {
        match self.design.section_count {
            0..=3 => self.run::<S, T, 3>(raw, sink),
            _ => self.run::<S, T, 4>(raw, sink),
        }
    }

    /// The loop for `K` sections: coefficients and states in locals so that they stay in
    /// registers.
    #[inline(always)]
    fn run<S: Copy + Into<i32>, T: Sink, const K: usize>(
        &mut self,
        raw: &[S],
        sink: T,
    ) -> T::Output {
        let base = self.base(raw.first().map(|&s| s.into()));
        let filter = Filter::<K> {
            base,
            sections: core::array::from_fn(|i| {
                self.design
                    .sections
                    .get(i)
                    .copied()
                    .unwrap_or(Section::IDENTITY)
            }),
            state: core::array::from_fn(|i| self.state.get(i).copied().unwrap_or([0.0; 2])),
        };
        let mut run = Run::<S, K> {
            raw,
            filter,
            taps: self.taps(),
            history: self.history,
            ahead: [0.0; AHEAD],
        };
        let out = sink.take(&mut run);
        self.history = run.history;
        for (dst, src) in self.state.iter_mut().zip(run.filter.state.iter()) {
            *dst = *src;
        }
        out
    }
}

/// What takes the equalised samples from [`Equaliser::feed_to`].
pub trait Sink {
    /// What it returns.
    type Output;
    /// Takes equalised samples from `pairs`, as many as it wants, in order.
    fn take(self, pairs: &mut impl Pairs) -> Self::Output;
}

/// Equalised samples handed to a [`Sink`]: the ADC's samples, each with its reconstructed
/// value (counts of the rigid plate).
pub trait Pairs {
    /// Equalises the next samples, one per slot of `slots` (at most 32), and calls
    /// `f(slot, raw, value)` on each until it returns `false`, a raw sample is at or above
    /// `raw_max` (taken, not fed to `f`: a stop too), or the slots or the samples run out
    /// (see [`Fed`]).
    fn each(
        &mut self,
        slots: &mut [f32],
        raw_max: i32,
        f: impl FnMut(&mut f32, i32, f32) -> bool,
    ) -> Fed;

    /// Equalises the next samples into `out`, one per slot, until either runs out.
    fn fill(&mut self, out: &mut [f32]);
}

/// What [`Pairs::each`] did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fed {
    /// Samples fed (calls that returned `true`).
    pub count: usize,
    /// The `(raw, value)` that stopped it (`f` returned `false`, or the raw sample was at or
    /// above `raw_max`): taken, the equaliser advanced past it, not fed.
    pub stop: Option<(i32, f32)>,
    /// The first and the last raw sample fed.
    pub ends: Option<(i32, i32)>,
    /// How many fed samples, counted back from the last, equal the one fed before them
    /// (`count - 1` when all are equal).
    pub repeats: usize,
}

/// The sink of [`Equaliser::process`]: stores the values.
struct Store<'a>(&'a mut [f32]);

impl Sink for Store<'_> {
    type Output = ();
    #[inline(always)]
    fn take(self, pairs: &mut impl Pairs) {
        pairs.fill(self.0);
    }
}

/// Samples the accelerometer's FIR runs ahead of the sections in [`Pairs::each`].
const AHEAD: usize = 32;

/// The equaliser over a block, its coefficients and states copied into locals.
struct Run<'a, S, const K: usize> {
    raw: &'a [S],
    filter: Filter<K>,
    /// The FIR's taps.
    taps: [f32; 5],
    /// The FIR's last four inputs, newest first.
    history: [f32; 4],
    /// The FIR's outputs, run ahead of the sections (a pure function of the inputs: what was
    /// run ahead and not taken is run again).
    ahead: [f32; AHEAD],
}

/// The accelerometer's FIR (direct form) over `block` into `out`, inputs relative to `base`,
/// from and to `history`: apart from the sections' loop (not inlined), so that its taps and
/// history take no registers there.
#[inline(never)]
fn fir_block<S: Copy + Into<i32>>(
    taps: &[f32; 5],
    base: f32,
    history: &mut [f32; 4],
    block: &[S],
    out: &mut [f32; AHEAD],
) {
    let mut running = *history;
    for (a, &s) in out.iter_mut().zip(block) {
        *a = fir(taps, &mut running, s.into() as f32 - base);
    }
    *history = running;
}

/// The FIR (direct form, the sections' gain in its taps) on the input `x` (relative to the
/// base), its `history` shifted.
#[inline(always)]
fn fir(taps: &[f32; 5], history: &mut [f32; 4], x: f32) -> f32 {
    let [c0, c1, c2, c3, c4] = *taps;
    let [h1, h2, h3, h4] = *history;
    *history = [x, h1, h2, h3];
    c0 * x + c1 * h1 + c2 * h2 + c3 * h3 + c4 * h4
}

/// What [`Pairs::each`] did, from the `count` raw samples it `fed` and the one that `stop`ped
/// it: the first and last fed, and the repeated raw samples, counted here once per call rather
/// than in the loop.
#[inline(always)]
fn fed_of<S: Copy + Into<i32>>(count: usize, fed: &[S], stop: Option<(i32, f32)>) -> Fed {
    let repeats = fed
        .windows(2)
        .rev()
        .take_while(|w| match w {
            [a, b] => (*a).into() == (*b).into(),
            _ => false,
        })
        .count();
    Fed {
        count,
        stop,
        ends: fed
            .first()
            .zip(fed.last())
            .map(|(&a, &b)| (a.into(), b.into())),
        repeats,
    }
}

/// The coefficients and the sections' states of a [`Run`].
struct Filter<const K: usize> {
    base: f32,
    sections: [Section; K],
    state: [[f32; 2]; K],
}

impl<const K: usize> Filter<K> {
    /// The sections on the FIR's output `v`, the base added back: the reconstructed value.
    #[inline(always)]
    fn sections(&mut self, mut v: f32) -> f32 {
        for (sec, st) in self.sections.iter().zip(self.state.iter_mut()) {
            v = sec.step(st, v);
        }
        v + self.base
    }

    /// `history` after the inputs `taken`.
    fn history_after<S: Copy + Into<i32>>(&self, mut history: [f32; 4], taken: &[S]) -> [f32; 4] {
        let newest = taken.len().saturating_sub(4);
        for &s in taken.get(newest..).unwrap_or(&[]) {
            let [h1, h2, h3, _] = history;
            history = [s.into() as f32 - self.base, h1, h2, h3];
        }
        history
    }
}

impl<S: Copy + Into<i32>, const K: usize> Pairs for Run<'_, S, K> {
    /// The FIR runs ahead over up to [`AHEAD`] samples, then the sections and `f` take them
    /// (the FIR's history and taps need not stay in registers beside the sections' and the
    /// caller's; the same arithmetic as [`Pairs::fill`]). Slots past [`AHEAD`] stay unused.
    #[inline(always)]
    fn each(
        &mut self,
        slots: &mut [f32],
        raw_max: i32,
        mut f: impl FnMut(&mut f32, i32, f32) -> bool,
    ) -> Fed {
        let Run {
            raw,
            filter,
            taps,
            history,
            ahead,
        } = self;
        let raw: &[S] = raw;
        // Run ahead only as far as the slots reach.
        let block = raw
            .get(..AHEAD.min(slots.len()).min(raw.len()))
            .unwrap_or(&[]);
        let mut running = *history;
        fir_block(taps, filter.base, &mut running, block, ahead);
        let mut count = slots.len().min(block.len());
        let mut stop = None;
        for (i, ((slot, &s), &a)) in slots.iter_mut().zip(block).zip(ahead.iter()).enumerate() {
            let x: i32 = s.into();
            let value = filter.sections(a);
            // Two tests, two branches (the saturation test apart from `f`'s).
            if x >= raw_max {
                (count, stop) = (i, Some((x, value)));
                break;
            }
            if !f(slot, x, value) {
                (count, stop) = (i, Some((x, value)));
                break;
            }
        }
        let taken = raw.get(..count + stop.is_some() as usize).unwrap_or(&[]);
        *history = if taken.len() == block.len() {
            running
        } else {
            filter.history_after(*history, taken)
        };
        self.raw = raw.get(taken.len()..).unwrap_or(&[]);
        fed_of(count, raw.get(..count).unwrap_or(&[]), stop)
    }

    #[inline(always)]
    fn fill(&mut self, out: &mut [f32]) {
        let raw = self.raw;
        let filter = &mut self.filter;
        let mut history = self.history;
        for (o, &s) in out.iter_mut().zip(raw) {
            let x = s.into() as f32 - filter.base;
            let v = fir(&self.taps, &mut history, x);
            *o = filter.sections(v);
        }
        self.history = history;
        self.raw = raw.get(out.len().min(raw.len())..).unwrap_or(&[]);
    }
}
