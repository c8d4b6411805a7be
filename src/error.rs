//! The one error type of the kernel: what a scene or a model input can be wrong with.

/// A parameter the kernel refused, with the name of the parameter.
///
/// Every constructor and closed form returns this instead of panicking or returning a
/// non-finite number.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Error {
    /// The parameter is NaN or infinite.
    NonFinite(&'static str),
    /// The parameter must be strictly positive and is zero or negative.
    NonPositive(&'static str),
    /// A `[min, max]` range has `min > max`.
    InvertedRange(&'static str),
    /// Poisson's ratio is outside `[0, 0.5)`.
    PoissonOutOfRange,
    /// The parameter is finite but a derived quantity leaves the range f32 can carry
    /// (below `1e-30` or above `1e30`), so the model would return garbage.
    Unrepresentable(&'static str),
    /// A scene needs at least two particle classes.
    TooFewClasses,
    /// More particle classes than the scene's fixed capacity.
    TooManyClasses,
    /// The setting is outside its documented range (for example a confident-error rate outside `(0, 0.5)`).
    OutOfRange(&'static str),
    /// A stage of the sensor chain cannot be inverted (see [`crate::equaliser`]).
    Chain {
        /// The stage.
        stage: ChainStage,
        /// What is wrong with it.
        fault: ChainFault,
    },
}

impl core::fmt::Display for Error {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Error::NonFinite(p) => write!(f, "{p} is not finite"),
            Error::NonPositive(p) => write!(f, "{p} must be > 0"),
            Error::InvertedRange(p) => write!(f, "range {p} has min > max"),
            Error::PoissonOutOfRange => write!(f, "Poisson's ratio must be in [0, 0.5)"),
            Error::Unrepresentable(p) => write!(f, "{p} leaves the range f32 can carry"),
            Error::TooFewClasses => write!(f, "a scene needs at least two classes"),
            Error::TooManyClasses => write!(f, "more classes than the scene's capacity"),
            Error::OutOfRange(p) => write!(f, "{p} is outside its allowed range"),
            Error::Chain { stage, fault } => write!(f, "sensor chain, {stage:?}: {fault:?}"),
        }
    }
}

impl core::error::Error for Error {}

/// `Ok(x)` when `x` is finite, `> 0` and inside [`REPRESENTABLE`], else the matching
/// [`Error`] naming `what` (a subnormal or absurdly large input would make the closed forms
/// lose their f32 precision silently).
pub(crate) fn positive(x: f32, what: &'static str) -> Result<f32, Error> {
    if !x.is_finite() {
        Err(Error::NonFinite(what))
    } else if x <= 0.0 {
        Err(Error::NonPositive(what))
    } else {
        representable(x, what)
    }
}

/// Smallest and largest magnitude a derived quantity may have before the scene refuses it.
pub(crate) const REPRESENTABLE: (f32, f32) = (1e-30, 1e30);

/// `Ok(x)` when `x` is finite and inside [`REPRESENTABLE`], else [`Error::Unrepresentable`].
pub(crate) fn representable(x: f32, what: &'static str) -> Result<f32, Error> {
    if x.is_finite() && x >= REPRESENTABLE.0 && x <= REPRESENTABLE.1 {
        Ok(x)
    } else {
        Err(Error::Unrepresentable(what))
    }
}

/// Which stage of the chain a [`ChainFault`] is in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ChainStage {
    /// Beam mode number `i` (from 0).
    BeamMode(u8),
    /// The accelerometer resonance.
    Accelerometer,
    /// The beam modes together (their zeros).
    Beam,
}

/// What is wrong with a chain stage.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ChainFault {
    /// A parameter is NaN or infinite.
    NonFinite,
    /// The frequency is zero or negative.
    FrequencyNotPositive,
    /// A beam mode at or above the Nyquist frequency `f_s / 2`: it cannot be sampled.
    AboveNyquist,
    /// The damping ratio is not in `(0, 1)`: an undamped stage never stops ringing, an
    /// overdamped one is no resonance.
    DampingOutOfRange,
    /// The gain is `<= -1`, or the modes' gains make the chain non-minimum-phase (a zero in the
    /// right half-plane): its inverse would be unstable.
    NonMinimumPhase,
    /// The chain's zeros could not be found to f32 precision (modes too close together).
    NotConverged,
    /// More than [`crate::equaliser::MAX_MODES`] modes.
    TooManyModes,
    /// The chain's equaliser was not designed at the chain's sample rate: give the dynamics
    /// to `SensorChain::with_dynamics` after setting the rate.
    NotDesigned,
}
